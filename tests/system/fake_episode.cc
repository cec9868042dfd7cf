// A stand-in for `enavi fly --spec-file SPEC --result-file RESULT` in farm tests: it writes a
// synthetic but schema-valid api::EpisodeResult derived only from the spec (so results are
// deterministic), and misbehaves on demand to exercise the farm's fault handling.
//
// Behaviour, from the spec's overrides (per episode) or the environment (every episode):
//   fake.sleep_s        / FAKE_EPISODE_SLEEP_S         sleep before answering
//   fake.busy_s         / FAKE_EPISODE_BUSY_S          spin one core this long (CPU-bound)
//   fake.crash_attempts / FAKE_EPISODE_CRASH_ATTEMPTS  abort() while ENAVI_ATTEMPT <= N
//   fake.exit_code      / FAKE_EPISODE_EXIT_CODE       exit with this code, no result
//   fake.hang           / FAKE_EPISODE_HANG            never finish
//   fake.garbage        / FAKE_EPISODE_GARBAGE         write a result file that is not JSON
//   fake.series_len     / FAKE_EPISODE_SERIES_LEN      time series samples (default 50)
// It appends "<episode id> <attempt>\n" to $FAKE_EPISODE_LOG (if set) when it starts.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "api/episode.h"

namespace {

double Setting(const enavi::api::EpisodeSpec& spec, const char* key, const char* env,
               double fallback) {
  if (auto it = spec.overrides.find(key); it != spec.overrides.end()) return it->second;
  if (const char* v = std::getenv(env); v != nullptr && *v != '\0') return std::atof(v);
  return fallback;
}

double BoardFactor(const std::string& board) {
  if (board == "pi4b") return 1.4;
  if (board == "tx2") return 1.2;
  if (board == "nx") return 1.0;
  if (board == "opi5") return 0.8;
  if (board == "x86") return 0.9;
  return 0.5;
}

}  // namespace

int main(int argc, char** argv) {
  std::string spec_file, result_file;
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--spec-file") == 0) spec_file = argv[i + 1];
    if (std::strcmp(argv[i], "--result-file") == 0) result_file = argv[i + 1];
  }
  if (spec_file.empty() || result_file.empty()) {
    std::cerr << "usage: fake_episode --spec-file SPEC.json --result-file RESULT.json\n";
    return 2;
  }
  enavi::api::EpisodeSpec spec;
  try {
    std::ifstream in(spec_file);
    spec = nlohmann::json::parse(in).get<enavi::api::EpisodeSpec>();
  } catch (const std::exception& e) {
    std::cerr << "fake_episode: bad spec " << spec_file << ": " << e.what() << "\n";
    return 2;
  }
  const char* episode = std::getenv("ENAVI_EPISODE_ID");
  const int attempt = std::getenv("ENAVI_ATTEMPT") ? std::atoi(std::getenv("ENAVI_ATTEMPT")) : 1;
  if (const char* log = std::getenv("FAKE_EPISODE_LOG"); log != nullptr && *log != '\0') {
    std::ofstream(log, std::ios::app) << (episode ? episode : "?") << " " << attempt << "\n";
  }

  const double sleep_s = Setting(spec, "fake.sleep_s", "FAKE_EPISODE_SLEEP_S", 0.0);
  if (Setting(spec, "fake.hang", "FAKE_EPISODE_HANG", 0.0) > 0) {
    while (true) std::this_thread::sleep_for(std::chrono::hours(1));
  }
  if (sleep_s > 0) std::this_thread::sleep_for(std::chrono::duration<double>(sleep_s));
  const double busy_s = Setting(spec, "fake.busy_s", "FAKE_EPISODE_BUSY_S", 0.0);
  if (busy_s > 0) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(busy_s);
    volatile double sink = 0;
    while (std::chrono::steady_clock::now() < until) {
      for (int i = 0; i < 10000; ++i) sink = sink + std::sqrt(static_cast<double>(i));
    }
  }
  if (attempt <= Setting(spec, "fake.crash_attempts", "FAKE_EPISODE_CRASH_ATTEMPTS", 0.0)) {
    std::cerr << "fake_episode: crashing on attempt " << attempt << " as asked\n";
    std::abort();
  }
  if (const int code = static_cast<int>(Setting(spec, "fake.exit_code", "FAKE_EPISODE_EXIT_CODE", 0))) {
    std::cerr << "fake_episode: exiting with " << code << " as asked\n";
    return code;
  }
  if (Setting(spec, "fake.garbage", "FAKE_EPISODE_GARBAGE", 0.0) > 0) {
    std::ofstream(result_file) << "this is not a result {";
    return 0;
  }

  // Synthetic flight: numbers depend only on the spec.
  enavi::api::EpisodeResult r;
  r.spec = spec;
  r.scenario = spec.world.find('.') == std::string::npos ? spec.world : "custom";
  const bool enavi = spec.method == "enavi";
  const double f = BoardFactor(spec.board);
  r.success = spec.seed % 7 != 0;
  r.collided = !r.success;
  r.end_reason = r.success ? "goal_reached" : "collision";
  r.flight_time_s = 30.0 * f * (enavi ? 0.85 : 1.0) + 0.1 * static_cast<double>(spec.seed % 10);
  r.path_length_m = 44.0 + 0.2 * static_cast<double>(spec.seed % 5);
  r.straight_line_m = 40.0;
  r.velocity_mean_mps = r.path_length_m / r.flight_time_s;
  r.velocity_std_mps = enavi ? 0.3 : 0.5;
  r.accel_peak_mps2 = 4.0;
  r.task_cpu_util_pct = {40.0 * f * (enavi ? 0.5 : 1.0), 20.0 * f, 10.0 * f, 5.0 * f};
  r.nav_cpu_util_pct = r.task_cpu_util_pct.Sum();
  r.jobs_released = 1000;
  r.deadline_misses = enavi ? 5 : 50;
  r.deadline_miss_ratio = r.deadline_misses / 1000.0;
  r.replans = 12;
  r.eci = {0.1, 0.4, 0.8};
  r.sim_time_s = r.flight_time_s;
  r.notes["producer"] = "fake_episode";
  r.events.push_back({1.0, "replan", "initial"});
  const int n = static_cast<int>(Setting(spec, "fake.series_len", "FAKE_EPISODE_SERIES_LEN", 50));
  for (int i = 0; i < n; ++i) {
    const double t = 0.1 * i;
    r.series.t.push_back(t);
    r.series.position.push_back({t, 0.1 * std::sin(t), 1.5});
    r.series.velocity.push_back({1.0, 0.1 * std::cos(t), 0.0});
    r.series.eci.push_back(0.4);
    r.series.f_per.push_back(enavi ? 15 : 30);
    r.series.f_col.push_back(10);
    r.series.f_dif.push_back(10);
    r.series.res.push_back(enavi ? 0.2 : 0.1);
    r.series.utilisation.push_back(r.nav_cpu_util_pct);
  }
  std::ofstream out(result_file);
  out << nlohmann::json(r).dump() << "\n";
  return out ? 0 : 1;
}
