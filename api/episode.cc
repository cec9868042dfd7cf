#include "api/episode.h"

#include <nlohmann/json.hpp>

namespace enavi::api {
namespace {

template <typename T>
void GetIf(const nlohmann::json& j, const char* key, T& out) {
  if (auto it = j.find(key); it != j.end() && !it->is_null()) it->get_to(out);
}

nlohmann::json SpecFields(const EpisodeSpec& s) {
  nlohmann::json j = {{"world", s.world},   {"seed", s.seed},     {"board", s.board},
                      {"method", s.method}, {"clock", s.clock},   {"cost", s.cost},
                      {"dilation", s.dilation}, {"timeout_s", s.timeout_s}};
  if (!s.world_params.empty()) j["world_params"] = s.world_params;
  if (s.start) j["start"] = *s.start;
  if (s.goal) j["goal"] = *s.goal;
  if (!s.policy.empty()) j["policy"] = s.policy;
  if (!s.overrides.empty()) j["overrides"] = s.overrides;
  if (!s.units.empty()) j["units"] = s.units;
  if (s.scale != 1.0) j["scale"] = s.scale;
  if (!s.up.empty()) j["up"] = s.up;
  if (s.recenter) j["recenter"] = true;
  if (!s.model_path.empty()) j["model_path"] = s.model_path;
  return j;
}

}  // namespace

void to_json(nlohmann::json& j, const EpisodeSpec& s) { j = SpecFields(s); }

void from_json(const nlohmann::json& j, EpisodeSpec& s) {
  s = EpisodeSpec{};
  GetIf(j, "world", s.world);
  GetIf(j, "seed", s.seed);
  GetIf(j, "world_params", s.world_params);
  if (j.contains("start") && !j["start"].is_null()) s.start = j["start"].get<Vec3>();
  if (j.contains("goal") && !j["goal"].is_null()) s.goal = j["goal"].get<Vec3>();
  GetIf(j, "board", s.board);
  GetIf(j, "method", s.method);
  GetIf(j, "clock", s.clock);
  GetIf(j, "cost", s.cost);
  GetIf(j, "dilation", s.dilation);
  GetIf(j, "timeout_s", s.timeout_s);
  GetIf(j, "policy", s.policy);
  GetIf(j, "overrides", s.overrides);
  GetIf(j, "units", s.units);
  GetIf(j, "scale", s.scale);
  GetIf(j, "up", s.up);
  GetIf(j, "recenter", s.recenter);
  GetIf(j, "model_path", s.model_path);
}

nlohmann::json ResultSummaryJson(const EpisodeResult& r) {
  nlohmann::json j = {
      {"scenario", r.scenario},
      {"world", r.spec.world},
      {"seed", r.spec.seed},
      {"board", r.spec.board},
      {"method", r.spec.method},
      {"clock", r.spec.clock},
      {"cost", r.spec.cost},
      {"success", r.success},
      {"collided", r.collided},
      {"timed_out", r.timed_out},
      {"end_reason", r.end_reason},
      {"flight_time_s", r.flight_time_s},
      {"path_length_m", r.path_length_m},
      {"straight_line_m", r.straight_line_m},
      {"velocity_mean_mps", r.velocity_mean_mps},
      {"velocity_std_mps", r.velocity_std_mps},
      {"accel_peak_mps2", r.accel_peak_mps2},
      {"nav_cpu_util_pct", r.nav_cpu_util_pct},
      {"task_cpu_util_pct",
       {{"perception", r.task_cpu_util_pct.perception},
        {"planning", r.task_cpu_util_pct.planning},
        {"collision", r.task_cpu_util_pct.collision},
        {"difference", r.task_cpu_util_pct.difference}}},
      {"deadline_miss_ratio", r.deadline_miss_ratio},
      {"jobs_released", r.jobs_released},
      {"deadline_misses", r.deadline_misses},
      {"replans", r.replans},
      {"replans_by_trigger", r.replans_by_trigger},
      {"plan_failures", r.plan_failures},
      {"emergency_stops", r.emergency_stops},
      {"time_stopped_s", r.time_stopped_s},
      {"setpoint_lag_p95_m", r.setpoint_lag_p95_m},
      {"eci", {{"min", r.eci.min}, {"mean", r.eci.mean}, {"max", r.eci.max}}},
      {"eci_time_ms_mean", r.eci_time_ms_mean},
      {"adapter_time_ms_mean", r.adapter_time_ms_mean},
      {"sim_time_s", r.sim_time_s},
      {"notes", r.notes},
  };
  j["collision_point"] = r.collision_point ? nlohmann::json(*r.collision_point) : nlohmann::json();
  return j;
}

void to_json(nlohmann::json& j, const EpisodeResult& r) {
  j = ResultSummaryJson(r);
  j["spec"] = r.spec;
  nlohmann::json events = nlohmann::json::array();
  for (const auto& e : r.events) events.push_back({{"t", e.t}, {"kind", e.kind}, {"detail", e.detail}});
  j["events"] = std::move(events);
  const TimeSeries& s = r.series;
  j["series"] = {{"t", s.t},     {"position", s.position}, {"velocity", s.velocity},
                 {"eci", s.eci}, {"f_per", s.f_per},       {"f_col", s.f_col},
                 {"f_dif", s.f_dif}, {"res", s.res},       {"utilisation", s.utilisation},
                 {"events", s.events}};
}

void from_json(const nlohmann::json& j, EpisodeResult& r) {
  r = EpisodeResult{};
  if (j.contains("spec")) j.at("spec").get_to(r.spec);
  GetIf(j, "scenario", r.scenario);
  GetIf(j, "success", r.success);
  GetIf(j, "collided", r.collided);
  GetIf(j, "timed_out", r.timed_out);
  GetIf(j, "end_reason", r.end_reason);
  if (j.contains("collision_point") && !j["collision_point"].is_null())
    r.collision_point = j["collision_point"].get<Vec3>();
  GetIf(j, "flight_time_s", r.flight_time_s);
  GetIf(j, "path_length_m", r.path_length_m);
  GetIf(j, "straight_line_m", r.straight_line_m);
  GetIf(j, "velocity_mean_mps", r.velocity_mean_mps);
  GetIf(j, "velocity_std_mps", r.velocity_std_mps);
  GetIf(j, "accel_peak_mps2", r.accel_peak_mps2);
  GetIf(j, "nav_cpu_util_pct", r.nav_cpu_util_pct);
  if (auto it = j.find("task_cpu_util_pct"); it != j.end()) {
    GetIf(*it, "perception", r.task_cpu_util_pct.perception);
    GetIf(*it, "planning", r.task_cpu_util_pct.planning);
    GetIf(*it, "collision", r.task_cpu_util_pct.collision);
    GetIf(*it, "difference", r.task_cpu_util_pct.difference);
  }
  GetIf(j, "deadline_miss_ratio", r.deadline_miss_ratio);
  GetIf(j, "jobs_released", r.jobs_released);
  GetIf(j, "deadline_misses", r.deadline_misses);
  GetIf(j, "replans", r.replans);
  GetIf(j, "replans_by_trigger", r.replans_by_trigger);
  GetIf(j, "plan_failures", r.plan_failures);
  GetIf(j, "emergency_stops", r.emergency_stops);
  GetIf(j, "time_stopped_s", r.time_stopped_s);
  GetIf(j, "setpoint_lag_p95_m", r.setpoint_lag_p95_m);
  if (auto it = j.find("eci"); it != j.end()) {
    GetIf(*it, "min", r.eci.min);
    GetIf(*it, "mean", r.eci.mean);
    GetIf(*it, "max", r.eci.max);
  }
  GetIf(j, "eci_time_ms_mean", r.eci_time_ms_mean);
  GetIf(j, "adapter_time_ms_mean", r.adapter_time_ms_mean);
  GetIf(j, "sim_time_s", r.sim_time_s);
  GetIf(j, "notes", r.notes);
  if (auto it = j.find("events"); it != j.end()) {
    for (const auto& e : *it) r.events.push_back({e.at("t"), e.at("kind"), e.at("detail")});
  }
  if (auto it = j.find("series"); it != j.end()) {
    TimeSeries& s = r.series;
    GetIf(*it, "t", s.t);
    GetIf(*it, "position", s.position);
    GetIf(*it, "velocity", s.velocity);
    GetIf(*it, "eci", s.eci);
    GetIf(*it, "f_per", s.f_per);
    GetIf(*it, "f_col", s.f_col);
    GetIf(*it, "f_dif", s.f_dif);
    GetIf(*it, "res", s.res);
    GetIf(*it, "utilisation", s.utilisation);
    GetIf(*it, "events", s.events);
  }
}

}  // namespace enavi::api
