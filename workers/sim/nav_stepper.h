#pragma once
// Learned navigation decision by decision (docs/rl.md, "Learned navigation"): a virtual-clock
// flight of the `learned` method (navstack/methods/learned/) stopped at each inference, when the
// board's scheduler starts it. The observation is the depth frame at the network's size and the
// vehicle's state with the goal (navstack/rl/nav_policy.h); the action supplied takes effect when
// the board would have finished the inference (with learned.zero_latency, at once and for free).
// The Python environment (enavi.make_nav) and the farm's collection jobs of `learned` both step
// flights through this, so their rewards and observations are the same.
//
// Reward of a step (from the vehicle's true position at the two decisions):
//   progress: the decrease of the distance to the goal, m
//   smoothness: -kSmoothnessWeight x |a - a_prev|^2 (actions clipped to [-1, 1])
//   at the end: +kGoalReward at the goal, -kCrashPenalty on a collision or on leaving the flight
//   bounds (the episode ends: terminated); a time-out truncates.

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "api/episode.h"
#include "navstack/rl/decision_port.h"
#include "navstack/rl/nav_policy.h"
#include "workers/sim/episode.h"

namespace enavi::sim {

inline constexpr double kGoalReward = 10.0;
inline constexpr double kCrashPenalty = 10.0;
inline constexpr double kSmoothnessWeight = 0.01;

struct NavTransition {
  std::vector<float> depth;  ///< height x width, row-major, in [0, 1]
  Eigen::Matrix<double, navstack::rl::kNavStateSize, 1> state;
  double reward = 0;
  bool terminated = false;  ///< goal, collision or out of bounds
  bool truncated = false;   ///< time-out (or another end of the episode's)
  std::map<std::string, double> metrics;  ///< at the end: success, collided, flight_time_s, ...
  std::string end_reason;
  double t = 0;             ///< sim time of the observation, s
};

class NavStepper {
 public:
  /// Starts the flight of `spec` (method learned, virtual clock, its camera.decimation and
  /// learned.* overrides set by the caller) in `world`, which must outlive it, with `options`
  /// (their decision port is the stepper's). @throws as Episode's constructor.
  NavStepper(const api::EpisodeSpec& spec, const PreparedWorld& world, EpisodeOptions options = {});
  ~NavStepper();
  NavStepper(const NavStepper&) = delete;
  NavStepper& operator=(const NavStepper&) = delete;

  /// The first observation. @throws std::runtime_error when the flight ends before it.
  NavTransition First();
  /// Supplies `action` (4 values, clipped to [-1, 1] by the method); the next observation or the
  /// end. @throws std::invalid_argument for a wrong size or a non-finite value,
  ///   std::logic_error after the end.
  NavTransition Step(const Eigen::VectorXd& action);
  bool finished() const { return finished_; }
  /// The flight's result (leaving the bounds ends it as "left_bounds"). @pre finished().
  const api::EpisodeResult& result() const { return *result_; }

 private:
  NavTransition Advance();

  const PreparedWorld& world_;
  // The episode goes first (members go in reverse order), before the port it writes to.
  std::unique_ptr<navstack::rl::DecisionPort> decisions_;
  std::unique_ptr<Episode> episode_;
  double last_distance_ = 0;
  Eigen::VectorXd last_action_;
  NavTransition last_;
  bool started_ = false, finished_ = false;
  std::optional<api::EpisodeResult> result_;
};

}  // namespace enavi::sim
