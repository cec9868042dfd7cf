#include "navstack/methods/method_config.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

#include "navstack/methods/registry.h"
#include "navstack/planning/planner_options.h"

namespace enavi::navstack {
namespace {

struct Setter {
  MethodTunable tunable;
  std::function<void(MethodConfig&, double)> set;
};

const std::vector<Setter>& Setters() {
  static const std::vector<Setter> setters = {
      {{"planner.v_max", 0.2, 10.0, 2.0, false, "maximum speed, m/s"},
       [](MethodConfig& c, double v) { c.nav.planner.v_max = v; }},
      {{"planner.a_max", 0.5, 20.0, 3.0, false, "maximum acceleration, m/s^2"},
       [](MethodConfig& c, double v) { c.nav.planner.a_max = v; }},
      {{"planner.yaw_rate_max", 0.1, 100.0, PlannerOptions{}.yaw_rate_max, false, "heading rate limit, rad/s"},
       [](MethodConfig& c, double v) { c.nav.planner.yaw_rate_max = v; }},
      {{"planner.yaw_accel_max", 0.1, 1000.0, PlannerOptions{}.yaw_accel_max, false,
        "heading acceleration limit, rad/s^2 (1000: about none, as in Ego-Planner's traj_server)"},
       [](MethodConfig& c, double v) { c.nav.planner.yaw_accel_max = v; }},
      {{"planner.robot_radius", 0.1, 2.0, 0.3, false, "obstacle inflation radius, m"},
       [](MethodConfig& c, double v) { c.nav.planner.robot_radius = v; }},
      {{"planner.optimizer", 0, 1, 0, true,
        "0: ESDF optimiser (fixed, enavi), 1: Ego-Planner's rebound (baseline); default: the method's"},
       [](MethodConfig& c, double v) {
         c.nav.planner.optimizer = v > 0 ? PlannerOptimizer::kRebound : PlannerOptimizer::kEsdf;
       }},
      {{"perception.stride", 1, 64, 2, true, "depth pixel stride for mapping"},
       [](MethodConfig& c, double v) { c.nav.perception_stride = static_cast<int>(v); }},
      {{"perception.max_range", 1.0, 10.0, 5.0, false, "mapping range, m"},
       [](MethodConfig& c, double v) { c.nav.perception_max_range = v; }},
      {{"sched.threads", 0, 64, 0, true, "threads the jobs run on (0: the method's default; capped at the board's cores)"},
       [](MethodConfig& c, double v) {
         if (v > 0) c.scheduler.threads = static_cast<int>(v);
       }},
      {{"sched.global_edf", 0, 1, 0, true, "1: preemptive global EDF, 0: FIFO without preemption"},
       [](MethodConfig& c, double v) {
         c.scheduler.policy = v > 0 ? SchedulingPolicy::kGlobalEdf : SchedulingPolicy::kFifoNonPreemptive;
       }},
  };
  return setters;
}

std::string Number(double v) {
  std::string s = std::to_string(v);
  s.erase(s.find_last_not_of('0') + 1);
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

}  // namespace

const std::vector<MethodTunable>& StackTunables() {
  static const std::vector<MethodTunable> list = [] {
    std::vector<MethodTunable> out;
    for (const Setter& s : Setters()) out.push_back(s.tunable);
    return out;
  }();
  return list;
}

std::vector<MethodTunable> StackTunablesFor(const MethodInfo& method) {
  std::vector<MethodTunable> out = StackTunables();
  out.insert(out.end(), method.tunables.begin(), method.tunables.end());
  return out;
}

std::string TunableNames(const std::vector<MethodTunable>& tunables) {
  std::string names;
  for (const MethodTunable& t : tunables) names += (names.empty() ? "" : ", ") + t.name;
  return names;
}

void CheckTunableRange(const MethodTunable& t, double value) {
  if (!std::isfinite(value) || value < t.min || value > t.max || (t.integer && value != std::floor(value)))
    throw std::invalid_argument(t.name + ": " + Number(value) + " is outside [" + Number(t.min) + ", " + Number(t.max) +
                                "]" + (t.integer ? " or not an integer" : ""));
}

MethodConfig ConfigureMethodDefaults(const MethodInfo& method, const MethodSetup& setup) {
  MethodConfig config;
  config.method = &method;
  ConfigureMethod(method, setup, &config.nav);
  config.scheduler = method.scheduler;
  return config;
}

bool ApplyOverride(const std::string& name, double value, MethodConfig* config) {
  const auto common = std::find_if(Setters().begin(), Setters().end(),
                                   [&](const Setter& s) { return s.tunable.name == name; });
  if (common != Setters().end()) {
    CheckTunableRange(common->tunable, value);
    common->set(*config, value);
    return true;
  }
  const std::vector<MethodTunable>& own = config->method->tunables;
  const auto it = std::find_if(own.begin(), own.end(), [&](const MethodTunable& t) { return t.name == name; });
  if (it == own.end()) return false;
  CheckTunableRange(*it, value);
  config->nav.params[name] = value;
  return true;
}

MethodConfig ConfigureMethodWithOverrides(const MethodInfo& method, const MethodSetup& setup,
                                          const std::map<std::string, double>& overrides) {
  MethodConfig config = ConfigureMethodDefaults(method, setup);
  for (const auto& [name, value] : overrides)
    if (!ApplyOverride(name, value, &config))
      throw std::invalid_argument(name + ": unknown parameter for method " + method.name +
                                  " (known: " + TunableNames(StackTunablesFor(method)) + ")");
  return config;
}

}  // namespace enavi::navstack
