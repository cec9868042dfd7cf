#pragma once
// The navigation stack's periodic and sporadic tasks (paper Sec. III.A) and what one job of a
// task hands back to the scheduler.

#include <array>
#include <functional>
#include <string_view>

#include "navstack/common/work.h"

namespace enavi::navstack {

enum class TaskId : int {
  kPerception = 0,  ///< depth -> points -> occupancy map (f_per)
  kPlanning,        ///< path search + B-spline optimisation (timer or trigger)
  kCollision,       ///< remaining trajectory vs current map (f_col)
  kDifference,      ///< environment-difference detection on raw frames (f_dif)
  kEci,             ///< complexity index of every frame (E-Navi only; not a navigation task)
  kAdapter,         ///< strategy controller decision (E-Navi only)
  kCount
};
inline constexpr int kTaskCount = static_cast<int>(TaskId::kCount);
inline constexpr std::array<std::string_view, kTaskCount> kTaskNames = {
    "perception", "planning", "collision", "difference", "eci", "adapter"};
inline constexpr std::string_view TaskName(TaskId id) { return kTaskNames[static_cast<int>(id)]; }
/// The four tasks the paper counts as navigation workload (eci and adapter are reported apart).
inline constexpr bool IsNavigationTask(TaskId id) {
  return id == TaskId::kPerception || id == TaskId::kPlanning || id == TaskId::kCollision ||
         id == TaskId::kDifference;
}

/// What a job did (priced by the cost model) and the effect it has once it finishes. The code
/// runs when the scheduler starts the job, reading the data available then; `commit` runs at the
/// job's finish time, so nothing it produces is visible earlier.
struct JobOutput {
  WorkCounts work;
  std::function<void()> commit;
  /// The job left a decision to be taken outside the stack (navstack/rl/decision_port.h) that its
  /// commit needs: the virtual executor stops at this instant, once the jobs given a core with it
  /// have run their code, until AdvanceTo is called again (VirtualExecutor::paused). Other
  /// executors refuse such a job.
  bool awaits_decision = false;
};

using JobFn = std::function<JobOutput()>;

}  // namespace enavi::navstack
