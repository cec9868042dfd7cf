// The learned navigation policy's network, observation and file (navstack/rl/nav_policy.h).
#include "navstack/rl/nav_policy.h"

#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "navstack/rl/random.h"

namespace enavi::navstack::rl {
namespace {

// A file in the test's temporary directory.
std::string TempFile(const std::string& name) {
  return (std::filesystem::path(::testing::TempDir()) / name).string();
}

NavObservation RampObservation(int width, int height) {
  NavObservation obs;
  for (int i = 0; i < width * height; ++i) obs.depth.push_back(static_cast<float>((i % 97) / 97.0));
  obs.state << 1, 0, 0, 0.5, 0.2, -0.1, 0, 0.3;
  return obs;
}

TEST(NavPolicyTest, CountsTheMultiplyAddsOfEveryLayer) {
  const NavPolicyNet net = MakeNavPolicy(64, 48, 1);
  // 64x48 -> 8 x 22x30 (5x5/2) -> 16 x 10x14 (3x3/2) -> 16 x 4x6 (3x3/2) -> 384 + 8 -> 64 -> 4.
  const std::int64_t conv = 8LL * 22 * 30 * 1 * 25 + 16LL * 10 * 14 * 8 * 9 + 16LL * 4 * 6 * 16 * 9;
  EXPECT_EQ(net.multiply_adds(), conv + 392LL * 64 + 64LL * 4);
  EXPECT_EQ(net.params().size(), (8 * 25 + 8) + (16 * 72 + 16) + (16 * 144 + 16) + (392 * 64 + 64) + (64 * 4 + 4));
}

TEST(NavPolicyTest, ComputesAConvolutionAsPyTorchLaysItOut) {
  // One 2x2/2 filter on a 8x8 ramp, no hidden layer: the output is tanh(w . features + b).
  NavPolicyNet net(8, 8, 10.0, {{1, 2, 2}}, {}, {1, 1, 1, 1});
  // Filter weights (1, 1, 2, 2) = {1, 0, 0, 0}: each output picks its block's top-left pixel.
  net.params()[0] = 1;
  NavObservation obs;
  for (int i = 0; i < 64; ++i) obs.depth.push_back(static_cast<float>(i) / 64.0f);
  // Linear layer 4 x (16 + 8): output k reads feature k (of 16) only.
  const int in = 16 + kNavStateSize;
  for (int k = 0; k < 4; ++k) net.params()[5 + k * in + k] = 1.0;
  const auto a = net.Forward(obs);
  // Features: pixel (2 oy, 2 ox) of the ramp, row-major over the 4x4 output.
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(a[k], std::tanh((2 * k) / 64.0), 1e-7) << k;
}

TEST(NavPolicyTest, AFileRoundTripsAndFliesTheSameNetwork) {
  const std::string path = TempFile("roundtrip-nav.json");
  const NavPolicyNet net = MakeNavPolicy(80, 60, 7);
  SaveNavPolicy(path, net, {{"note", "test"}});
  const NavPolicyNet back = LoadNavPolicy(path);
  EXPECT_EQ(back.width(), 80);
  EXPECT_EQ(back.multiply_adds(), net.multiply_adds());
  const NavObservation obs = RampObservation(80, 60);
  // float32 weights on disk: the same network to float precision.
  EXPECT_LT((back.Forward(obs) - net.Forward(obs)).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_EQ(back.Forward(obs), LoadNavPolicy(path).Forward(obs)) << "a file flies the same each time";
}

TEST(NavPolicyTest, ABadFileNamesItsFieldAndReason) {
  const std::string path = TempFile("bad-nav.json");
  nlohmann::json j = NavPolicyToJson(MakeNavPolicy(64, 48, 1));
  const auto refused = [&](const nlohmann::json& doc, const std::string& expect) {
    std::ofstream(path) << doc.dump();
    try {
      LoadNavPolicy(path);
      ADD_FAILURE() << "accepted; expected " << expect;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad-nav.json"), std::string::npos) << e.what();
    }
  };
  nlohmann::json bad = j;
  bad["format"] = "enavi-frequency-policy";
  refused(bad, "format: expected \"enavi-nav-policy\"");
  bad = j;
  bad["conv"][0]["kernel"] = 60;
  refused(bad, "conv[0]: its output would be empty");
  bad = j;
  bad["parameters"]["sha256"] = std::string(64, '0');
  refused(bad, "parameters.sha256: does not match");
  bad = j;
  bad["hidden"] = {32};
  refused(bad, "parameters.count: expected");
  bad = j;
  bad["action_scale"] = {1, 1, 1};
  refused(bad, "action_scale");
  bad = j;
  bad["log_std"] = {-0.5, -0.5, 5, -0.5};
  refused(bad, "log_std: must be finite and in [-20");
  bad = j;
  bad["log_std"] = {-0.5};
  refused(bad, "log_std");
  std::ofstream(path) << "{\"format\": ";
  EXPECT_THROW(LoadNavPolicy(path), std::invalid_argument);
}

TEST(NavPolicyTest, SamplesFromItsGaussianWithTheLogDensityOfTheDraw) {
  NavPolicyNet net = MakeNavPolicy(64, 48, 2);
  const NavObservation obs = RampObservation(64, 48);
  Rng rng(NavExploreSeed(5));
  EXPECT_THROW(SampleNavAction(net, obs, &rng), std::invalid_argument) << "no log_std: nothing to sample";
  const std::array<double, kNavActionSize> log_std = {-0.5, -1.0, -2.0, 0.0};
  net.set_log_std(log_std);
  // The file keeps it: a saved and loaded network samples the same draws.
  const std::string path = TempFile("sampled-nav.json");
  SaveNavPolicy(path, net);
  EXPECT_EQ(*LoadNavPolicy(path).log_std(), log_std);

  const Eigen::Vector4d mean = net.Forward(obs);
  Rng a(NavExploreSeed(5)), b(NavExploreSeed(5));
  Eigen::Vector4d sum = Eigen::Vector4d::Zero(), sq = Eigen::Vector4d::Zero();
  constexpr int kDraws = 4000;
  for (int n = 0; n < kDraws; ++n) {
    const SampledNavAction s = SampleNavAction(net, obs, &a);
    EXPECT_EQ(s.action, SampleNavAction(net, obs, &b).action) << "the same seed draws the same";
    // log N(x; mu, sigma) summed over the four components, from the draw itself.
    double log_prob = 0;
    for (int i = 0; i < kNavActionSize; ++i) {
      const double sigma = std::exp(log_std[static_cast<std::size_t>(i)]);
      const double z = (s.action[i] - mean[i]) / sigma;
      log_prob += -0.5 * z * z - std::log(sigma) - 0.5 * std::log(2 * M_PI);
    }
    ASSERT_NEAR(s.log_prob, log_prob, 1e-9);
    sum += s.action - mean;
    sq += (s.action - mean).cwiseAbs2();
  }
  for (int i = 0; i < kNavActionSize; ++i) {
    const double sigma = std::exp(log_std[static_cast<std::size_t>(i)]);
    EXPECT_NEAR(sum[i] / kDraws, 0.0, 4 * sigma / std::sqrt(double(kDraws))) << i;
    EXPECT_NEAR(std::sqrt(sq[i] / kDraws), sigma, 0.05 * sigma) << i;
  }
}

TEST(NavPolicyTest, TheCanonicalTextIsOnePerNetworkAndKeepsTheMetadata) {
  NavPolicyNet net = MakeNavPolicy(64, 48, 4);
  net.set_log_std({-1, -1, -1, -1});
  const std::string canonical = CanonicalNavPolicyText(NavPolicyToJson(net, {{"run", 7}}).dump(2), "a");
  EXPECT_EQ(CanonicalNavPolicyText(canonical, "b"), canonical);
  EXPECT_NE(canonical.find("\"run\":7"), std::string::npos);
  EXPECT_TRUE(IsNavPolicyText(canonical));
  EXPECT_FALSE(IsNavPolicyText("{\"format\": \"enavi-frequency-policy\"}"));
  EXPECT_FALSE(IsNavPolicyText("not json"));
}

TEST(NavPolicyTest, TheObservationKeepsTheNearestReturnOfEachBlockAndTheGoalInTheYawFrame) {
  DepthImage image(8, 6);
  image.at(3, 2) = 2.0f;  // block (1, 1) of the 4x3 reduction
  image.at(2, 2) = 5.0f;
  image.at(7, 5) = 20.0f;  // beyond max_depth: as no return
  VehicleState s;
  s.p_WB = {1, 1, 2};
  s.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));  // facing +y
  s.v_WB = {0, 2, 0};
  const NavObservation o = MakeNavObservation(image, s, {1, 11, 2}, 4, 3, 10.0, {2, 2, 1, 1});
  EXPECT_FLOAT_EQ(o.depth[1 * 4 + 1], 0.2f);
  EXPECT_FLOAT_EQ(o.depth[0], 1.0f);
  EXPECT_FLOAT_EQ(o.depth[2 * 4 + 3], 1.0f);
  EXPECT_NEAR(o.state[0], 1.0, 1e-12) << "the goal straight ahead";
  EXPECT_NEAR(o.state[1], 0.0, 1e-12);
  EXPECT_NEAR(o.state[3], 0.5, 1e-12) << "10 m of 20";
  EXPECT_NEAR(o.state[4], 1.0, 1e-12) << "2 m/s forward of 2";
  EXPECT_THROW(MakeNavObservation(image, s, {0, 0, 0}, 3, 3, 10.0, {2, 2, 1, 1}), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack::rl
