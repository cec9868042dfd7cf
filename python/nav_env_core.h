#pragma once
// Learned navigation as a step-by-step environment (docs/rl.md, "Learned navigation"): each step
// is one inference of the `learned` method in a real virtual-clock flight, stepped by
// sim::NavStepper (its header documents the observation, the board's latency and the rewards).

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "navstack/rl/nav_policy.h"
#include "workers/sim/nav_stepper.h"

namespace enavi::python {

using sim::NavTransition;

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
  NavEnvConfig config_;
  int width_ = 0, height_ = 0;
  std::int64_t multiply_adds_ = 0;
  std::shared_ptr<const sim::PreparedWorld> world_;
  std::unique_ptr<sim::NavStepper> stepper_;  ///< before world_ goes (members go in reverse order)
};

}  // namespace enavi::python
