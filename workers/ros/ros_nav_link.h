#pragma once
// The ROS bridge's link (docs/ros.md): a user's ROS 1 stack flown as the episode's navigation
// method, on the emulated clock.
//
// Per episode: the board's cgroups (emulation::BoardSlot: the board's capacity for the group,
// one board core for each thread), a private master on a free loopback port, the simulator's
// node /enavi_sim, and the stack (roslaunch or a command) started inside the board's groups, so
// every process and thread of it runs at the board's speed. Sim time is wall time / dilation:
// the simulator publishes /clock and the streams at their due wall times (the emulated clock's
// pacing) and tracks what the stack commands. Nothing is left behind: the processes run under a
// supervisor that ends them and removes the groups even when the simulator is killed
// (process_supervisor.h).
//
// What the stack can do wrong ends the episode with a reason (NavLink::failure): it exits
// (stack_exited, stack_crashed, with its exit status and the tail of its log), never advertises
// its command topic within startup_timeout_s (stack_not_ready), never commands within
// command_timeout_s of sim time (no_command), commands NaN or out-of-bounds setpoints
// (bad_command), or publishes another type on the command topic (command_wrong_type).

#include <memory>
#include <string>

#include "api/ros_stack.h"
#include "workers/board/board_profile.h"
#include "workers/emulation/emulation_options.h"
#include "workers/ros/bridge_node.h"
#include "workers/sim/nav_link.h"

namespace enavi::ros {

struct RosLinkOptions {
  api::RosStack stack;
  board::BoardProfile board;
  double dilation = 0;  ///< <= 0: the smallest that fits the host's free CPUs
  EpisodeGeometry geometry;
  navstack::VehicleState initial;
  /// Where the episode's logs (stack.log, master.log, ros_log/) go; empty: a temporary
  /// directory removed afterwards (the result keeps the stack log's tail when it failed).
  std::string output_dir;
  /// Record the episode's topics into this bag file (empty: no recording).
  std::string bag_file;
  emulation::EmulationOptions emulation;
};

class RosNavLink final : public sim::NavLink {
 public:
  /// Prepares the board, starts the master, joins it, starts the stack and waits until it
  /// advertises its command topic. A stack that fails to get there is not an error: the episode
  /// ends at once with failure() set. Throws std::invalid_argument when this host cannot emulate
  /// the board (see emulation::BoardSlot) or ROS is not installed, std::runtime_error when the
  /// master cannot be started.
  explicit RosNavLink(RosLinkOptions options);
  /// Stops the stack, the recorder and the master, removes the groups.
  ~RosNavLink() override;

  void OnState(const navstack::VehicleState& state) override;
  void OnFrame(navstack::DepthFramePtr frame) override;
  void AdvanceTo(double t) override;
  navstack::TrajectorySample Reference(double t) override;
  std::vector<navstack::NavEvent> TakeEvents() override;
  /// A ROS stack's task rates and map are its own business: zero (not known to the farm).
  navstack::TaskRates rates() const override;
  double map_resolution() const override { return 0; }
  sim::NavAccounting Accounting() const override;
  /// Stops the stack and the recorder (their CPU and the bag are final after this).
  void FinishEpisode(bool collided, bool reached_goal) override;
  const navstack::rl::Rollout* rollout() const override { return nullptr; }
  double OffBoardSeconds(navstack::TaskId task, const navstack::WorkCounts& work, double host_cpu_s) const override;
  std::optional<sim::LinkFailure> failure() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Makes ROS methods fly in this process: registers the bridge's link with the episode
/// (sim::RegisterLink, method kind ros, clock emulated). The composition roots call it where the
/// bridge was built.
void RegisterRosLink();

}  // namespace enavi::ros
