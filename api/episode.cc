#include "api/episode.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/fixed.h"
#include "api/json_read.h"

namespace enavi::api {
namespace {

// Typed reads through the validated reader: a value of the wrong type names its field.
void Read(const JsonReader& r, const nlohmann::json& v, const std::string& at, std::string& out) { out = r.String(v, at); }
void Read(const JsonReader& r, const nlohmann::json& v, const std::string& at, double& out) { out = r.Number(v, at); }
void Read(const JsonReader& r, const nlohmann::json& v, const std::string& at, bool& out) { out = r.Bool(v, at); }
void Read(const JsonReader& r, const nlohmann::json& v, const std::string& at, std::uint64_t& out) { out = r.Unsigned(v, at); }
void Read(const JsonReader& r, const nlohmann::json& v, const std::string& at, std::int64_t& out) { out = r.Integer(v, at); }
void Read(const JsonReader& r, const nlohmann::json& v, const std::string& at, Vec3& out) {
  const std::vector<double> p = r.Numbers(v, at, 3);
  out = {p[0], p[1], p[2]};
}
void Read(const JsonReader& r, const nlohmann::json& v, const std::string& at, std::optional<Vec3>& out) {
  Read(r, v, at, out.emplace());
}
void Read(const JsonReader& r, const nlohmann::json& v, const std::string& at, std::vector<double>& out) {
  out = r.Numbers(v, at);
}
template <typename T>
void Read(const JsonReader& r, const nlohmann::json& v, const std::string& at, std::vector<T>& out) {
  r.Array(v, at);
  out.resize(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) Read(r, v[i], JsonReader::Index(at, i), out[i]);
}
template <typename T>
void Read(const JsonReader& r, const nlohmann::json& v, const std::string& at, std::map<std::string, T>& out) {
  out.clear();
  for (const auto& [key, value] : r.Object(v, at).items()) Read(r, value, JsonReader::Join(at, key), out[key]);
}

// The keys of one JSON object: optional ones keep their default when absent or null.
class Fields {
 public:
  Fields(const JsonReader& r, const nlohmann::json& obj, std::string at) : r_(r), obj_(r.Object(obj, at)), at_(std::move(at)) {}
  template <typename T>
  void Optional(const char* key, T& out) const {
    if (const nlohmann::json* v = r_.Optional(obj_, at_, key)) Read(r_, *v, JsonReader::Join(at_, key), out);
  }
  template <typename T>
  void Required(const char* key, T& out) const {
    Read(r_, r_.Field(obj_, at_, key), JsonReader::Join(at_, key), out);
  }
  /// The object at `key`, or nothing when it is absent or null.
  std::optional<Fields> Child(const char* key) const {
    const nlohmann::json* v = r_.Optional(obj_, at_, key);
    if (!v) return std::nullopt;
    return Fields(r_, *v, JsonReader::Join(at_, key));
  }
  const nlohmann::json* Find(const char* key) const { return r_.Optional(obj_, at_, key); }

 private:
  const JsonReader& r_;
  const nlohmann::json& obj_;
  std::string at_;
};

void ReadWind(const Fields& f, WindSpec& w) {
  f.Optional("speed_mps", w.speed_mps);
  f.Optional("direction_deg", w.direction_deg);
  f.Optional("turbulence", w.turbulence);
  if (const auto g = f.Child("gust")) {
    g->Optional("start_s", w.gust.start_s);
    g->Optional("rise_s", w.gust.rise_s);
    g->Optional("hold_s", w.gust.hold_s);
    g->Optional("speed_mps", w.gust.speed_mps);
    g->Optional("direction_deg", w.gust.direction_deg);
  }
}

nlohmann::json WindJson(const WindSpec& w) {
  nlohmann::json j = {{"speed_mps", w.speed_mps}, {"direction_deg", w.direction_deg}, {"turbulence", w.turbulence}};
  if (w.gust.speed_mps > 0.0)
    j["gust"] = {{"start_s", w.gust.start_s}, {"rise_s", w.gust.rise_s}, {"hold_s", w.gust.hold_s},
                 {"speed_mps", w.gust.speed_mps}, {"direction_deg", w.gust.direction_deg}};
  return j;
}

// The spec's fields under `f`: each optional (a spec file may name only what differs from the
// defaults), each checked for its type.
void ReadSpec(const Fields& f, EpisodeSpec& s) {
  s = EpisodeSpec{};
  f.Optional("world", s.world);
  f.Optional("seed", s.seed);
  f.Optional("world_params", s.world_params);
  f.Optional("start", s.start);
  f.Optional("goal", s.goal);
  f.Optional("board", s.board);
  f.Optional("method", s.method);
  f.Optional("clock", s.clock);
  f.Optional("cost", s.cost);
  f.Optional("dilation", s.dilation);
  f.Optional("speed_probe", s.speed_probe);
  f.Optional("timeout_s", s.timeout_s);
  f.Optional("policy", s.policy);
  f.Optional("overrides", s.overrides);
  f.Optional("units", s.units);
  f.Optional("scale", s.scale);
  f.Optional("up", s.up);
  f.Optional("recenter", s.recenter);
  f.Optional("model_path", s.model_path);
  if (const nlohmann::json* ros = f.Find("ros")) s.ros = ros->get<RosStack>();
  f.Optional("rosbag_dir", s.rosbag_dir);
  if (const auto wind = f.Child("wind")) ReadWind(*wind, s.wind);
  f.Optional("odometry_noise", s.odometry_noise);
  if (s.ros && s.ros->name != s.method)
    throw std::invalid_argument("episode spec: method '" + s.method + "' is not its ROS stack's name '" + s.ros->name + "'");
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
  if (s.speed_probe != "check") j["speed_probe"] = s.speed_probe;
  if (s.ros) j["ros"] = *s.ros;
  if (!s.rosbag_dir.empty()) j["rosbag_dir"] = s.rosbag_dir;
  // Absent in still air with perfect odometry, so the specs of such episodes read as before.
  if (s.wind != WindSpec{}) j["wind"] = WindJson(s.wind);
  if (s.odometry_noise != "none") j["odometry_noise"] = s.odometry_noise;
  return j;
}

}  // namespace

std::string WindSpecError(const WindSpec& w) {
  const auto speed = [](double v) { return std::isfinite(v) && v >= 0.0 && v <= kMaxWindSpeed; };
  const std::string speed_range = "must be in [0, " + Fixed(kMaxWindSpeed, 0) + "] m/s";
  if (!speed(w.speed_mps)) return "wind.speed_mps: " + speed_range;
  const auto angle = [](double a) { return std::isfinite(a) && std::abs(a) <= 360.0; };
  if (!angle(w.direction_deg)) return "wind.direction_deg: must be in [-360, 360] degrees";
  if (std::find_if(kTurbulenceLevels.begin(), kTurbulenceLevels.end(),
                   [&](const char* l) { return w.turbulence == l; }) == kTurbulenceLevels.end())
    return "wind.turbulence: '" + w.turbulence + "' is not one of none, light, moderate, severe";
  const GustSpec& g = w.gust;
  if (!(std::isfinite(g.start_s) && g.start_s >= 0.0)) return "wind.gust.start_s: must be finite and >= 0 s";
  if (!(std::isfinite(g.rise_s) && g.rise_s > 0.0)) return "wind.gust.rise_s: must be finite and > 0 s";
  if (!(std::isfinite(g.hold_s) && g.hold_s >= 0.0)) return "wind.gust.hold_s: must be finite and >= 0 s";
  if (!speed(g.speed_mps)) return "wind.gust.speed_mps: " + speed_range;
  if (!angle(g.direction_deg)) return "wind.gust.direction_deg: must be in [-360, 360] degrees";
  return "";
}

std::string OdometryNoiseError(const std::string& preset) {
  for (const char* p : kOdometryNoisePresets)
    if (preset == p) return "";
  return "odometry_noise: '" + preset + "' is not one of none, good, typical, poor";
}

void to_json(nlohmann::json& j, const EpisodeSpec& s) { j = SpecFields(s); }

void from_json(const nlohmann::json& j, EpisodeSpec& s) {
  const JsonReader r("episode spec");
  ReadSpec(Fields(r, j, ""), s);
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
      {"task_cpu_util_pct", r.task_cpu_util_pct},
      {"deadline_miss_ratio", r.deadline_miss_ratio},
      {"jobs_released", r.jobs_released},
      {"deadline_misses", r.deadline_misses},
      {"replans", r.replans},
      {"replans_by_trigger", r.replans_by_trigger},
      {"plan_failures", r.plan_failures},
      {"emergency_stops", r.emergency_stops},
      {"time_stopped_s", r.time_stopped_s},
      {"setpoint_lag_p95_m", r.setpoint_lag_p95_m},
      {"eci",
       {{"min", r.eci.min},
        {"mean", r.eci.mean},
        {"max", r.eci.max},
        {"flight_min", r.eci.flight_min},
        {"flight_max", r.eci.flight_max},
        {"flight_frames", r.eci.flight_frames}}},
      {"eci_time_ms_mean", r.eci_time_ms_mean},
      {"adapter_time_ms_mean", r.adapter_time_ms_mean},
      {"sim_time_s", r.sim_time_s},
      {"notes", r.notes},
  };
  j["collision_point"] = r.collision_point ? nlohmann::json(*r.collision_point) : nlohmann::json();
  j["collided_with"] = r.collided_with;
  // A number for compare and the dashboard, which read numbers and booleans only.
  j["collided_mover"] = r.collided_with.rfind("mover:", 0) == 0;
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
  // Only when the episode has them, so the results of still air and perfect odometry read as before.
  if (!s.wind_speed.empty()) j["series"]["wind_speed"] = s.wind_speed;
  if (!s.odometry_error.empty()) j["series"]["odometry_error"] = s.odometry_error;
}

void from_json(const nlohmann::json& j, EpisodeResult& r) {
  r = EpisodeResult{};
  const JsonReader reader("episode result");
  const Fields f(reader, j, "");
  if (const auto spec = f.Child("spec")) ReadSpec(*spec, r.spec);
  f.Optional("scenario", r.scenario);
  f.Required("success", r.success);
  f.Optional("collided", r.collided);
  f.Optional("timed_out", r.timed_out);
  f.Required("end_reason", r.end_reason);
  f.Optional("collision_point", r.collision_point);
  f.Optional("collided_with", r.collided_with);
  f.Optional("flight_time_s", r.flight_time_s);
  f.Optional("path_length_m", r.path_length_m);
  f.Optional("straight_line_m", r.straight_line_m);
  f.Optional("velocity_mean_mps", r.velocity_mean_mps);
  f.Optional("velocity_std_mps", r.velocity_std_mps);
  f.Optional("accel_peak_mps2", r.accel_peak_mps2);
  f.Optional("nav_cpu_util_pct", r.nav_cpu_util_pct);
  f.Optional("task_cpu_util_pct", r.task_cpu_util_pct);
  f.Optional("deadline_miss_ratio", r.deadline_miss_ratio);
  f.Optional("jobs_released", r.jobs_released);
  f.Optional("deadline_misses", r.deadline_misses);
  f.Optional("replans", r.replans);
  f.Optional("replans_by_trigger", r.replans_by_trigger);
  f.Optional("plan_failures", r.plan_failures);
  f.Optional("emergency_stops", r.emergency_stops);
  f.Optional("time_stopped_s", r.time_stopped_s);
  f.Optional("setpoint_lag_p95_m", r.setpoint_lag_p95_m);
  if (const auto e = f.Child("eci")) {
    e->Optional("min", r.eci.min);
    e->Optional("mean", r.eci.mean);
    e->Optional("max", r.eci.max);
    e->Optional("flight_min", r.eci.flight_min);
    e->Optional("flight_max", r.eci.flight_max);
    e->Optional("flight_frames", r.eci.flight_frames);
  }
  f.Optional("eci_time_ms_mean", r.eci_time_ms_mean);
  f.Optional("adapter_time_ms_mean", r.adapter_time_ms_mean);
  f.Optional("sim_time_s", r.sim_time_s);
  f.Optional("notes", r.notes);
  if (const nlohmann::json* events = f.Find("events")) {
    reader.Array(*events, "events");
    for (std::size_t i = 0; i < events->size(); ++i) {
      const Fields e(reader, (*events)[i], JsonReader::Index("events", i));
      EpisodeEvent ev;
      e.Required("t", ev.t);
      e.Required("kind", ev.kind);
      e.Required("detail", ev.detail);
      r.events.push_back(std::move(ev));
    }
  }
  if (const auto series = f.Child("series")) {
    TimeSeries& s = r.series;
    series->Optional("t", s.t);
    series->Optional("position", s.position);
    series->Optional("velocity", s.velocity);
    series->Optional("eci", s.eci);
    series->Optional("f_per", s.f_per);
    series->Optional("f_col", s.f_col);
    series->Optional("f_dif", s.f_dif);
    series->Optional("res", s.res);
    series->Optional("utilisation", s.utilisation);
    series->Optional("wind_speed", s.wind_speed);
    series->Optional("odometry_error", s.odometry_error);
    series->Optional("events", s.events);
  }
}

}  // namespace enavi::api
