#pragma once
// Learned navigation as a step-by-step environment (docs/rl.md, "Learned navigation"): each step
// is one inference of the `learned` method (navstack/methods/learned/) in a real virtual-clock
// flight: the observation is the depth frame at the network's size and the vehicle's state with
// the goal (navstack/rl/nav_policy.h), the action a velocity setpoint with yaw rate. The inference
// runs on the board: the job waits in a DecisionPort at the instant the board's scheduler starts
// it, and the action supplied takes effect when the board would have finished it (with
// zero_latency, at once and for free).
//
// Reward of a step (from the vehicle's true position at the two decisions):
//   progress: the decrease of the distance to the goal, m
//   smoothness: -kSmoothnessWeight x |a - a_prev|^2 (actions in [-1, 1])
//   at the end: +kGoalReward at the goal, -kCrashPenalty on a collision or on leaving the flight
//   bounds (the episode ends: terminated); a time-out truncates.

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "navstack/rl/decision_port.h"
#include "navstack/rl/nav_policy.h"
#include "workers/sim/episode.h"

namespace enavi::python {

inline constexpr double kGoalReward = 10.0;
inline constexpr double kCrashPenalty = 10.0;
inline constexpr double kSmoothnessWeight = 0.01;

struct NavEnvConfig {
  std::string world = "forest";  ///< any world the CLI accepts (a scenario id or a file)
  std::string board = "pi4b";
  int decimation = 10;           ///< of the 640x480 sensor: 10 -> 64x48, 4 -> 160x120, 2 -> 320x240
  bool zero_latency = false;     ///< no board in the loop (the ablation)
  /// Multiply-adds of the policy's network per inference, priced on the board; 0: the default
  /// architecture's at this image size (rl::DefaultNavArchitecture).
  std::int64_t multiply_adds = 0;
  double timeout_s = 0;          ///< 0: derived from the start-goal distance
  std::map<std::string, std::string> world_params;
  std::map<std::string, double> overrides;
};

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

class NavEnvCore {
 public:
  /// @throws std::invalid_argument for an unknown board, a bad decimation, or learned.* overrides.
  explicit NavEnvCore(NavEnvConfig config);
  ~NavEnvCore();
  NavEnvCore(const NavEnvCore&) = delete;
  NavEnvCore& operator=(const NavEnvCore&) = delete;

  /// Starts an episode (world and episode seed `seed`); returns its first observation.
  NavTransition Reset(std::uint64_t seed);
  /// Takes `action` (4 values; clipped to [-1, 1] by the method); returns the next observation or
  /// the end. @throws std::invalid_argument for a wrong size or a non-finite value,
  ///   std::logic_error without reset().
  NavTransition Step(const Eigen::VectorXd& action);

  int width() const { return width_; }
  int height() const { return height_; }
  std::int64_t multiply_adds() const { return multiply_adds_; }

 private:
  NavTransition Advance();

  NavEnvConfig config_;
  int width_ = 0, height_ = 0;
  std::int64_t multiply_adds_ = 0;
  std::shared_ptr<const sim::PreparedWorld> world_;
  std::unique_ptr<navstack::rl::DecisionPort> decisions_;
  std::unique_ptr<sim::Episode> episode_;
  double last_distance_ = 0;
  Eigen::VectorXd last_action_;
  NavTransition last_;
  bool finished_ = true;
};

}  // namespace enavi::python
