#include "navstack/rl/nav_policy.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "api/atomic_file.h"
#include "navstack/rl/json_read.h"
#include "navstack/rl/random.h"
#include "navstack/rl/weight_block.h"

namespace enavi::navstack::rl {
namespace {

using detail::JsonReader;
using nlohmann::json;
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Output size of a valid-padding convolution.
int ConvOut(int in, const ConvLayer& c) { return in < c.kernel ? 0 : (in - c.kernel) / c.stride + 1; }

}  // namespace

NavPolicyNet::NavPolicyNet(int width, int height, double max_depth_m, std::vector<ConvLayer> conv,
                           std::vector<int> hidden, std::array<double, kNavActionSize> action_scale)
    : width_(width), height_(height), max_depth_m_(max_depth_m), conv_(std::move(conv)), hidden_(std::move(hidden)),
      action_scale_(action_scale) {
  if (width_ < 8 || width_ > 640 || height_ < 8 || height_ > 480)
    throw std::invalid_argument("input: width and height must be within 8x8 and 640x480");
  if (!(max_depth_m_ > 0)) throw std::invalid_argument("input.max_depth_m: must be > 0");
  for (double s : action_scale_)
    if (!(s > 0)) throw std::invalid_argument("action_scale: every scale must be > 0");
  shapes_ = {{1, height_, width_}};
  for (std::size_t l = 0; l < conv_.size(); ++l) {
    const ConvLayer& c = conv_[l];
    if (c.out < 1 || c.kernel < 1 || c.stride < 1)
      throw std::invalid_argument("conv[" + std::to_string(l) + "]: out, kernel and stride must be >= 1");
    const auto [ci, hi, wi] = shapes_.back();
    const int ho = ConvOut(hi, c), wo = ConvOut(wi, c);
    if (ho < 1 || wo < 1)
      throw std::invalid_argument("conv[" + std::to_string(l) + "]: its output would be empty on a " +
                                  std::to_string(wi) + "x" + std::to_string(hi) + " input");
    shapes_.push_back({c.out, ho, wo});
    layers_.push_back({static_cast<Eigen::Index>(c.out) * ci * c.kernel * c.kernel + c.out, ci * c.kernel * c.kernel});
    macs_ += static_cast<std::int64_t>(c.out) * ho * wo * ci * c.kernel * c.kernel;
  }
  const auto [cl, hl, wl] = shapes_.back();
  int in = cl * hl * wl + kNavStateSize;
  std::vector<int> sizes = hidden_;
  sizes.push_back(kNavActionSize);
  for (std::size_t l = 0; l < sizes.size(); ++l) {
    if (sizes[l] < 1) throw std::invalid_argument("hidden[" + std::to_string(l) + "]: must be >= 1");
    layers_.push_back({static_cast<Eigen::Index>(sizes[l]) * in + sizes[l], in});
    macs_ += static_cast<std::int64_t>(sizes[l]) * in;
    in = sizes[l];
  }
  Eigen::Index count = 0;
  for (const auto& [n, fan_in] : layers_) count += n;
  params_ = Eigen::VectorXd::Zero(count);
}

Eigen::Matrix<double, kNavActionSize, 1> NavPolicyNet::Forward(const NavObservation& obs) const {
  if (static_cast<int>(obs.depth.size()) != width_ * height_)
    throw std::invalid_argument("nav policy: the observation's image is not " + std::to_string(width_) + "x" +
                                std::to_string(height_));
  // Activations as channels x (height * width), row-major: PyTorch's NCHW for one sample.
  RowMatrix x = Eigen::Map<const Eigen::Matrix<float, 1, Eigen::Dynamic>>(obs.depth.data(), width_ * height_).cast<double>();
  Eigen::Index at = 0;
  for (std::size_t l = 0; l < conv_.size(); ++l) {
    const ConvLayer& c = conv_[l];
    const auto [ci, hi, wi] = shapes_[l];
    const auto [co, ho, wo] = shapes_[l + 1];
    const int patch = ci * c.kernel * c.kernel;
    // im2col: one column per output pixel, rows in the weights' (in, ky, kx) order.
    RowMatrix cols(patch, static_cast<Eigen::Index>(ho) * wo);
    for (int ch = 0; ch < ci; ++ch)
      for (int ky = 0; ky < c.kernel; ++ky)
        for (int kx = 0; kx < c.kernel; ++kx) {
          const int row = (ch * c.kernel + ky) * c.kernel + kx;
          for (int oy = 0; oy < ho; ++oy)
            for (int ox = 0; ox < wo; ++ox)
              cols(row, oy * wo + ox) = x(ch, (oy * c.stride + ky) * wi + ox * c.stride + kx);
        }
    const Eigen::Map<const RowMatrix> W(params_.data() + at, co, patch);
    at += static_cast<Eigen::Index>(co) * patch;
    const Eigen::Map<const Eigen::VectorXd> b(params_.data() + at, co);
    at += co;
    x = ((W * cols).colwise() + b).cwiseMax(0.0);
  }
  Eigen::VectorXd h(x.size() + kNavStateSize);
  h << Eigen::Map<const Eigen::VectorXd>(x.data(), x.size()), obs.state;
  std::vector<int> sizes = hidden_;
  sizes.push_back(kNavActionSize);
  for (std::size_t l = 0; l < sizes.size(); ++l) {
    const Eigen::Map<const RowMatrix> W(params_.data() + at, sizes[l], h.size());
    at += W.size();
    const Eigen::Map<const Eigen::VectorXd> b(params_.data() + at, sizes[l]);
    at += sizes[l];
    h = ((W * h) + b).array().tanh().matrix();
  }
  return h;
}

void NavPolicyNet::set_log_std(const std::array<double, kNavActionSize>& log_std) {
  for (const double v : log_std)
    if (!(v >= kMinLogStd && v <= kMaxLogStd))
      throw std::invalid_argument("must be finite and in [" + std::to_string(kMinLogStd) + ", " +
                                  std::to_string(kMaxLogStd) + "]");
  log_std_ = log_std;
}

SampledNavAction SampleNavAction(const NavPolicyNet& net, const NavObservation& obs, Rng* rng) {
  if (!net.log_std())
    throw std::invalid_argument("nav policy: sampling needs the policy's log_std (examples/torch_nav_ppo.py writes it)");
  SampledNavAction s;
  s.action = net.Forward(obs);
  constexpr double kHalfLog2Pi = 0.91893853320467274178;
  for (int i = 0; i < kNavActionSize; ++i) {
    const double log_std = (*net.log_std())[static_cast<std::size_t>(i)];
    const double z = rng->Normal();
    s.action[i] += std::exp(log_std) * z;
    s.log_prob += -0.5 * z * z - log_std - kHalfLog2Pi;
  }
  return s;
}

std::uint64_t NavExploreSeed(std::uint64_t episode_seed) { return DeriveSeed(episode_seed, 0x6e6176 /* "nav" */); }

NavPolicyNet DefaultNavArchitecture(int width, int height) {
  return NavPolicyNet(width, height, 10.0, {{8, 5, 2}, {16, 3, 2}, {16, 3, 2}}, {64}, {2.0, 2.0, 1.0, 1.0});
}

NavPolicyNet MakeNavPolicy(int width, int height, std::uint64_t seed) {
  NavPolicyNet net = DefaultNavArchitecture(width, height);
  Rng rng(seed);
  Eigen::Index at = 0;
  for (const auto& [count, fan_in] : net.layer_sizes())
    for (Eigen::Index i = 0; i < count; ++i) net.params()[at++] = (2 * rng.Uniform01() - 1) / std::sqrt(double(fan_in));
  return net;
}

NavObservation MakeNavObservation(const DepthImage& image, const VehicleState& state, const Eigen::Vector3d& goal_W,
                                  int width, int height, double max_depth_m,
                                  const std::array<double, kNavActionSize>& action_scale) {
  if (image.width % width != 0 || image.height % height != 0 || image.width / width != image.height / height)
    throw std::invalid_argument("nav policy: a " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                " depth image does not reduce to the network's " + std::to_string(width) + "x" +
                                std::to_string(height) + " by whole blocks");
  const int n = image.width / width;
  NavObservation obs;
  obs.depth.assign(static_cast<std::size_t>(width) * height, 1.0f);
  const float range = static_cast<float>(max_depth_m);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      float nearest = range;
      for (int dv = 0; dv < n; ++dv)
        for (int du = 0; du < n; ++du) {
          const float d = image.at(u * n + du, v * n + dv);
          if (DepthImage::Valid(d)) nearest = std::min(nearest, d);
        }
      obs.depth[static_cast<std::size_t>(v) * width + u] = nearest / range;
    }
  // The yaw frame: heading only, so that the state does not tilt with the attitude.
  const Eigen::Vector3d x_W = state.q_WB * Eigen::Vector3d::UnitX();
  const double yaw = std::atan2(x_W.y(), x_W.x());
  const Eigen::Matrix3d R_YW = Eigen::AngleAxisd(-yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d g = R_YW * (goal_W - state.p_WB);
  const double d = g.norm();
  obs.state.segment<3>(0) = g / std::max(d, 1.0);
  obs.state[3] = std::min(d / 20.0, 1.0);
  obs.state.segment<3>(4) = R_YW * state.v_WB / action_scale[0];
  obs.state[7] = (state.q_WB * state.w_WB_B).z() / action_scale[3];
  return obs;
}

json NavPolicyToJson(const NavPolicyNet& net, const json& metadata) {
  json conv = json::array();
  for (const ConvLayer& c : net.conv()) conv.push_back({{"out", c.out}, {"kernel", c.kernel}, {"stride", c.stride}});
  const Eigen::VectorXd& p = net.params();
  json j = {{"format", kNavPolicyFormat},
          {"version", kNavPolicyVersion},
          {"input", {{"width", net.width()}, {"height", net.height()}, {"max_depth_m", net.max_depth_m()}}},
          {"conv", conv},
          {"hidden", net.hidden()},
          {"action_scale", net.action_scale()},
          {"parameters", detail::EncodeWeights(std::vector<double>(p.data(), p.data() + p.size()), WeightPrecision::kFloat32,
                                               kNavPolicyParameterLayout,
                                               [](std::size_t i) { return "parameters[" + std::to_string(i) + "]"; })},
          {"metadata", metadata}};
  if (net.log_std()) j["log_std"] = *net.log_std();
  return j;
}

NavPolicyNet NavPolicyFromJson(const json& j, const std::string& source) {
  const JsonReader r(source);
  r.Object(j, "");
  const std::string format = r.String(r.Field(j, "", "format"), "format");
  if (format != kNavPolicyFormat) r.Fail("format", "expected \"" + std::string(kNavPolicyFormat) + "\", got \"" + format + "\"");
  const std::int64_t version = r.Integer(r.Field(j, "", "version"), "version");
  if (version != kNavPolicyVersion) r.Fail("version", "expected " + std::to_string(kNavPolicyVersion) + ", got " + std::to_string(version));
  const json& input = r.Object(r.Field(j, "", "input"), "input");
  const auto small_int = [&](const json& v, const std::string& field) {
    const std::int64_t n = r.Integer(v, field);
    if (n < 0 || n > 100000) r.Fail(field, "out of range");
    return static_cast<int>(n);
  };
  std::vector<ConvLayer> conv;
  const json& cj = r.Array(r.Field(j, "", "conv"), "conv");
  for (std::size_t l = 0; l < cj.size(); ++l) {
    const std::string f = JsonReader::Index("conv", l);
    conv.push_back({small_int(r.Field(cj[l], f, "out"), f + ".out"), small_int(r.Field(cj[l], f, "kernel"), f + ".kernel"),
                    small_int(r.Field(cj[l], f, "stride"), f + ".stride")});
  }
  std::vector<int> hidden;
  const json& hj = r.Array(r.Field(j, "", "hidden"), "hidden");
  for (std::size_t l = 0; l < hj.size(); ++l) hidden.push_back(small_int(hj[l], JsonReader::Index("hidden", l)));
  const std::vector<double> scale = r.Numbers(r.Field(j, "", "action_scale"), "action_scale", kNavActionSize);
  std::array<double, kNavActionSize> action_scale{};
  std::copy(scale.begin(), scale.end(), action_scale.begin());
  NavPolicyNet net;
  try {
    net = NavPolicyNet(small_int(r.Field(input, "input", "width"), "input.width"),
                       small_int(r.Field(input, "input", "height"), "input.height"),
                       r.Number(r.Field(input, "input", "max_depth_m"), "input.max_depth_m"), conv, hidden, action_scale);
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    const std::size_t colon = what.find(": ");
    r.Fail(what.substr(0, colon), what.substr(colon + 2));
  }
  const std::vector<double> w =
      detail::DecodeWeights(r.Field(j, "", "parameters"), r, "parameters", static_cast<std::size_t>(net.params().size()),
                            kNavPolicyParameterLayout, [](std::size_t i) { return "parameters[" + std::to_string(i) + "]"; });
  net.params() = Eigen::Map<const Eigen::VectorXd>(w.data(), static_cast<Eigen::Index>(w.size()));
  if (j.contains("log_std")) {
    const std::vector<double> v = r.Numbers(j["log_std"], "log_std", kNavActionSize);
    std::array<double, kNavActionSize> log_std{};
    std::copy(v.begin(), v.end(), log_std.begin());
    try {
      net.set_log_std(log_std);
    } catch (const std::invalid_argument& e) {
      r.Fail("log_std", e.what());
    }
  }
  r.Object(r.Field(j, "", "metadata"), "metadata");
  return net;
}

NavPolicyNet LoadNavPolicy(const std::string& path) {
  return NavPolicyFromJson(detail::ReadJsonFile(path, "nav policy file"), "nav policy file '" + path + "'");
}

bool IsNavPolicyFile(const std::string& path) {
  try {
    const json j = detail::ReadJsonFile(path, "policy file");
    return j.is_object() && j.value("format", std::string()) == kNavPolicyFormat;
  } catch (const std::exception&) {
    return false;
  }
}

bool IsNavPolicyText(const std::string& text) {
  const json j = json::parse(text, nullptr, false);
  return j.is_object() && j.value("format", std::string()) == kNavPolicyFormat;
}

std::string CanonicalNavPolicyText(const std::string& text, const std::string& source) {
  const json j = detail::ParseJson(text, source);
  const NavPolicyNet net = NavPolicyFromJson(j, source);
  return NavPolicyToJson(net, j.at("metadata")).dump();
}

void SaveNavPolicy(const std::string& path, const NavPolicyNet& net, const json& metadata) {
  api::WriteFileAtomic(path, NavPolicyToJson(net, metadata).dump() + "\n");
}

}  // namespace enavi::navstack::rl
