#pragma once
// How the episode reaches the navigation stack: in-process on the virtual clock, in a throttled
// child process on the emulated clock, or a stack of its own processes (a ROS stack). The
// episode (sensor, controller, physics, metrics) is the same for all; only this link differs.
// Links are registered by method kind and clock (link_registry.h).

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "navstack/common/camera.h"
#include "navstack/common/state.h"
#include "navstack/runtime/executor.h"
#include "navstack/methods/method.h"

namespace enavi::sim {

/// What the stack spent and missed, per task, for the episode's results.
struct NavAccounting {
  std::array<navstack::TaskStats, navstack::kTaskCount> tasks{};
  std::int64_t plan_failures = 0;
  std::map<std::string, std::string> notes;  ///< how the numbers were produced (fallbacks, quotas)
  /// A stack that runs as processes of its own (a ROS stack): board seconds of CPU by process
  /// (node) name, measured; its navigation CPU is their sum. Empty for the in-process methods,
  /// whose CPU is their tasks'.
  std::map<std::string, double> process_cpu_board_s;

  const navstack::TaskStats& operator[](navstack::TaskId id) const { return tasks[static_cast<int>(id)]; }
};

/// Why a stack that runs as processes ended the episode (it exited, misbehaved): the result's end
/// reason and what the results say about it.
struct LinkFailure {
  std::string reason;  ///< stack_exited, stack_crashed, stack_not_ready, no_command, bad_command, ...
  std::string detail;
};

class NavLink {
 public:
  virtual ~NavLink() = default;
  /// Latest odometry and a new sensor frame (call before AdvanceTo for the same instant).
  virtual void OnState(const navstack::VehicleState& state) = 0;
  virtual void OnFrame(navstack::DepthFramePtr frame) = 0;
  /// Lets the stack run up to sim time t (virtual: the EDF schedule; emulated: wall-clock pacing).
  virtual void AdvanceTo(double t) = 0;
  /// The last AdvanceTo stopped before t: a decision of the stack waits for its action from
  /// outside (navstack/rl/decision_port.h, the Python environment). Supply it, then call
  /// AdvanceTo(t) again: the stack goes on from the same instant as if it had been there at once.
  /// Only the virtual clock's link stops; the others never do.
  virtual bool paused() const { return false; }
  /// The reference the flight controller tracks at t.
  virtual navstack::TrajectorySample Reference(double t) = 0;
  virtual std::vector<navstack::NavEvent> TakeEvents() = 0;
  /// Current configuration, for the time series.
  virtual navstack::TaskRates rates() const = 0;
  virtual double map_resolution() const = 0;
  virtual NavAccounting Accounting() const = 0;
  /// The episode ended: E-Navi closes its rollout (reward of the last epoch, terminal flag).
  virtual void FinishEpisode(bool collided, bool reached_goal) = 0;
  /// The E-Navi rollout recorded for training, or null.
  virtual const navstack::rl::Rollout* rollout() const = 0;
  /// Board seconds of work done outside the stack's schedule (the metrics' eci of every frame).
  virtual double OffBoardSeconds(navstack::TaskId task, const navstack::WorkCounts& work,
                                 double host_cpu_s) const = 0;
  /// The stack ended the episode (checked after every AdvanceTo); the in-process stacks never do.
  virtual std::optional<LinkFailure> failure() const { return std::nullopt; }
};

}  // namespace enavi::sim
