#pragma once
// The emulated clock's link (`--clock emulated`, docs/design.md, "Time: two clocks", issue 5): the navigation
// stack runs in its own process inside the board's cgroup, the simulator stays outside and is
// paced to wall-clock time times the dilation k (1 sim second = k wall seconds).
//
// Process model: the simulator fork()s itself once the world is loaded; the child runs only the
// navstack (NavStack on a navstack::RealtimeExecutor) and _exit()s, never returning into the
// simulator's code. fork without exec hands the child the exact MethodOptions the episode
// built (no second serialisation to keep in step with the stack), works the same under
// `enavi fly`, the farm's `enavi fly` subprocesses and in-process tests, and the child's
// address space is shared copy-on-write. The child waits on a pipe until it is inside the
// board's groups, so no navstack instruction runs unthrottled; PR_SET_PDEATHSIG kills it if the
// simulator dies.
//
// IPC: frames and odometry through emulation::ShmChannel (memfd, triple buffer, seqlocks, futexes);
// the stack's outputs (trajectories as B-spline control points, hold reference, task rates,
// map resolution, events, per-task accounting) through seqlock slots in a shared anonymous
// mapping (emulated_wire.h).
//
// Speed: quota = cores x speed / k for the board group, speed / k for each thread's group,
// speed = board per-core speed / host per-core speed (host calibration file). Each worker
// thread is a SCHED_DEADLINE speed server (runtime = speed / k x period) where the kernel
// grants it; else its per-thread cgroup quota throttles it. The result notes say which.
//
// Clean-up: the child and the episode's groups are removed when the link is destroyed, also
// when the episode throws, and on SIGINT/SIGTERM (handlers installed while the link lives if
// the process had none; the signal is re-raised after the clean-up). Groups left by a killed
// simulator are reaped by the next emulated episode on the host.

#include <sys/types.h>

#include <memory>

#include "navstack/runtime/virtual_executor.h"
#include "workers/board/board_profile.h"
#include "workers/emulation/emulation_options.h"
#include "workers/sim/nav_link.h"

namespace enavi::emulation {

class EmulatedNavLink final : public sim::NavLink {
 public:
  /// Starts the navstack process and waits until its threads run in the board's groups.
  /// `dilation` <= 0 picks the smallest k (multiple of 0.25) at which the board fits the host's
  /// free CPUs. Throws std::invalid_argument when this host cannot emulate the board (no valid
  /// host calibration, no writable cgroup hierarchy, admission refused, board faster than the
  /// host), std::runtime_error when the navstack process fails to start.
  EmulatedNavLink(const navstack::MethodInfo& method, const navstack::MethodOptions& options, int threads,
                  navstack::SchedulingPolicy policy,
                  const board::BoardProfile& board, double dilation, const navstack::VehicleState& initial,
                  const EmulationOptions& emulation = {});
  /// Stops the navstack process, removes the episode's groups.
  ~EmulatedNavLink() override;

  void OnState(const navstack::VehicleState& state) override;
  void OnFrame(navstack::DepthFramePtr frame) override;
  /// Sleeps until wall time reaches epoch + t x k, then takes the stack's newest outputs.
  /// Throws std::runtime_error if the navstack process died or failed, or on SIGINT/SIGTERM.
  void AdvanceTo(double t) override;
  navstack::TrajectorySample Reference(double t) override;
  std::vector<navstack::NavEvent> TakeEvents() override;
  navstack::TaskRates rates() const override;
  double map_resolution() const override;
  sim::NavAccounting Accounting() const override;
  /// Rollouts (E-Navi training) are recorded on the virtual clock only: nothing to close here.
  void FinishEpisode(bool, bool) override {}
  const navstack::rl::Rollout* rollout() const override { return nullptr; }
  /// Work done in the simulator process (the metrics' eci): host CPU time / board speed.
  double OffBoardSeconds(navstack::TaskId task, const navstack::WorkCounts& work, double host_cpu_s) const override;

  pid_t navstack_pid() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Makes the emulated clock one episodes in this process can run on (sim::RegisterLink, method
/// kind navstack, clock "emulated"). The composition roots that fly on it call it once (enavi's
/// main; the emulated clock's tests).
void RegisterEmulatedLink();

}  // namespace enavi::emulation
