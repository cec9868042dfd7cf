// The binary rollout form the farm ships and stores: exact round trip, and clear refusals.
#include <gtest/gtest.h>

#include "navstack/rl/rollout.h"

namespace enavi::navstack::rl {
namespace {

Rollout Sample() {
  Rollout r;
  r.id = "j1-00003";
  r.policy_iteration = 7;
  r.bootstrap_value = 0.125;
  r.info = {{"success", 1.0}, {"flight_time_s", 16.75}};
  for (int t = 0; t < 3; ++t) {
    RolloutStep s;
    s.obs = Eigen::VectorXd::LinSpaced(16, -1.0 / 7.0 + t, 1.0 / 3.0 + t);  // full-precision doubles
    s.mask.assign(98, 0);
    for (int a = t; a < 98; a += 5) s.mask[a] = 1;
    s.action = t + 5;
    s.log_prob = -1.0 / (t + 3.0);
    s.value = 0.1 * t;
    s.reward = t == 2 ? 10.0 : -0.01;
    s.done = t == 2;
    r.steps.push_back(s);
  }
  return r;
}

TEST(RolloutCodecTest, RoundTripsExactly) {
  const Rollout r = Sample();
  const std::string bytes = EncodeRollout(r);
  const Rollout back = DecodeRollout(bytes, "test");
  ASSERT_EQ(back.steps.size(), r.steps.size());
  EXPECT_EQ(back.id, r.id);
  EXPECT_EQ(back.policy_iteration, r.policy_iteration);
  EXPECT_EQ(back.bootstrap_value, r.bootstrap_value);
  EXPECT_EQ(back.info, r.info);
  for (std::size_t t = 0; t < r.steps.size(); ++t) {
    EXPECT_EQ(back.steps[t].obs, r.steps[t].obs);
    EXPECT_EQ(back.steps[t].mask, r.steps[t].mask);
    EXPECT_EQ(back.steps[t].action, r.steps[t].action);
    EXPECT_EQ(back.steps[t].log_prob, r.steps[t].log_prob);
    EXPECT_EQ(back.steps[t].value, r.steps[t].value);
    EXPECT_EQ(back.steps[t].reward, r.steps[t].reward);
    EXPECT_EQ(back.steps[t].done, r.steps[t].done);
  }
  // Compact: 16 doubles + 13 mask bytes + 29 bytes of scalars per step, under half of JSON.
  EXPECT_LT(bytes.size(), SerializeRollout(r).size() / 2);
}

TEST(RolloutCodecTest, RefusesTruncatedCorruptAndInconsistentBlobs) {
  const std::string bytes = EncodeRollout(Sample());
  EXPECT_THROW(DecodeRollout(bytes.substr(0, bytes.size() - 1), "test"), std::invalid_argument);
  EXPECT_THROW(DecodeRollout(bytes + "x", "test"), std::invalid_argument);
  std::string magic = bytes;
  magic[0] = 'X';
  EXPECT_THROW(DecodeRollout(magic, "test"), std::invalid_argument);

  Rollout outside = Sample();
  outside.steps[0].action = 1;  // not in the mask (0, 5, 10, ...)
  try {
    DecodeRollout(EncodeRollout(outside), "blob of ep 3");
    FAIL() << "an action outside its mask must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("blob of ep 3: rollout steps[0].action"), std::string::npos) << e.what();
  }
  Rollout positive = Sample();
  positive.steps[1].log_prob = 0.5;
  EXPECT_THROW(DecodeRollout(EncodeRollout(positive), "test"), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack::rl
