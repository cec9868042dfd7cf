#pragma once
// From an episode spec to the navigation stack's configuration: the method's task rates and the
// named tunables a job spec may override (STYLE.md rule 10: names and ranges).

#include <map>
#include <string>
#include <vector>

#include "api/episode.h"
#include "navstack/runtime/virtual_executor.h"
#include "navstack/methods/method.h"
#include "workers/sim/depth_camera.h"

namespace enavi::sim {

/// How the stack's jobs are scheduled on the board: threads 0 = all board cores (E-Navi's global
/// EDF); the baseline's ROS node runs its callbacks on one spinner thread.
using SchedulerConfig = navstack::MethodScheduler;

struct EpisodeConfig {
  const navstack::MethodInfo* method = nullptr;  ///< from the registry
  navstack::MethodOptions nav;
  SchedulerConfig scheduler;
  DepthNoise noise;
};

/// One overridable parameter: its name in job specs, allowed range, and what it sets.
using Tunable = navstack::MethodTunable;
/// The tunables every method accepts: the stack's (navstack::StackTunables: planner, perception,
/// scheduler), then the simulator's camera.*.
const std::vector<Tunable>& CommonTunables();
/// Every tunable a spec for `method` may override: the common ones, then the method's own.
std::vector<Tunable> TunablesFor(const navstack::MethodInfo& method);

/// The registries as plain data for job-spec validation at submit (api cannot see them):
/// navstack's methods with their tunables, the board profiles, the scenario generators, the clocks.
api::Catalog FarmCatalog();

/// Builds the configuration for `spec.method` (the registry's) and applies `spec.overrides`; the
/// method is told whether to record a training rollout and where its decisions come from when they
/// are taken outside it (EpisodeOptions::rollout, ::decisions). Throws std::invalid_argument naming
/// an unknown method or override, an out-of-range value with its range, or decisions a method
/// cannot take from outside.
EpisodeConfig MakeEpisodeConfig(const api::EpisodeSpec& spec, bool record_rollout = false,
                                navstack::rl::DecisionPort* decisions = nullptr);

}  // namespace enavi::sim
