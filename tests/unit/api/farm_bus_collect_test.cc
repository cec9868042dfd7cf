// The collection topics: policies by hash (durable, for late workers too), collection
// assignments with their policy hash, and results with their binary rollout in one sample.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "api/farm_bus.h"
#include "tests/unit/api/cyclone_log_guard.h"
#include "tests/unit/api/farm_test_util.h"

namespace enavi::api {
namespace {

using namespace std::chrono_literals;
using testing::TestBus;
using testing::WaitFor;

// Bytes of every value, zeros included: a rollout is binary.
std::string Binary(std::size_t n) {
  std::string s(n, '\0');
  for (std::size_t i = 0; i < n; ++i) s[i] = static_cast<char>((i * 131) % 256);
  return s;
}

class FarmBusCollectTest : public ::testing::Test {
 protected:
  testing::CycloneLogGuard cyclone_log_;
};

TEST_F(FarmBusCollectTest, PolicyReachesWorkersThatJoinLater) {
  const BusOptions bus = TestBus();
  ServerBus server(bus);
  // A policy file is ~1.2 MB of canonical JSON.
  const PolicyBlob policy{std::string(64, 'e'), std::string(1'200'000, '7')};
  server.Publish(policy);
  WorkerBus late(bus, "late");
  std::vector<PolicyBlob> got;
  ASSERT_TRUE(WaitFor([&] {
    auto in = late.Wait(20ms);
    for (auto& p : in.policies) got.push_back(std::move(p));
    return !got.empty();
  }, 30s));
  EXPECT_EQ(got.front().hash, policy.hash);
  EXPECT_EQ(got.front().json, policy.json);
  EXPECT_NO_THROW(server.Retire(policy));
}

TEST_F(FarmBusCollectTest, CollectionAssignmentAndRolloutResultRoundTrip) {
  const BusOptions bus = TestBus();
  ServerBus server(bus);
  WorkerBus worker(bus, "w1");
  ASSERT_TRUE(WaitFor([&] { return worker.MatchedServers() == 1; }));

  Assignment a;
  a.worker_id = "w1";
  a.episode_id = "j1-00002";
  a.attempt = 2;
  a.job_id = "j1";
  a.spec.world = "empty";
  a.spec.method = "enavi";
  a.spec.policy = "sha256:" + std::string(64, 'f');
  a.policy_hash = std::string(64, 'f');
  server.Publish(a);
  std::vector<Assignment> assignments;
  ASSERT_TRUE(WaitFor([&] {
    for (auto& x : worker.Wait(20ms).assignments) assignments.push_back(std::move(x));
    return !assignments.empty();
  }));
  EXPECT_EQ(assignments.front().policy_hash, a.policy_hash);
  EXPECT_EQ(assignments.front().spec.policy, a.spec.policy);
  EXPECT_NO_THROW(server.Retire(a)) << "retired from the collection topic";

  ResultMessage m;
  m.episode_id = a.episode_id;
  m.attempt = a.attempt;
  m.worker_id = "w1";
  m.job_id = "j1";
  m.result.spec = a.spec;
  m.result.success = true;
  m.policy_hash = a.policy_hash;
  m.rollout = Binary(200'000);
  worker.Publish(m);
  std::vector<ResultMessage> results;
  ASSERT_TRUE(WaitFor([&] {
    auto in = server.Wait(20ms);
    for (const auto& b : in.bad_samples) ADD_FAILURE() << b;
    for (auto& r : in.results) results.push_back(std::move(r));
    return !results.empty();
  }));
  EXPECT_EQ(results.front().policy_hash, m.policy_hash);
  EXPECT_EQ(results.front().rollout, m.rollout);
  EXPECT_TRUE(results.front().result.success);
  EXPECT_NO_THROW(worker.Retire(m));

  ResultMessage huge = m;
  huge.rollout = std::string(kMaxRolloutBytes + 1, 'x');
  EXPECT_THROW(worker.Publish(huge), std::invalid_argument);
}

TEST(SpoolJsonTest, RolloutAndPolicyHashSurviveTheSpool) {
  ResultMessage m;
  m.episode_id = "j1-00000";
  m.attempt = 1;
  m.worker_id = "w";
  m.job_id = "j1";
  m.policy_hash = std::string(64, 'a');
  m.rollout = Binary(1000);
  const ResultMessage back = ResultMessageFromJson(nlohmann::json::parse(ToJson(m).dump()));
  EXPECT_EQ(back.rollout, m.rollout);
  EXPECT_EQ(back.policy_hash, m.policy_hash);
}

}  // namespace
}  // namespace enavi::api
