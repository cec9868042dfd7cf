#include "workers/sim/episode_config.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>

#include "navstack/methods/registry.h"
#include "navstack/planning/planner_options.h"
#include "navstack/rl/shipped_policy.h"
#include "workers/board/board_profile.h"
#include "workers/sim/episode.h"
#include "worlds/generators.h"

namespace enavi::sim {

namespace {

struct Setter {
  Tunable tunable;
  std::function<void(EpisodeConfig&, double)> set;
};

const std::vector<Setter>& Setters() {
  static const std::vector<Setter> setters = {
      {{"planner.v_max", 0.2, 10.0, 2.0, false, "maximum speed, m/s"},
       [](EpisodeConfig& c, double v) { c.nav.planner.v_max = v; }},
      {{"planner.a_max", 0.5, 20.0, 3.0, false, "maximum acceleration, m/s^2"},
       [](EpisodeConfig& c, double v) { c.nav.planner.a_max = v; }},
      {{"planner.yaw_rate_max", 0.1, 100.0, navstack::PlannerOptions{}.yaw_rate_max, false, "heading rate limit, rad/s"},
       [](EpisodeConfig& c, double v) { c.nav.planner.yaw_rate_max = v; }},
      {{"planner.yaw_accel_max", 0.1, 1000.0, navstack::PlannerOptions{}.yaw_accel_max, false,
        "heading acceleration limit, rad/s^2 (1000: about none, as in Ego-Planner's traj_server)"},
       [](EpisodeConfig& c, double v) { c.nav.planner.yaw_accel_max = v; }},
      {{"planner.robot_radius", 0.1, 2.0, 0.3, false, "obstacle inflation radius, m"},
       [](EpisodeConfig& c, double v) { c.nav.planner.robot_radius = v; }},
      {{"planner.optimizer", 0, 1, 0, true, "0: ESDF optimiser (fixed, enavi), 1: Ego-Planner's rebound (baseline); default: the method's"},
       [](EpisodeConfig& c, double v) {
         c.nav.planner.optimizer = v > 0 ? navstack::PlannerOptimizer::kRebound : navstack::PlannerOptimizer::kEsdf;
       }},
      {{"perception.stride", 1, 64, 2, true, "depth pixel stride for mapping"},
       [](EpisodeConfig& c, double v) { c.nav.perception.stride = static_cast<int>(v); }},
      {{"perception.max_range", 1.0, 10.0, 5.0, false, "mapping range, m"},
       [](EpisodeConfig& c, double v) { c.nav.perception.max_range = v; }},
      {{"camera.decimation", 1, 8, 2, true, "depth stream: the 640x480 sensor decimated n x n (2: 320x240); perception.stride counts its pixels"},
       [](EpisodeConfig& c, double v) {
         c.nav.camera = navstack::CameraIntrinsics::Default().Decimated(static_cast<int>(v));
       }},
      {{"camera.noise_k", 0.0, 0.05, 0.0, false, "depth noise sigma = k d^2, 1/m"},
       [](EpisodeConfig& c, double v) { c.noise.k = v; }},
      {{"sched.threads", 0, 64, 0, true, "threads the jobs run on (0: the method's default; capped at the board's cores)"},
       [](EpisodeConfig& c, double v) {
         if (v > 0) c.scheduler.threads = static_cast<int>(v);
       }},
      {{"sched.global_edf", 0, 1, 0, true, "1: preemptive global EDF, 0: FIFO without preemption"},
       [](EpisodeConfig& c, double v) {
         c.scheduler.policy = v > 0 ? navstack::SchedulingPolicy::kGlobalEdf
                                    : navstack::SchedulingPolicy::kFifoNonPreemptive;
       }},
  };
  return setters;
}

std::string Known(const navstack::MethodInfo& method) {
  std::string known;
  for (const Tunable& t : TunablesFor(method)) known += (known.empty() ? "" : ", ") + t.name;
  return known;
}

void CheckRange(const Tunable& t, double value) {
  if (!std::isfinite(value) || value < t.min || value > t.max || (t.integer && value != std::floor(value)))
    throw std::invalid_argument("overrides." + t.name + ": " + std::to_string(value) + " is outside [" +
                                std::to_string(t.min) + ", " + std::to_string(t.max) + "]" +
                                (t.integer ? " or not an integer" : ""));
}

}  // namespace

const std::vector<Tunable>& CommonTunables() {
  static const std::vector<Tunable> list = [] {
    std::vector<Tunable> out;
    for (const auto& s : Setters()) out.push_back(s.tunable);
    return out;
  }();
  return list;
}

std::vector<Tunable> TunablesFor(const navstack::MethodInfo& method) {
  std::vector<Tunable> out = CommonTunables();
  out.insert(out.end(), method.tunables.begin(), method.tunables.end());
  return out;
}

api::Catalog FarmCatalog() {
  api::Catalog catalog;
  for (const navstack::MethodInfo& m : navstack::Methods()) {
    api::MethodEntry entry;
    entry.name = m.name;
    entry.summary = m.summary;
    for (const Tunable& t : TunablesFor(m)) entry.tunables.push_back({t.name, t.min, t.max, t.integer});
    catalog.methods.push_back(std::move(entry));
  }
  catalog.boards = board::KnownBoards();
  for (const worlds::GeneratorInfo& g : worlds::Generators()) catalog.scenarios.push_back(g.id);
  for (const ClockInfo& c : Clocks()) catalog.clocks.push_back(c.name);
  return catalog;
}

EpisodeConfig MakeEpisodeConfig(const api::EpisodeSpec& spec) {
  EpisodeConfig config;
  if (spec.ros) {
    // A user's ROS stack: no method of ours, no tunables (its launch arguments configure it); it
    // reads the default depth stream, and its processes need the real time of the emulated clock.
    if (!spec.overrides.empty())
      throw std::invalid_argument("overrides: method '" + spec.method +
                                  "' is a ROS stack: it has no tunables (its launch arguments are its stack's args)");
    if (spec.clock != "emulated")
      throw std::invalid_argument("clock: method '" + spec.method + "' is a ROS stack: it runs on the emulated clock only "
                                  "(its processes run in real time inside the board's cgroup), not on '" + spec.clock + "'");
    return config;
  }
  config.method = navstack::FindMethod(spec.method);
  if (!config.method) {
    std::string known;
    for (const std::string& n : navstack::MethodNames()) known += (known.empty() ? "" : ", ") + n;
    throw std::invalid_argument("method: unknown method '" + spec.method + "' (known: " + known + ")");
  }
  const navstack::MethodInfo& method = *config.method;
  navstack::MethodSetup setup;
  setup.seed = spec.seed;
  if (method.uses_policy) setup.policy = navstack::rl::LoadPolicyOrShipped(spec.policy);
  navstack::ConfigureMethod(method, setup, &config.nav);
  config.scheduler = {method.scheduler.policy, method.scheduler.threads};
  for (const auto& [name, value] : spec.overrides) {
    const auto common = std::find_if(Setters().begin(), Setters().end(),
                                     [&name = name](const Setter& s) { return s.tunable.name == name; });
    if (common != Setters().end()) {
      CheckRange(common->tunable, value);
      common->set(config, value);
      continue;
    }
    const auto own = std::find_if(method.tunables.begin(), method.tunables.end(),
                                  [&name = name](const Tunable& t) { return t.name == name; });
    if (own == method.tunables.end())
      throw std::invalid_argument("overrides." + name + ": unknown parameter for method " + method.name +
                                  " (known: " + Known(method) + ")");
    CheckRange(*own, value);
    config.nav.params[name] = value;
  }
  return config;
}

}  // namespace enavi::sim
