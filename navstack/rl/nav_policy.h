#pragma once
// A learned navigation policy (docs/rl.md, "Learned navigation"): a depth image and the vehicle's
// state in, a velocity setpoint with yaw rate out. A small CNN (convolutions with ReLU, then
// tanh hidden layers over the image features and the state, a tanh output) whose layout is
// PyTorch's, so that a network trained in PyTorch (examples/torch_nav_ppo.py) flies here
// unchanged. Its observation is built here too, once, for the flight and the Python environment.
//
// Policy file: versioned minified JSON, the weights as one base64 block of float32 (as
// policy_io.h's frequency policies, for the same reasons):
//
//   {"format": "enavi-nav-policy", "version": 1,
//    "input": {"width": 64, "height": 48, "max_depth_m": 10},
//    "conv": [{"out": 8, "kernel": 5, "stride": 2}, ...],   (valid padding, ReLU after each)
//    "hidden": [64],                                         (tanh)
//    "action_scale": [2, 2, 1, 1],                           (m/s, m/s, m/s, rad/s at output 1)
//    "log_std": [-0.5, -0.5, -0.5, -0.5],   (optional: the Gaussian around the output that PPO
//                                            samples from; sampling collection jobs need it)
//    "parameters": {"dtype": "float32", "byte_order": "little", "encoding": "base64",
//                   "layout": kNavPolicyParameterLayout, "count": n, "sha256": "...", "data": "..."},
//    "metadata": {...}}

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "navstack/common/camera.h"
#include "navstack/common/state.h"

namespace enavi::navstack::rl {

inline constexpr const char* kNavPolicyFormat = "enavi-nav-policy";
inline constexpr int kNavPolicyVersion = 1;
inline constexpr const char* kNavPolicyParameterLayout =
    "per convolution the weights (out x in x kernel x kernel) then the bias, then per linear layer "
    "the weights (out x in, row-major) then the bias: PyTorch's Conv2d and Linear";

/// The state part of the observation, in order (all in the vehicle's yaw frame: x forward, y left,
/// z up): the goal's direction scaled by min(1, distance) (3), the distance to the goal / 20 m
/// capped at 1 (1), the velocity / action_scale[0] (3), the yaw rate / action_scale[3] (1).
inline constexpr int kNavStateSize = 8;
/// The action: forward, left and up velocity and yaw rate, each in [-1, 1] times action_scale.
inline constexpr int kNavActionSize = 4;

/// Bounds of a policy's log_std (a std of 2e-9 to 7.4 in action units of [-1, 1]).
inline constexpr double kMinLogStd = -20.0;
inline constexpr double kMaxLogStd = 2.0;

class Rng;

struct ConvLayer {
  int out = 0, kernel = 0, stride = 1;
};

/// What the network sees at one instant.
struct NavObservation {
  /// Depth / max_depth_m in [0, 1], row-major height x width; no return (too near, too far, sky)
  /// reads 1.
  std::vector<float> depth;
  Eigen::Matrix<double, kNavStateSize, 1> state = Eigen::Matrix<double, kNavStateSize, 1>::Zero();
};

class NavPolicyNet {
 public:
  NavPolicyNet() = default;
  /// @throws std::invalid_argument when the layers do not fit the image (a convolution's output
  ///   would be empty) or a size is out of range.
  NavPolicyNet(int width, int height, double max_depth_m, std::vector<ConvLayer> conv, std::vector<int> hidden,
               std::array<double, kNavActionSize> action_scale);

  int width() const { return width_; }
  int height() const { return height_; }
  double max_depth_m() const { return max_depth_m_; }
  const std::vector<ConvLayer>& conv() const { return conv_; }
  const std::vector<int>& hidden() const { return hidden_; }
  const std::array<double, kNavActionSize>& action_scale() const { return action_scale_; }
  /// Log standard deviation of the exploration Gaussian per action (PPO's), if the file has one.
  const std::optional<std::array<double, kNavActionSize>>& log_std() const { return log_std_; }
  /// @throws std::invalid_argument for a value outside [kMinLogStd, kMaxLogStd] or not finite.
  void set_log_std(const std::array<double, kNavActionSize>& log_std);
  /// Flat parameters in kNavPolicyParameterLayout's order.
  Eigen::VectorXd& params() { return params_; }
  const Eigen::VectorXd& params() const { return params_; }
  /// Per layer (convolutions, then linear layers): its weights and biases, and its fan-in.
  const std::vector<std::pair<Eigen::Index, int>>& layer_sizes() const { return layers_; }
  /// Multiply-adds of one forward pass (what the board is charged for, as policy_flop).
  std::int64_t multiply_adds() const { return macs_; }

  /// The action in [-1, 1] (before action_scale). @pre obs.depth has width x height values.
  Eigen::Matrix<double, kNavActionSize, 1> Forward(const NavObservation& obs) const;

 private:
  int width_ = 0, height_ = 0;
  double max_depth_m_ = 10;
  std::vector<ConvLayer> conv_;
  std::vector<int> hidden_;
  std::array<double, kNavActionSize> action_scale_{};
  std::optional<std::array<double, kNavActionSize>> log_std_;
  std::vector<std::array<int, 3>> shapes_;  ///< channels, height, width after each convolution (input first)
  std::vector<std::pair<Eigen::Index, int>> layers_;
  Eigen::VectorXd params_;
  std::int64_t macs_ = 0;
};

/// The architecture examples/torch_nav_ppo.py trains (three convolutions 8x5/2, 16x3/2, 16x3/2,
/// one hidden layer of 64, speeds up to 2 m/s, yaw rate up to 1 rad/s) on a width x height image,
/// weights zero (its sizes and multiply-adds are what it is for).
NavPolicyNet DefaultNavArchitecture(int width, int height);
/// DefaultNavArchitecture with its weights drawn as PyTorch's defaults draw them (uniform within
/// 1/sqrt(fan-in)) from `seed`: an untrained network for tests and calibration flights (their
/// work does not depend on it).
NavPolicyNet MakeNavPolicy(int width, int height, std::uint64_t seed);

/// The observation of a frame at the state `state` with the goal at `goal_W`, for `net`'s input:
/// the image is reduced to the network's size by the minimum over each block (the nearest
/// obstacle survives the reduction). @throws std::invalid_argument when the frame's size is not a
/// whole multiple of the network's.
NavObservation MakeNavObservation(const DepthImage& image, const VehicleState& state, const Eigen::Vector3d& goal_W,
                                  int width, int height, double max_depth_m,
                                  const std::array<double, kNavActionSize>& action_scale);

/// An action drawn from the policy's Gaussian, N(Forward(obs), exp(log_std)^2) per component
/// (as examples/torch_nav_ppo.py samples it), and its log-density; the method clips it to [-1, 1]
/// when it lands. @throws std::invalid_argument when the policy has no log_std.
struct SampledNavAction {
  Eigen::Matrix<double, kNavActionSize, 1> action;
  double log_prob = 0;
};
SampledNavAction SampleNavAction(const NavPolicyNet& net, const NavObservation& obs, Rng* rng);
/// The seed of an episode's exploration draws (the `learned` method's and a collection's alike).
std::uint64_t NavExploreSeed(std::uint64_t episode_seed);

nlohmann::json NavPolicyToJson(const NavPolicyNet& net, const nlohmann::json& metadata = nlohmann::json::object());
/// @throws std::invalid_argument "<source>: <field>: <reason>".
NavPolicyNet NavPolicyFromJson(const nlohmann::json& j, const std::string& source);
/// @throws std::invalid_argument naming the file (and field) when it is missing, not JSON, or bad.
NavPolicyNet LoadNavPolicy(const std::string& path);
/// Whether the file at `path` says it is a nav policy (its "format"); false for anything else,
/// also an unreadable file (whose loader then names the problem).
bool IsNavPolicyFile(const std::string& path);
/// Whether `text` is a JSON object that says it is a nav policy (its "format").
bool IsNavPolicyText(const std::string& text);
/// The nav policy in `text`, validated and written as SaveNavPolicy writes it (its metadata kept):
/// the form its content hash is taken of. @throws std::invalid_argument as NavPolicyFromJson.
std::string CanonicalNavPolicyText(const std::string& text, const std::string& source);
/// Writes the file atomically. @throws std::runtime_error on I/O failure.
void SaveNavPolicy(const std::string& path, const NavPolicyNet& net,
                   const nlohmann::json& metadata = nlohmann::json::object());

}  // namespace enavi::navstack::rl
