#include "tests/support/synthetic_result.h"

#include <algorithm>
#include <cmath>

namespace enavi::testing {
namespace {

double BoardFactor(const std::string& board) {
  if (board == "pi4b") return 1.4;
  if (board == "tx2") return 1.2;
  if (board == "nx") return 1.0;
  if (board == "opi5") return 0.8;
  if (board == "x86") return 0.9;
  return 0.5;
}

}  // namespace

api::EpisodeResult SyntheticResult(const api::EpisodeSpec& spec, int series_len) {
  api::EpisodeResult r;
  r.spec = spec;
  r.scenario = spec.world.find('.') == std::string::npos ? spec.world : "custom";
  const bool enavi = spec.method == "enavi";
  const double f = BoardFactor(spec.board);
  const auto v_max = spec.overrides.find("planner.v_max");
  const double slow = v_max == spec.overrides.end() ? 1.0 : std::max(1.0, 2.0 / v_max->second);
  r.success = spec.seed % 7 != 0;
  r.collided = !r.success;
  r.end_reason = r.success ? "goal_reached" : "collision";
  r.flight_time_s = (30.0 * f * (enavi ? 0.85 : 1.0) + 0.1 * static_cast<double>(spec.seed % 10)) * slow;
  r.path_length_m = 44.0 + 0.2 * static_cast<double>(spec.seed % 5);
  r.straight_line_m = 40.0;
  r.velocity_mean_mps = r.path_length_m / r.flight_time_s;
  r.velocity_std_mps = enavi ? 0.3 : 0.5;
  r.accel_peak_mps2 = 4.0;
  r.task_cpu_util_pct = {
      {"perception", 40.0 * f * (enavi ? 0.5 : 1.0)}, {"planning", 20.0 * f}, {"collision", 10.0 * f}, {"difference", 5.0 * f}};
  r.nav_cpu_util_pct = r.task_cpu_util_pct["perception"] + r.task_cpu_util_pct["planning"] +
                       r.task_cpu_util_pct["collision"] + r.task_cpu_util_pct["difference"];
  r.jobs_released = 1000;
  r.deadline_misses = enavi ? 5 : 50;
  if (const auto misses = spec.overrides.find("fake.deadline_misses"); misses != spec.overrides.end())
    r.deadline_misses = static_cast<int>(misses->second);
  r.deadline_miss_ratio = r.deadline_misses / 1000.0;
  r.replans = 12;
  r.eci = {0.1, 0.4, 0.8};
  r.sim_time_s = r.flight_time_s;
  r.notes["producer"] = "fake_episode";
  // A planted provenance difference (enavi compare names it).
  if (const auto rev = spec.overrides.find("fake.cost_model_revision"); rev != spec.overrides.end())
    r.notes["provenance.cost_model_sha256"] = "fake-revision-" + std::to_string(static_cast<int>(rev->second));
  r.events.push_back({1.0, "replan", "initial"});
  // A path along x that weaves in y, with speed and eci varying over the flight.
  const double dt = r.flight_time_s / std::max(series_len, 1);
  for (int i = 0; i < series_len; ++i) {
    const double t = dt * i;
    const double x = r.straight_line_m * i / std::max(series_len - 1, 1);
    r.series.t.push_back(t);
    r.series.position.push_back({x, 2.0 * std::sin(x / 6.0), 1.5});
    r.series.velocity.push_back({x / std::max(t, dt) , 0.3 * std::cos(x / 6.0), 0.0});
    r.series.eci.push_back(0.4 + 0.3 * std::sin(x / 9.0));
    r.series.f_per.push_back(enavi ? 15 : 30);
    r.series.f_col.push_back(10);
    r.series.f_dif.push_back(10);
    r.series.res.push_back(enavi ? 0.2 : 0.1);
    r.series.utilisation.push_back(r.nav_cpu_util_pct);
    // The air and the odometry's columns only where the spec has them, as a flight records them.
    if (spec.wind.Active()) r.series.wind_speed.push_back(spec.wind.speed_mps + 1.5 * std::sin(t));
    if (spec.odometry_noise != "none") r.series.odometry_error.push_back(0.01 * t);
  }
  return r;
}

}  // namespace enavi::testing
