// Rollout serialisation: exact round trip and named errors.

#include "navstack/rl/rollout.h"

#include <functional>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "navstack/rl/random.h"

namespace enavi::navstack::rl {
namespace {

Rollout Sample() {
  Rollout r;
  r.id = "tx2/s2/seed1";
  r.policy_iteration = 12;
  r.bootstrap_value = -0.123456789012345678;
  r.info = {{"success", 1.0}, {"flight_time_s", 31.25}};
  Rng rng(3);
  for (int t = 0; t < 5; ++t) {
    RolloutStep s;
    s.obs = Eigen::VectorXd(4);
    for (int k = 0; k < 4; ++k) s.obs[k] = rng.Normal() / 7.0;
    s.mask = {1, 0, 1, 1, 0, 1};
    s.action = t % 2 == 0 ? 2 : 5;
    s.log_prob = -std::abs(rng.Normal());
    s.value = rng.Normal();
    s.reward = 0.1 * t - 1.0 / 3.0;
    s.done = t == 4;
    r.steps.push_back(s);
  }
  return r;
}

TEST(RolloutTest, SerialisationRoundTripsExactly) {
  const Rollout r = Sample();
  const Rollout q = DeserializeRollout(SerializeRollout(r), "test");
  ASSERT_EQ(q.steps.size(), r.steps.size());
  EXPECT_EQ(q.id, r.id);
  EXPECT_EQ(q.policy_iteration, r.policy_iteration);
  EXPECT_EQ(q.bootstrap_value, r.bootstrap_value);
  EXPECT_EQ(q.info, r.info);
  for (std::size_t t = 0; t < r.steps.size(); ++t) {
    EXPECT_TRUE(q.steps[t].obs == r.steps[t].obs) << "step " << t;
    EXPECT_EQ(q.steps[t].mask, r.steps[t].mask);
    EXPECT_EQ(q.steps[t].action, r.steps[t].action);
    EXPECT_EQ(q.steps[t].log_prob, r.steps[t].log_prob);
    EXPECT_EQ(q.steps[t].value, r.steps[t].value);
    EXPECT_EQ(q.steps[t].reward, r.steps[t].reward);
    EXPECT_EQ(q.steps[t].done, r.steps[t].done);
  }
  EXPECT_EQ(SerializeRollout(q), SerializeRollout(r));
}

void ExpectRefused(const std::function<void(nlohmann::json&)>& damage, const std::string& field) {
  nlohmann::json j = RolloutToJson(Sample());
  damage(j);
  try {
    RolloutFromJson(j, "rollout from worker 3");
    ADD_FAILURE() << "accepted damage to " << field;
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("rollout from worker 3"), std::string::npos) << msg;
    EXPECT_NE(msg.find(field), std::string::npos) << msg;
  }
}

TEST(RolloutTest, DamagedRolloutsNameTheField) {
  ExpectRefused([](auto& j) { j["version"] = 9; }, "version");
  ExpectRefused([](auto& j) { j["steps"][1]["action"] = 1; }, "steps[1].action");  // masked
  ExpectRefused([](auto& j) { j["steps"][2]["mask"] = "10x101"; }, "steps[2].mask");
  ExpectRefused([](auto& j) { j["steps"][0]["obs"].erase(0); }, "steps[0].obs");
  ExpectRefused([](auto& j) { j["steps"][3]["reward"] = nullptr; }, "steps[3].reward");
  ExpectRefused([](auto& j) { j["steps"][3]["log_prob"] = 0.5; }, "steps[3].log_prob");
  ExpectRefused([](auto& j) { j.erase("bootstrap_value"); }, "bootstrap_value");
  EXPECT_THROW(DeserializeRollout("{\"format\":", "cut"), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack::rl
