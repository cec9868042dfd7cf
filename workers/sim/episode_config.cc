#include "workers/sim/episode_config.h"

#include <algorithm>
#include <functional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "navstack/methods/method_config.h"
#include "navstack/methods/registry.h"
#include "navstack/rl/nav_policy.h"
#include "navstack/rl/shipped_policy.h"
#include "workers/board/board_profile.h"
#include "workers/sim/link_registry.h"
#include "worlds/generators.h"

namespace enavi::sim {

namespace {

struct Setter {
  Tunable tunable;
  std::function<void(EpisodeConfig&, double)> set;
};

// The simulator's own tunables (the depth stream it renders); the stack's are navstack's
// (navstack/methods/method_config.h).
const std::vector<Setter>& CameraSetters() {
  static const std::vector<Setter> setters = {
      {{"camera.decimation", 1, 10, 2, true, "depth stream: the 640x480 sensor decimated n x n (2: 320x240, 10: 64x48); perception.stride counts its pixels"},
       [](EpisodeConfig& c, double v) {
         c.nav.camera = navstack::CameraIntrinsics::Default().Decimated(static_cast<int>(v));
       }},
      {{"camera.noise_k", 0.0, 0.05, 0.0, false, "depth noise sigma = k d^2, 1/m"},
       [](EpisodeConfig& c, double v) { c.noise.k = v; }},
  };
  return setters;
}

}  // namespace

const std::vector<Tunable>& CommonTunables() {
  static const std::vector<Tunable> list = [] {
    std::vector<Tunable> out = navstack::StackTunables();
    for (const auto& s : CameraSetters()) out.push_back(s.tunable);
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

EpisodeConfig MakeEpisodeConfig(const api::EpisodeSpec& spec, bool record_rollout,
                                navstack::rl::DecisionPort* decisions) {
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
  // The cost model prices the method's jobs at its cost family's prices (the emulated clock's
  // budgets too): a family `enavi calibrate` has not fitted yet flies on measured costs only.
  if (spec.cost == "model" || spec.clock != "virtual") {
    const board::ReferenceCosts reference = board::LoadReferenceCosts();
    if (!reference.families.contains(method.cost_family)) {
      std::string priced;
      for (const auto& [family, c] : reference.families) priced += (priced.empty() ? "" : ", ") + family;
      throw std::invalid_argument("method '" + method.name + "': its cost family '" + method.cost_family +
                                  "' has no prices in reference costs " + reference.calibration_id + " (priced: " +
                                  priced + "): fit them with `enavi calibrate --write-reference "
                                  "workers/board/profiles/reference_costs.yaml` (its plan flies every registered "
                                  "method) and rebuild, or fly it on the virtual clock with cost: measured");
    }
  }
  if (decisions && !method.external_decisions)
    throw std::invalid_argument("method: '" + spec.method + "' takes no decisions from outside");
  navstack::MethodSetup setup;
  setup.seed = spec.seed;
  setup.record_rollout = record_rollout;
  setup.decisions = decisions;
  if (method.uses_policy) setup.policy = navstack::rl::LoadPolicyOrShipped(spec.policy);
  if (method.uses_nav_policy && !spec.policy.empty()) {
    setup.nav_policy = std::make_shared<const navstack::rl::NavPolicyNet>(navstack::rl::LoadNavPolicy(spec.policy));
  }
  navstack::MethodConfig stack = navstack::ConfigureMethodDefaults(method, setup);
  // The camera's overrides set what the stack's leave alone (nav.camera, noise): applied last.
  std::vector<std::pair<const Setter*, double>> camera;
  for (const auto& [name, value] : spec.overrides) {
    const auto it = std::find_if(CameraSetters().begin(), CameraSetters().end(),
                                 [&name = name](const Setter& s) { return s.tunable.name == name; });
    try {
      if (it != CameraSetters().end()) {
        navstack::CheckTunableRange(it->tunable, value);
        camera.emplace_back(&*it, value);
      } else if (!navstack::ApplyOverride(name, value, &stack)) {
        throw std::invalid_argument(name + ": unknown parameter for method " + method.name +
                                    " (known: " + navstack::TunableNames(TunablesFor(method)) + ")");
      }
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("overrides.") + e.what());
    }
  }
  config.nav = std::move(stack.nav);
  config.scheduler = stack.scheduler;
  for (const auto& [setter, value] : camera) setter->set(config, value);
  return config;
}

}  // namespace enavi::sim
