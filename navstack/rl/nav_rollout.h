#pragma once
// Rollouts of the learned navigation policy (docs/rl.md, "Collecting navigation rollouts"): what a
// collection job of method `learned` records per decision, as the navigation environment gives it
// (workers/sim/nav_stepper.h), and its compact binary form shipped over DDS and stored.
//
// Binary form (little-endian): "ENV1", u32 width, u32 height, u32 steps (the same offsets as the
// frequency rollout's "ENR1" header, so the store reads the step count of either), f64
// max_depth_m, u32 + id bytes, u32 info count + (u32 + key, f64) each; then the steps as one zlib
// stream of, per step: depth (width x height u16, the observation's depth x 65535 rounded: within
// 7.7e-6 of what the policy saw, 0.15 mm at 10 m), state (8 f64), action (4 f64, as drawn, before
// the method's clip), f64 log_prob, f64 reward, u8 done. Depth images compress: 64x48 steps take
// about 2-3 kB instead of 6.6 kB (measured in nav_rollout_test).

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "navstack/rl/nav_policy.h"

namespace enavi::navstack::rl {

/// One decision of the policy and its consequence.
struct NavRolloutStep {
  std::vector<std::uint16_t> depth;  ///< height x width, row-major: depth / max_depth_m x 65535
  Eigen::Matrix<double, kNavStateSize, 1> state = Eigen::Matrix<double, kNavStateSize, 1>::Zero();
  Eigen::Matrix<double, kNavActionSize, 1> action = Eigen::Matrix<double, kNavActionSize, 1>::Zero();
  double log_prob = 0;  ///< of `action` under the policy's Gaussian when sampled; 0 when greedy
  double reward = 0;    ///< received after the action
  bool done = false;    ///< a true terminal after this step (goal, collision, out of bounds)
};

/// One episode's decisions (the last one not done: truncated by a time-out).
struct NavRollout {
  int width = 0, height = 0;
  double max_depth_m = 10;
  std::vector<NavRolloutStep> steps;
  std::string id;
  std::map<std::string, double> info;  ///< episode metrics (success, collided, flight time, ...)

  double Return() const;  ///< undiscounted sum of rewards
};

/// The depth of an observation (in [0, 1]) as stored, and back.
std::vector<std::uint16_t> QuantizeDepth(const std::vector<float>& depth);
float DepthValue(std::uint16_t stored);

/// True when `bytes` starts as a nav rollout ("ENV1").
bool IsNavRolloutBlob(std::string_view bytes);
/// @throws std::logic_error for steps of the wrong size.
std::string EncodeNavRollout(const NavRollout& rollout);
/// @throws std::invalid_argument naming `source` and the field on a truncated, corrupt,
///   oversized or non-finite blob.
NavRollout DecodeNavRollout(std::string_view bytes, const std::string& source);

/// Checks a stored or shipped rollout of either form (ENR1, rollout.h; ENV1) by decoding it;
/// returns its step count. @throws std::invalid_argument as the decoders.
std::size_t CheckRolloutBlob(std::string_view bytes, const std::string& source);

}  // namespace enavi::navstack::rl
