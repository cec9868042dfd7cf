// The learned method's rollouts and their binary form (navstack/rl/nav_rollout.h).
#include "navstack/rl/nav_rollout.h"

#include <cstring>

#include <gtest/gtest.h>

#include "navstack/rl/random.h"
#include "navstack/rl/rollout.h"

namespace enavi::navstack::rl {
namespace {

// An episode of `steps` decisions with camera-like depth: a smooth scene plus per-pixel noise.
NavRollout Episode(int steps, bool terminal) {
  NavRollout r;
  r.width = 64;
  r.height = 48;
  r.id = "forest-3-pi4b";
  r.info = {{"success", 1.0}, {"flight_time_s", 9.75}};
  Rng rng(11);
  for (int t = 0; t < steps; ++t) {
    std::vector<float> depth;
    for (int y = 0; y < r.height; ++y)
      for (int x = 0; x < r.width; ++x)
        depth.push_back(static_cast<float>(std::clamp(0.3 + 0.2 * std::sin(0.1 * x + 0.05 * t) + 0.01 * rng.Normal(), 0.0, 1.0)));
    NavRolloutStep s;
    s.depth = QuantizeDepth(depth);
    for (int i = 0; i < kNavStateSize; ++i) s.state[i] = rng.Normal();
    for (int i = 0; i < kNavActionSize; ++i) s.action[i] = rng.Normal();
    s.log_prob = -3.5 + 0.1 * t;
    s.reward = 0.05 * t;
    s.done = terminal && t + 1 == steps;
    r.steps.push_back(std::move(s));
  }
  return r;
}

TEST(NavRolloutTest, RoundTripsExactlyAndCompresses) {
  const NavRollout r = Episode(300, true);
  const std::string blob = EncodeNavRollout(r);
  ASSERT_TRUE(IsNavRolloutBlob(blob));
  const NavRollout back = DecodeNavRollout(blob, "test");
  EXPECT_EQ(back.width, 64);
  EXPECT_EQ(back.height, 48);
  EXPECT_EQ(back.id, r.id);
  EXPECT_EQ(back.info, r.info);
  ASSERT_EQ(back.steps.size(), r.steps.size());
  for (std::size_t t = 0; t < r.steps.size(); ++t) {
    EXPECT_EQ(back.steps[t].depth, r.steps[t].depth);
    EXPECT_EQ(back.steps[t].state, r.steps[t].state);
    EXPECT_EQ(back.steps[t].action, r.steps[t].action);
    EXPECT_EQ(back.steps[t].log_prob, r.steps[t].log_prob);
    EXPECT_EQ(back.steps[t].reward, r.steps[t].reward);
    EXPECT_EQ(back.steps[t].done, r.steps[t].done);
  }
  EXPECT_EQ(CheckRolloutBlob(blob, "test"), 300u);
  // 6,257 bytes a step raw; the smooth part of the image compresses, the noise does not.
  const double per_step = static_cast<double>(blob.size()) / 300;
  EXPECT_LT(per_step, 64 * 48 * 2 + 14 * 8 + 1);
  RecordProperty("bytes_per_step", std::to_string(per_step));
}

TEST(NavRolloutTest, TheStoredDepthIsWithinHalfAStepOfWhatThePolicySaw) {
  const std::vector<float> depth = {0.0f, 1.0f, 0.123456f, 0.5f, 0.99999f, 1.5f, -0.2f};
  const std::vector<std::uint16_t> q = QuantizeDepth(depth);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_NEAR(DepthValue(q[i]), depth[i], 0.5 / 65535 + 1e-7) << i;
  EXPECT_EQ(q[5], 65535) << "clipped to the range";
  EXPECT_EQ(q[6], 0);
}

TEST(NavRolloutTest, ABadBlobNamesItsSourceAndField) {
  const std::string good = EncodeNavRollout(Episode(20, true));
  auto refused = [](const std::string& blob, const std::string& expect) {
    try {
      DecodeNavRollout(blob, "rollout of e-1");
      ADD_FAILURE() << "accepted; expected " << expect;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("rollout of e-1: rollout " + expect), std::string::npos) << e.what();
    }
  };
  refused("ENR1" + good.substr(4), "magic: not an ENV1 nav rollout");
  refused(good.substr(0, 10), "height: truncated");
  refused(good.substr(0, good.size() - 10), "steps: the compressed steps do not decode");
  std::string bad = good;
  const std::uint32_t steps = 21;  // one step more than the stream holds
  std::memcpy(bad.data() + 12, &steps, 4);
  refused(bad, "steps: the compressed steps do not decode to 21 steps");
  bad = good;
  const std::uint32_t huge = 4000000;  // a header asking for gigabytes is refused before allocating
  std::memcpy(bad.data() + 12, &huge, 4);
  refused(bad, "steps: 4000000 steps of 3072 pixels exceed the 1 GiB bound");
  bad = good;
  const std::uint32_t wide = 100000;
  std::memcpy(bad.data() + 4, &wide, 4);
  refused(bad, "width: 100000x48 is not an image size");

  // A terminal in the middle of an episode is not a rollout of one episode.
  NavRollout r = Episode(5, false);
  r.steps[2].done = true;
  refused(EncodeNavRollout(r), "steps[2].done: a terminal before the last step");
  r = Episode(5, false);
  r.steps[3].reward = std::nan("");
  refused(EncodeNavRollout(r), "reward: not a finite number");
}

TEST(NavRolloutTest, EitherFormIsCheckedByItsOwnDecoder) {
  Rollout freq;
  RolloutStep s;
  s.obs = Eigen::VectorXd::Zero(3);
  s.mask = {1, 1};
  s.action = 1;
  s.log_prob = -0.7;
  freq.steps = {s, s};
  EXPECT_EQ(CheckRolloutBlob(EncodeRollout(freq), "f"), 2u);
  EXPECT_FALSE(IsNavRolloutBlob(EncodeRollout(freq)));
  EXPECT_EQ(CheckRolloutBlob(EncodeNavRollout(Episode(4, false)), "n"), 4u);
  EXPECT_THROW(CheckRolloutBlob("ENV1", "n"), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack::rl
