#include "workers/sim/episode_config.h"

#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "navstack/rl/policy_io.h"

namespace enavi::sim {

// Generated from navstack/rl/policies/*.json by cmake/EmbedFiles.cmake.
const std::map<std::string, std::string>& EmbeddedPolicies();

namespace {

constexpr const char* kDefaultPolicyName = "enavi_default.json";

struct Setter {
  Tunable tunable;
  std::function<void(EpisodeConfig&, double)> set;
};

const std::vector<Setter>& Setters() {
  static const std::vector<Setter> setters = {
      {{"planner.v_max", 0.2, 10.0, false, "maximum speed, m/s"},
       [](EpisodeConfig& c, double v) { c.nav.planner.v_max = v; }},
      {{"planner.a_max", 0.5, 20.0, false, "maximum acceleration, m/s^2"},
       [](EpisodeConfig& c, double v) { c.nav.planner.a_max = v; }},
      {{"planner.robot_radius", 0.1, 2.0, false, "obstacle inflation radius, m"},
       [](EpisodeConfig& c, double v) { c.nav.planner.robot_radius = v; }},
      {{"perception.stride", 1, 64, true, "depth pixel stride for mapping"},
       [](EpisodeConfig& c, double v) { c.nav.perception.stride = static_cast<int>(v); }},
      {{"perception.max_range", 1.0, 10.0, false, "mapping range, m"},
       [](EpisodeConfig& c, double v) { c.nav.perception.max_range = v; }},
      {{"rates.f_per", 1.0, 30.0, false, "baseline perception rate, Hz"},
       [](EpisodeConfig& c, double v) { c.nav.rates.f_per = v; }},
      {{"rates.f_plan", 0.0, 50.0, false, "baseline planning timer, Hz (0: triggered)"},
       [](EpisodeConfig& c, double v) { c.nav.rates.f_plan = v; }},
      {{"rates.f_dif", 0.0, 30.0, false, "difference detection rate, Hz"},
       [](EpisodeConfig& c, double v) { c.nav.rates.f_dif = v; }},
      {{"map.resolution", 0.05, 1.0, false, "baseline map resolution, m"},
       [](EpisodeConfig& c, double v) {
         c.nav.rates.resolution = v;
         c.nav.map.resolution = v;
       }},
      {{"camera.decimation", 1, 8, true, "depth stream: the 640x480 sensor decimated n x n (2: 320x240); perception.stride counts its pixels"},
       [](EpisodeConfig& c, double v) {
         c.nav.camera = navstack::CameraIntrinsics::Default().Decimated(static_cast<int>(v));
       }},
      {{"camera.noise_k", 0.0, 0.05, false, "depth noise sigma = k d^2, 1/m"},
       [](EpisodeConfig& c, double v) { c.noise.k = v; }},
      {{"strategy.explore", 0, 1, true, "E-Navi: 1 samples the policy's actions (training), 0 greedy"},
       [](EpisodeConfig& c, double v) {
         if (c.nav.strategy) c.nav.strategy->mode = v > 0 ? navstack::rl::ActMode::kSample : navstack::rl::ActMode::kGreedy;
       }},
      {{"strategy.f_adapt", 1.0, 30.0, false, "E-Navi: strategy controller decisions per second, Hz"},
       [](EpisodeConfig& c, double v) {
         if (c.nav.strategy) c.nav.strategy->f_adapt = v;
       }},
      {{"sched.threads", 0, 64, true, "threads the jobs run on (0: all board cores)"},
       [](EpisodeConfig& c, double v) { c.scheduler.threads = static_cast<int>(v); }},
      {{"sched.global_edf", 0, 1, true, "1: preemptive global EDF, 0: FIFO without preemption"},
       [](EpisodeConfig& c, double v) {
         c.scheduler.policy = v > 0 ? navstack::SchedulingPolicy::kGlobalEdf
                                    : navstack::SchedulingPolicy::kFifoNonPreemptive;
       }},
  };
  return setters;
}

}  // namespace

const std::vector<Tunable>& Tunables() {
  static const std::vector<Tunable> list = [] {
    std::vector<Tunable> out;
    for (const auto& s : Setters()) out.push_back(s.tunable);
    return out;
  }();
  return list;
}

navstack::TaskRates BaselineRates() {
  navstack::TaskRates r;
  r.f_per = 30.0;
  r.f_plan = 20.0;
  r.f_col = 0.0;
  r.collision_on_map_update = true;
  r.f_dif = 0.0;
  r.resolution = 0.1;
  return r;
}

navstack::TaskRates EnaviInitialRates() {
  navstack::TaskRates r;
  r.f_per = 10.0;
  r.f_plan = 0.0;  // planning on triggers: collision, difference, end of trajectory
  r.f_col = 5.0;
  r.collision_on_map_update = false;
  r.f_dif = 5.0;
  r.resolution = 0.5;  // the Resolution Adapter's coarsest level; it refines from there
  return r;
}

std::shared_ptr<const navstack::rl::PolicyFile> LoadPolicy(const std::string& path) {
  if (!path.empty()) return std::make_shared<const navstack::rl::PolicyFile>(navstack::rl::LoadFrequencyPolicy(path));
  static const std::shared_ptr<const navstack::rl::PolicyFile> shipped = [] {
    const auto& files = EmbeddedPolicies();
    const auto it = files.find(kDefaultPolicyName);
    if (it == files.end()) return std::shared_ptr<const navstack::rl::PolicyFile>();
    return std::make_shared<const navstack::rl::PolicyFile>(
        navstack::rl::PolicyFromJson(nlohmann::json::parse(it->second), std::string("shipped ") + kDefaultPolicyName));
  }();
  if (!shipped)
    throw std::invalid_argument(std::string("policy: this build ships no trained E-Navi policy (") + kDefaultPolicyName +
                                "); train one with `enavi train` and pass it with --policy FILE");
  return shipped;
}

EpisodeConfig MakeEpisodeConfig(const api::EpisodeSpec& spec) {
  EpisodeConfig config;
  if (spec.method == "baseline") {
    config.nav.rates = BaselineRates();
    config.nav.map.resolution = config.nav.rates.resolution;
    config.scheduler = {navstack::SchedulingPolicy::kFifoNonPreemptive, 1};
  } else if (spec.method == "enavi") {
    config.nav.rates = EnaviInitialRates();
    navstack::StrategyOptions strategy;
    strategy.policy = LoadPolicy(spec.policy);
    strategy.seed = spec.seed;
    config.nav.strategy = strategy;
    config.scheduler = {navstack::SchedulingPolicy::kGlobalEdf, 0};
  } else {
    throw std::invalid_argument("method: unknown method '" + spec.method + "' (known: baseline, enavi)");
  }
  config.nav.seed = spec.seed;
  for (const auto& [name, value] : spec.overrides) {
    const Setter* found = nullptr;
    for (const auto& s : Setters())
      if (s.tunable.name == name) found = &s;
    if (!found) {
      std::string known;
      for (const auto& s : Setters()) known += (known.empty() ? "" : ", ") + s.tunable.name;
      throw std::invalid_argument("overrides." + name + ": unknown parameter (known: " + known + ")");
    }
    const Tunable& t = found->tunable;
    if (!std::isfinite(value) || value < t.min || value > t.max || (t.integer && value != std::floor(value)))
      throw std::invalid_argument("overrides." + name + ": " + std::to_string(value) + " is outside [" +
                                  std::to_string(t.min) + ", " + std::to_string(t.max) + "]" +
                                  (t.integer ? " or not an integer" : ""));
    found->set(config, value);
  }
  return config;
}

}  // namespace enavi::sim
