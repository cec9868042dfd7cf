#pragma once
// What measures an episode: each metric, the time series and the progress report is a monitor,
// a small piece of the episode's state that sees every frame, every batch of the stack's events
// and every step, and writes its part of the result at the end. A new metric or series column
// is a monitor (or a change inside one, episode_monitors.h), not an edit of the step.

#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "api/episode.h"
#include "navstack/common/camera.h"
#include "navstack/common/state.h"
#include "navstack/eci/eci.h"
#include "navstack/methods/navigator.h"
#include "workers/sim/nav_link.h"

namespace enavi::sim {

/// A depth frame as the episode rendered it, with the eci computed for the metrics.
struct FrameView {
  const navstack::DepthFrame& frame;
  const navstack::EciResult& eci;
  const navstack::VehicleState& vehicle;  ///< at the frame's capture
};

/// One physics step at sim time t, after the stack ran up to t and the controller acted.
struct StepView {
  long k = 0;  ///< physics steps before this one
  double t = 0;
  const navstack::VehicleState& vehicle;  ///< at t
  const Eigen::Vector3d& p_ref;           ///< the reference position the controller tracks
  const NavLink& link;
  /// The odometry the stack was given, when it is not the truth (spec.odometry_noise).
  const navstack::VehicleState* estimate = nullptr;
  /// The air at the vehicle during the last step, when the episode flies in wind (spec.wind).
  const Eigen::Vector3d* air_W = nullptr;
};

/// What the episode came to, for the monitors' results.
struct EpisodeTotals {
  double T = 0;  ///< s, flight time (sim time at the end)
  const NavAccounting& accounting;  ///< the stack's, final
};

class EpisodeMonitor {
 public:
  virtual ~EpisodeMonitor() = default;
  /// A new frame; `board_s` is what computing its eci costs on the board.
  virtual void OnFrame(const FrameView& /*frame*/, double /*board_s*/) {}
  /// The events the stack reported during the step.
  virtual void OnEvents(std::span<const navstack::NavEvent> /*events*/) {}
  virtual void OnStep(const StepView& /*step*/) {}
  /// Writes its part of the result.
  virtual void Write(const EpisodeTotals& /*totals*/, api::EpisodeResult* /*result*/) const {}
};

}  // namespace enavi::sim
