#pragma once
// The contract for one flight episode: what to fly (EpisodeSpec) and what came out of it
// (EpisodeResult). `enavi fly --json`, the worker, the DDS messages and the SQLite store all use
// these records and their JSON form, so a result means the same thing everywhere.

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "api/ros_stack.h"

namespace enavi::api {

using Vec3 = std::array<double, 3>;

/// Cost modes of the virtual clock (docs/design.md, "Time: two clocks").
inline constexpr std::array<const char*, 2> kCostModes = {"model", "measured"};
/// What the emulated clock does with its measurement of the host's speed before an episode
/// (workers/board/EMULATION.md, "Host calibration file"): check reports the drift since the
/// calibration and keeps the calibration's speed, use emulates the board on the speed now, off
/// measures nothing.
inline constexpr std::array<const char*, 3> kSpeedProbeModes = {"check", "use", "off"};

/// Dryden turbulence severities (MIL-F-8785C low altitude; workers/sim/wind.h).
inline constexpr std::array<const char*, 4> kTurbulenceLevels = {"none", "light", "moderate", "severe"};
/// Imperfect-odometry presets (workers/sim/odometry_noise.h); "none" hands the stack the truth.
inline constexpr std::array<const char*, 4> kOdometryNoisePresets = {"none", "good", "typical", "poor"};
/// Largest mean wind or gust speed a spec may ask for, m/s.
inline constexpr double kMaxWindSpeed = 40.0;

/// A discrete "1-cosine" gust (MIL-F-8785C Sec. 3.7.5) in time: from start_s it rises over rise_s
/// to speed_mps, holds for hold_s and falls back over rise_s. speed_mps 0: no gust.
struct GustSpec {
  double start_s = 0.0;
  double rise_s = 1.0;
  double hold_s = 0.0;
  double speed_mps = 0.0;
  double direction_deg = 0.0;  ///< where it blows to, degrees from world +x toward +y
  bool operator==(const GustSpec&) const = default;
};

/// The air an episode flies in (workers/sim/wind.h): a mean wind, a gust and Dryden turbulence.
/// The stack is never told; the vehicle's drag feels it. Default: still air.
struct WindSpec {
  double speed_mps = 0.0;      ///< mean wind, horizontal
  double direction_deg = 0.0;  ///< where it blows to, degrees from world +x toward +y
  std::string turbulence = "none";  ///< one of kTurbulenceLevels
  GustSpec gust;
  bool Active() const { return speed_mps > 0.0 || turbulence != "none" || gust.speed_mps > 0.0; }
  bool operator==(const WindSpec&) const = default;
};

/// Why `wind` is not valid, as "wind.FIELD: reason", or "" when it is.
std::string WindSpecError(const WindSpec& wind);
/// Why `preset` is not an odometry-noise preset, as "odometry_noise: reason", or "" when it is.
std::string OdometryNoiseError(const std::string& preset);

/// A tunable as job validation sees it.
struct TunableRange {
  std::string name;
  double min = 0, max = 0;
  bool integer = false;
};
/// A registered navigation method as job validation sees it.
struct MethodEntry {
  std::string name;
  std::string summary;
  std::vector<TunableRange> tunables;  ///< every override a spec for this method may set
};
/// What job validation knows, as data. api sits below the registries (methods: navstack/methods;
/// boards: workers/board/profiles; scenarios: the worlds generators; clocks: workers/sim), so the
/// composition root hands their contents in (sim::FarmCatalog()).
struct Catalog {
  std::vector<MethodEntry> methods;
  std::vector<std::string> boards;
  std::vector<std::string> scenarios;
  std::vector<std::string> clocks;
  /// Overrides with one of these prefixes pass unchecked (episode commands other than
  /// `enavi fly`, e.g. the farm tests' fake episode with its `fake.*` knobs).
  std::vector<std::string> unchecked_prefixes;

  const MethodEntry* Find(const std::string& name) const {
    for (const MethodEntry& m : methods)
      if (m.name == name) return &m;
    return nullptr;
  }
};

struct EpisodeSpec {
  std::string world = "s1";  ///< scenario id (a worlds generator), a world file, a mesh or an SDF world
  std::uint64_t seed = 1;    ///< world generator seed and episode seed (sensor noise, planner)
  std::map<std::string, std::string> world_params;  ///< generator parameters
  std::optional<Vec3> start;  ///< required for mesh and SDF worlds
  std::optional<Vec3> goal;
  // Mesh-file worlds: how the file is placed (empty/unset: what the file declares, else m, z up).
  std::string units;          ///< m, cm, mm, in, ft
  double scale = 1.0;         ///< uniform factor after the unit
  std::string up;             ///< y or z
  bool recenter = false;      ///< horizontal centre of the bounds to x = y = 0, lowest point to z = 0
  std::vector<std::string> model_path;  ///< SDF worlds: directories model:// URIs are looked up in
  std::string board = "host";
  std::string method = "baseline";
  std::string clock = "virtual";
  std::string cost = "model";
  double dilation = 1.0;      ///< emulated clock: 1 sim second = dilation wall seconds
  std::string speed_probe = "check";  ///< emulated clock: one of kSpeedProbeModes
  double timeout_s = 0.0;     ///< 0: derived from the start-goal distance
  std::string policy;         ///< E-Navi policy file; empty: the shipped default
  std::map<std::string, double> overrides;  ///< named tunables (validated by the runner)
  /// The method is a user's ROS 1 stack (docs/ros.md): how to start it and its topics; `method`
  /// is its name. Absent for the registered methods.
  std::optional<RosStack> ros;
  /// ROS methods: record the episode's topics into episode.bag in this directory (empty: none).
  std::string rosbag_dir;
  WindSpec wind;  ///< still air by default
  std::string odometry_noise = "none";  ///< the stack's odometry: one of kOdometryNoisePresets
};

/// Per-task CPU utilisation, % of one board core (psutil convention), by the method's key for each
/// of its navigation tasks (navstack::MethodInfo::task_keys; the built-ins' are perception,
/// planning, collision and difference): `task_cpu_util_pct.<key>` in results, tables, `enavi
/// compare` and the dashboard.
using TaskUtilisation = std::map<std::string, double>;

/// eci of the frames of an episode (docs/results.md, "eci range along a flight").
struct EciSummary {
  double min = 0, mean = 0, max = 0;  ///< over every frame, the hover before take-off included
  /// Over the frames in flight: from the first frame at which the vehicle moves faster than
  /// 0.5 m/s (the flight recorder's take-off speed) to the end. flight_frames = 0 when it never
  /// took off (then flight_min = flight_max = 0).
  double flight_min = 0, flight_max = 0;
  std::int64_t flight_frames = 0;
};

struct EpisodeEvent {
  double t = 0;
  std::string kind;    ///< replan, collision_trigger, difference_trigger, deadline_miss, failsafe, ...
  std::string detail;
};

/// Time series sampled at a fixed rate for plots; all columns have the same length.
struct TimeSeries {
  std::vector<double> t;
  std::vector<Vec3> position, velocity;
  std::vector<double> eci, f_per, f_col, f_dif, res, utilisation;
  /// Speed of the air at the vehicle, m/s: empty unless the episode flies in wind (spec.wind).
  std::vector<double> wind_speed;
  /// |estimated - true position| of the odometry the stack was given, m: empty unless the
  /// episode has odometry noise (spec.odometry_noise); the other columns are the truth.
  std::vector<double> odometry_error;
  std::vector<std::string> events;  ///< event kinds in the interval ending at t, ';'-separated
  std::size_t size() const { return t.size(); }
};

struct EpisodeResult {
  EpisodeSpec spec;
  std::string scenario;  ///< world's scenario id (or "custom")
  bool success = false;
  bool collided = false;
  bool timed_out = false;
  std::string end_reason;  ///< goal_reached, collision, timeout, failsafe, error: ...
  std::optional<Vec3> collision_point;
  /// What a collision touched: "static" (the world's objects or ground) or "mover:NAME" (one of
  /// the world's movers); empty without a collision.
  std::string collided_with;
  double flight_time_s = 0;
  double path_length_m = 0;
  double straight_line_m = 0;
  double velocity_mean_mps = 0;
  double velocity_std_mps = 0;
  double accel_peak_mps2 = 0;
  double nav_cpu_util_pct = 0;  ///< sum of the four navigation tasks
  TaskUtilisation task_cpu_util_pct;
  double deadline_miss_ratio = 0;
  std::int64_t jobs_released = 0;
  std::int64_t deadline_misses = 0;
  std::int64_t replans = 0;
  std::map<std::string, std::int64_t> replans_by_trigger;  ///< what asked for each plan that landed
  std::int64_t plan_failures = 0;   ///< planning calls that returned no trajectory
  std::int64_t emergency_stops = 0;
  double time_stopped_s = 0;        ///< below 0.1 m/s after first exceeding 0.5 m/s, before the end
  double setpoint_lag_p95_m = 0;    ///< p95 of |reference position - vehicle position|
  EciSummary eci;
  double eci_time_ms_mean = 0;
  double adapter_time_ms_mean = 0;
  double sim_time_s = 0;
  std::map<std::string, std::string> notes;  ///< how the result was produced (clock, fallbacks)
  std::vector<EpisodeEvent> events;
  TimeSeries series;
};

void to_json(nlohmann::json& j, const EpisodeSpec& s);
void from_json(const nlohmann::json& j, EpisodeSpec& s);
/// The flat result record (no time series or events): what `enavi fly --json` prints.
nlohmann::json ResultSummaryJson(const EpisodeResult& r);
/// Everything including time series and events.
void to_json(nlohmann::json& j, const EpisodeResult& r);
void from_json(const nlohmann::json& j, EpisodeResult& r);

}  // namespace enavi::api
