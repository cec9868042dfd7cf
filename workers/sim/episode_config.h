#pragma once
// From an episode spec to the navigation stack's configuration: the method's task rates and the
// named tunables a job spec may override (STYLE.md rule 10: names and ranges).

#include <map>
#include <string>
#include <vector>

#include "api/episode.h"
#include "navstack/runtime/virtual_executor.h"
#include "navstack/stack/nav_stack.h"
#include "workers/sim/depth_camera.h"

namespace enavi::sim {

/// How the stack's jobs are scheduled on the board.
struct SchedulerConfig {
  navstack::SchedulingPolicy policy = navstack::SchedulingPolicy::kGlobalEdf;
  /// Threads the jobs may use: 0 = all board cores (E-Navi's global EDF); the baseline's ROS
  /// node runs its callbacks on one spinner thread.
  int threads = 0;
};

struct EpisodeConfig {
  navstack::NavStackOptions nav;
  SchedulerConfig scheduler;
  DepthNoise noise;
};

/// One overridable parameter: its name in job specs, allowed range, and what it sets.
struct Tunable {
  std::string name;
  double min = 0, max = 0;
  bool integer = false;
  std::string help;
};
const std::vector<Tunable>& Tunables();

/// The baseline's configuration (paper Sec. VI): perception 30 Hz, planning on a 20 Hz timer,
/// collision check after every map update, no difference detection, 0.1 m map, no adaptation.
/// Its jobs run as the callbacks of one single-threaded ROS node (Ego-Planner's), first come
/// first served without preemption: the "partitioned scheme with static periods" the paper
/// contrasts E-Navi with (Sec. I).
navstack::TaskRates BaselineRates();

/// E-Navi's configuration before its first decision: triggered planning, periodic collision and
/// difference checks, the coarsest resolution of the adapter's ladder, global EDF on all cores.
navstack::TaskRates EnaviInitialRates();

/// The E-Navi frequency-adapter policy at `path`, or the shipped default when empty. Throws
/// std::invalid_argument naming the file and field for a missing or corrupt file.
std::shared_ptr<const navstack::rl::PolicyFile> LoadPolicy(const std::string& path);

/// Builds the configuration for `spec.method` and applies `spec.overrides`. Throws
/// std::invalid_argument naming an unknown override or an out-of-range value with its range.
EpisodeConfig MakeEpisodeConfig(const api::EpisodeSpec& spec);

}  // namespace enavi::sim
