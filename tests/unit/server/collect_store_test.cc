// Collection jobs in the store: one rollout per done episode, written with its result (a re-run
// attempt that finishes first wins, a late duplicate is ignored), stale-policy rollouts refused by
// hash, and the tables added to a database created before them. Other jobs' policy files are
// loaded at submit.
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "navstack/rl/nav_policy.h"
#include "navstack/rl/policy_io.h"
#include "navstack/rl/rollout.h"
#include "server/scheduler/collection.h"
#include "server/store/sqlite.h"
#include "server/store/collect_store.h"
#include "server/store/ingest.h"
#include "server/store/jobs.h"
#include "server/store/leases.h"
#include "server/store/store.h"

namespace enavi::server {
namespace {

namespace fs = std::filesystem;

constexpr std::int64_t kNow = 1'000'000;
constexpr std::int64_t kLease = 15'000;
const std::string kHash(64, 'a');
const std::string kOtherHash(64, 'b');

std::string RolloutBytes(int steps, double reward) {
  navstack::rl::Rollout r;
  for (int t = 0; t < steps; ++t) {
    navstack::rl::RolloutStep s;
    s.obs = Eigen::VectorXd::Constant(16, t);
    s.mask.assign(98, 1);
    s.action = t;
    s.log_prob = -1;
    s.reward = reward;
    s.done = t + 1 == steps;
    r.steps.push_back(s);
  }
  return navstack::rl::EncodeRollout(r);
}

api::ResultMessage Ok(const Lease& l, const std::string& worker, std::string policy_hash, std::string rollout) {
  api::ResultMessage m;
  m.episode_id = l.episode_id;
  m.attempt = l.attempt;
  m.worker_id = worker;
  m.job_id = l.job_id;
  m.status = api::ResultStatus::kOk;
  m.result.spec = l.spec;
  m.result.success = true;
  m.policy_hash = std::move(policy_hash);
  m.rollout = std::move(rollout);
  return m;
}

class CollectStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("collect_store_test-" + std::to_string(getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    store_ = std::make_unique<Store>(dir_ / "farm.db");
  }
  void TearDown() override {
    store_.reset();
    fs::remove_all(dir_);
  }
  std::string CollectionJob(int episodes) {
    store_->collect().PutPolicy(kHash, "{}", kNow);
    std::vector<api::EpisodeSpec> specs(static_cast<std::size_t>(episodes));
    for (int i = 0; i < episodes; ++i) {
      specs[i].world = "empty";
      specs[i].method = "enavi";
      specs[i].seed = static_cast<std::uint64_t>(i + 1);
      specs[i].policy = "sha256:" + kHash;
    }
    return store_->jobs().CreateJob("collect", "yaml", specs, kNow, {}, CollectionInfo{kHash, true});
  }
  fs::path dir_;
  std::unique_ptr<Store> store_;
};

TEST_F(CollectStoreTest, ReRunAttemptStoresExactlyOneRollout) {
  const std::string job = CollectionJob(1);
  ASSERT_EQ(store_->collect().Collection(job)->policy_hash, kHash);
  const Lease first = store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow).at(0);
  // w1 goes silent: its lease expires and w2 runs attempt 2.
  ASSERT_EQ(store_->leases().ExpireLeases(kNow + kLease + 1).size(), 1u);
  const Lease second = store_->leases().LeaseEpisodes("w2", 1, {}, kNow + 3 * kLease, kNow + kLease + 2).at(0);
  ASSERT_EQ(second.attempt, 2);
  auto out = store_->ingest().Ingest({Ok(second, "w2", kHash, RolloutBytes(5, 1.0))}, kNow + kLease + 3);
  EXPECT_EQ(out.at(0).ack, api::AckStatus::kStored);
  // w1's late result of attempt 1 (a different rollout) is a duplicate: nothing changes.
  out = store_->ingest().Ingest({Ok(first, "w1", kHash, RolloutBytes(7, 2.0))}, kNow + kLease + 4);
  EXPECT_EQ(out.at(0).ack, api::AckStatus::kDuplicate);

  const auto rollouts = store_->collect().Rollouts(job);
  ASSERT_EQ(rollouts.size(), 1u);
  EXPECT_EQ(rollouts[0].attempt, 2);
  EXPECT_EQ(rollouts[0].worker, "w2");
  EXPECT_EQ(rollouts[0].rollout, RolloutBytes(5, 1.0));
  EXPECT_EQ(rollouts[0].policy_hash, kHash);
}

TEST_F(CollectStoreTest, StaleOrMissingRolloutIsRefusedAndTheEpisodeRunsAgain) {
  const std::string job = CollectionJob(1);
  Lease l = store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow).at(0);
  auto out = store_->ingest().Ingest({Ok(l, "w1", kOtherHash, RolloutBytes(3, 1.0))}, kNow + 1);
  EXPECT_EQ(out.at(0).ack, api::AckStatus::kRecorded);
  EXPECT_EQ(out.at(0).event, "requeued");
  EXPECT_TRUE(store_->collect().Rollouts(job).empty());
  const auto episodes = store_->jobs().Episodes(job);
  EXPECT_EQ(episodes.at(0).state, "pending");
  EXPECT_NE(episodes.at(0).last_error.find("stale policy"), std::string::npos) << episodes.at(0).last_error;

  l = store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow + 2).at(0);
  out = store_->ingest().Ingest({Ok(l, "w1", kHash, "")}, kNow + 3);
  EXPECT_EQ(out.at(0).ack, api::AckStatus::kRecorded);
  EXPECT_NE(store_->jobs().Episodes(job).at(0).last_error.find("without a rollout"), std::string::npos);

  l = store_->leases().LeaseEpisodes("w1", 1, {}, kNow + kLease, kNow + 4).at(0);
  out = store_->ingest().Ingest({Ok(l, "w1", kHash, RolloutBytes(3, 1.0))}, kNow + 5);
  EXPECT_EQ(out.at(0).ack, api::AckStatus::kStored);
  EXPECT_EQ(store_->collect().Rollouts(job).size(), 1u);
  EXPECT_EQ(store_->collect().ActivePolicies().size(), 0u) << "the job is done";
}

// A job that flies a policy file (not a collection) has the file loaded once at submit: a file
// that does not load is refused naming it and the field, before any episode flies it.
TEST_F(CollectStoreTest, AJobsPolicyFileThatDoesNotLoadIsRefusedAtSubmit) {
  const fs::path good = dir_ / "policy.json", bad = dir_ / "bad.json";
  navstack::rl::SavePolicyFile(good.string(), navstack::rl::MakeFrequencyPolicy(navstack::ActionGrid(), 1));
  std::ofstream(bad) << "{}";
  api::JobSpec job;
  std::vector<api::EpisodeSpec> episodes(2);
  episodes[0].method = episodes[1].method = "enavi";
  episodes[0].policy = episodes[1].policy = good.string();
  EXPECT_EQ(PrepareCollection(store_.get(), job, &episodes), std::nullopt);
  EXPECT_EQ(episodes[1].policy, good.string()) << "a job that does not collect flies the file itself";
  episodes[1].policy = bad.string();
  try {
    PrepareCollection(store_.get(), job, &episodes);
    FAIL() << "a policy file that does not load was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "policy file '" + bad.string() + "': format: missing");
  }
}

// A collection of the learned method stores its nav policy by the hash of its canonical text, and
// refuses a policy of the other kind, or sampling from a policy without a log_std.
TEST_F(CollectStoreTest, ANavPolicyCollectsForTheLearnedMethodOnly) {
  navstack::rl::NavPolicyNet net = navstack::rl::MakeNavPolicy(64, 48, 3);
  const fs::path greedy = dir_ / "greedy.json", sampled = dir_ / "sampled.json", freq = dir_ / "freq.json";
  navstack::rl::SaveNavPolicy(greedy.string(), net, {{"note", "kept"}});
  net.set_log_std({-0.5, -0.5, -1, -1});
  navstack::rl::SaveNavPolicy(sampled.string(), net);
  navstack::rl::SavePolicyFile(freq.string(), navstack::rl::MakeFrequencyPolicy(navstack::ActionGrid(), 1));
  auto prepare = [&](const std::string& method, const fs::path& policy, bool sample) {
    api::JobSpec job;
    job.methods = {method};
    job.policy = policy.string();
    job.collect = api::CollectSpec{sample};
    std::vector<api::EpisodeSpec> episodes(2);
    for (auto& e : episodes) {
      e.method = method;
      e.policy = job.policy;
    }
    const auto info = PrepareCollection(store_.get(), job, &episodes);
    EXPECT_EQ(episodes[0].policy, "sha256:" + info->policy_hash);
    return *info;
  };
  const CollectionInfo info = prepare("learned", sampled, true);
  const std::string stored = *store_->collect().Policy(info.policy_hash);
  EXPECT_EQ(navstack::rl::NavPolicyFromJson(nlohmann::json::parse(stored), "stored").log_std()->at(2), -1.0);
  EXPECT_EQ(prepare("learned", sampled, true).policy_hash, info.policy_hash) << "one hash per network";
  EXPECT_NE(store_->collect().Policy(prepare("learned", greedy, false).policy_hash)->find("\"kept\""),
            std::string::npos) << "the metadata is kept";
  auto refusal = [&](const std::string& method, const fs::path& policy, bool sample) {
    try {
      prepare(method, policy, sample);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    ADD_FAILURE() << method << " collected with " << policy;
    return std::string();
  };
  EXPECT_NE(refusal("learned", greedy, true).find("sample: true draws from the nav policy's Gaussian"), std::string::npos);
  EXPECT_NE(refusal("enavi", sampled, true).find("is a nav policy (method learned); the job flies enavi"),
            std::string::npos);
  EXPECT_NE(refusal("learned", freq, false).find("is a frequency policy (method enavi); the job flies learned"),
            std::string::npos);
}

TEST_F(CollectStoreTest, DatabaseFromBeforeCollectionGainsTheTables) {
  store_.reset();
  {
    // A database as the previous build left it: no collection tables.
    Database db(dir_ / "farm.db", 1000);
    db.Exec("DROP TABLE rollouts; DROP TABLE collect_jobs; DROP TABLE policies;");
  }
  store_ = std::make_unique<Store>(dir_ / "farm.db");
  const std::string job = CollectionJob(2);
  EXPECT_TRUE(store_->collect().Collection(job).has_value());
  EXPECT_EQ(store_->collect().ActivePolicies().count(kHash), 1u);
  EXPECT_FALSE(store_->collect().Collection("j-nope").has_value());
}

}  // namespace
}  // namespace enavi::server
