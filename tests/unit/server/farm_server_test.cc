#include "server/scheduler/farm_server.h"

#include <unistd.h>

#include <filesystem>
#include <thread>

#include <gtest/gtest.h>

#include "server/store/collect_store.h"
#include "server/store/queries.h"
#include "tests/unit/api/farm_test_util.h"

namespace enavi::server {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using testing::WaitFor;

// A scripted worker: the test decides what it announces and answers.
struct FakeWorker {
  FakeWorker(const api::BusOptions& bus, std::string id, int slots)
      : bus(bus, id), slots(slots) {
    status.worker_id = std::move(id);
    status.slots = slots;
    status.free_slots = slots;
  }
  void Heartbeat() {
    status.running.clear();
    for (const auto& a : running) status.running.push_back({a.episode_id, a.attempt});
    ++status.seq;
    bus.Publish(status);
  }
  void Pump() {
    auto in = bus.Wait(20ms);
    for (auto& a : in.assignments) {
      // Like the real worker: the replay of an attempt it already has is ignored.
      const bool known = std::any_of(assignments.begin(), assignments.end(), [&](const api::Assignment& b) {
        return b.episode_id == a.episode_id && b.attempt == a.attempt;
      });
      if (known) continue;
      running.push_back(a);
      assignments.push_back(std::move(a));
    }
    for (auto& a : in.acks) acks.push_back(std::move(a));
    for (auto& e : in.events) events.push_back(std::move(e));
  }
  api::ResultMessage Finish(const api::Assignment& a) {
    api::ResultMessage m;
    m.episode_id = a.episode_id;
    m.attempt = a.attempt;
    m.worker_id = status.worker_id;
    m.job_id = a.job_id;
    m.result.spec = a.spec;
    m.result.success = true;
    m.result.flight_time_s = 10;
    running.erase(std::remove_if(running.begin(), running.end(),
                                 [&](const api::Assignment& r) { return r.episode_id == a.episode_id; }),
                  running.end());
    bus.Publish(m);
    return m;
  }
  api::WorkerBus bus;
  int slots;
  api::WorkerStatus status;
  std::vector<api::Assignment> assignments, running;
  std::vector<api::ResultAck> acks;
  std::vector<api::JobEvent> events;
};

class FarmServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("farm_server_test-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    store_ = std::make_unique<Store>(dir_ / "farm.db");
    options_.bus = testing::TestBus();
    options_.lease = 1500ms;
    options_.worker_timeout = 1500ms;
    options_.tick = 50ms;
  }
  void TearDown() override {
    server_.reset();
    store_.reset();
    fs::remove_all(dir_);
  }
  void StartServer() {
    server_ = std::make_unique<FarmServer>(store_.get(), options_);
    server_->Start();
  }
  std::string SubmitEpisodes(int n) {
    std::vector<api::EpisodeSpec> episodes(n);
    for (int i = 0; i < n; ++i) episodes[i].seed = static_cast<std::uint64_t>(i + 1);
    return server_->Submit("test", "yaml", episodes);
  }
  // Heartbeats and pumps the worker until `done` holds.
  bool Drive(FakeWorker& w, const std::function<bool()>& done,
             std::chrono::milliseconds timeout = 20s) {
    return WaitFor([&] {
      w.Heartbeat();
      w.Pump();
      return done();
    }, timeout);
  }

  fs::path dir_;
  std::unique_ptr<Store> store_;
  FarmServerOptions options_;
  std::unique_ptr<FarmServer> server_;
};

TEST_F(FarmServerTest, AssignsPendingEpisodesUpToTheWorkersSlots) {
  StartServer();
  FakeWorker w(options_.bus, "w1", 2);
  const std::string job = SubmitEpisodes(5);
  ASSERT_TRUE(Drive(w, [&] { return w.assignments.size() >= 2; }));
  // Keep heartbeating a while: no third assignment while both slots are leased.
  Drive(w, [] { return false; }, 500ms);
  EXPECT_EQ(w.assignments.size(), 2u);
  EXPECT_EQ(store_->jobs().Progress(job, NowMs())->leased, 2);
  EXPECT_EQ(w.assignments[0].attempt, 1);
  EXPECT_EQ(w.assignments[0].job_id, job);
}

// An episode of a ROS method goes only to a worker that offers ros (docs/ros.md); until one
// connects the job says why its episodes wait.
TEST_F(FarmServerTest, ARosMethodsEpisodeWaitsForAWorkerWithRos) {
  StartServer();
  std::vector<api::EpisodeSpec> episodes(2);
  episodes[0].method = "enavi";
  episodes[1].method = "ego";
  episodes[1].clock = "emulated";
  episodes[1].ros = api::RosStack{};
  episodes[1].ros->name = "ego";
  episodes[1].ros->run = {"true"};
  const std::string job = server_->Submit("test", "yaml", episodes);
  FakeWorker plain(options_.bus, "plain", 2);
  ASSERT_TRUE(Drive(plain, [&] { return plain.assignments.size() >= 1; }));
  Drive(plain, [] { return false; }, 500ms);
  ASSERT_EQ(plain.assignments.size(), 1u) << "the ROS episode must not go to a worker without ros";
  EXPECT_EQ(plain.assignments[0].spec.method, "enavi");
  api::JobProgress p = *store_->jobs().Progress(job, NowMs());
  EXPECT_EQ(p.pending_needs, (std::map<std::string, int>{{"ros", 1}}));
  server_->ExplainWaiting(&p);
  EXPECT_EQ(p.waiting.rfind("1 episode(s) need a worker with ros, and no connected worker has it", 0), 0u) << p.waiting;

  FakeWorker ros(options_.bus, "ros", 1);
  ros.status.features = {"ros"};
  ASSERT_TRUE(Drive(ros, [&] { return !ros.assignments.empty(); }));
  EXPECT_EQ(ros.assignments[0].spec.method, "ego");
  ASSERT_TRUE(ros.assignments[0].spec.ros.has_value()) << "the stack travels with the episode";
  p = *store_->jobs().Progress(job, NowMs());
  server_->ExplainWaiting(&p);
  EXPECT_EQ(p.waiting, "");
}

TEST_F(FarmServerTest, ResultIsStoredBeforeItIsAcknowledgedAndDuplicatesAreAckedToo) {
  StartServer();
  FakeWorker w(options_.bus, "w1", 1);
  const std::string job = SubmitEpisodes(1);
  ASSERT_TRUE(Drive(w, [&] { return !w.assignments.empty(); }));
  const api::ResultMessage m = w.Finish(w.assignments[0]);
  ASSERT_TRUE(Drive(w, [&] { return !w.acks.empty(); }));
  EXPECT_EQ(w.acks[0].status, api::AckStatus::kStored);
  EXPECT_EQ(store_->queries().Results(job).size(), 1u) << "acknowledged means stored";
  EXPECT_EQ(store_->jobs().Progress(job, NowMs())->state, "done");
  w.bus.Publish(m);  // re-sent, e.g. after a lost ack
  ASSERT_TRUE(Drive(w, [&] { return w.acks.size() >= 2; }));
  EXPECT_EQ(w.acks[1].status, api::AckStatus::kDuplicate);
  EXPECT_EQ(store_->queries().Results(job).size(), 1u);
  EXPECT_EQ(server_->stats().duplicates, 1u);
}

// A rogue or broken worker's oversized result: refused, logged, not stored, the attempt failed.
TEST_F(FarmServerTest, ResultAboveTheSizeLimitIsRefusedAndNotStored) {
  options_.max_result_bytes = 1024;
  StartServer();
  FakeWorker w(options_.bus, "w1", 1);
  const std::string job = SubmitEpisodes(1);
  ASSERT_TRUE(Drive(w, [&] { return !w.assignments.empty(); }));
  api::ResultMessage m;
  m.episode_id = w.assignments[0].episode_id;
  m.attempt = w.assignments[0].attempt;
  m.worker_id = "w1";
  m.job_id = job;
  m.result.spec = w.assignments[0].spec;
  m.result.series.t.assign(200, 0.5);  // 1600 bytes of samples
  EXPECT_EQ(ResultPayloadBytes(m), 1600u);
  w.running.clear();
  w.bus.Publish(m);
  ASSERT_TRUE(Drive(w, [&] { return !w.acks.empty(); }));
  EXPECT_EQ(w.acks[0].status, api::AckStatus::kRecorded) << "the worker may forget it";
  EXPECT_TRUE(store_->queries().Results(job).empty()) << "an oversized result must not be stored";
  const auto episodes = store_->jobs().Episodes(job);
  ASSERT_EQ(episodes.size(), 1u);
  EXPECT_NE(episodes[0].last_error.find("result of 1600 bytes, above the server's limit of 1024"),
            std::string::npos)
      << episodes[0].last_error;
  EXPECT_EQ(server_->stats().oversized, 1u);
}

TEST_F(FarmServerTest, RolloutAboveTheSizeLimitIsRefusedAndNotStored) {
  options_.max_rollout_bytes = 1024;
  StartServer();
  FakeWorker w(options_.bus, "w1", 1);
  const std::string job = SubmitEpisodes(1);
  ASSERT_TRUE(Drive(w, [&] { return !w.assignments.empty(); }));
  api::ResultMessage m;
  m.episode_id = w.assignments[0].episode_id;
  m.attempt = w.assignments[0].attempt;
  m.worker_id = "w1";
  m.job_id = job;
  m.result.spec = w.assignments[0].spec;
  m.policy_hash = std::string(64, 'a');
  m.rollout = std::string(2000, 'r');
  w.running.clear();
  w.bus.Publish(m);
  ASSERT_TRUE(Drive(w, [&] { return !w.acks.empty(); }));
  EXPECT_EQ(w.acks[0].status, api::AckStatus::kRecorded);
  EXPECT_TRUE(store_->queries().Results(job).empty());
  EXPECT_TRUE(store_->collect().Rollouts(job).empty());
  const auto episodes = store_->jobs().Episodes(job);
  ASSERT_EQ(episodes.size(), 1u);
  EXPECT_NE(episodes[0].last_error.find("rollout of 2000 bytes, above the server's limit of 1024"),
            std::string::npos)
      << episodes[0].last_error;
  EXPECT_EQ(server_->stats().oversized, 1u);
}

TEST_F(FarmServerTest, VanishedWorkersEpisodeIsRunAgainElsewhere) {
  StartServer();
  auto w1 = std::make_unique<FakeWorker>(options_.bus, "w1", 1);
  const std::string job = SubmitEpisodes(1);
  ASSERT_TRUE(Drive(*w1, [&] { return !w1->assignments.empty(); }));
  const std::string episode = w1->assignments[0].episode_id;
  w1.reset();  // the worker process is gone
  FakeWorker w2(options_.bus, "w2", 1);
  ASSERT_TRUE(Drive(w2, [&] { return !w2.assignments.empty(); }));
  EXPECT_EQ(w2.assignments[0].episode_id, episode);
  EXPECT_EQ(w2.assignments[0].attempt, 2) << "the lost lease counted as an attempt";
  w2.Finish(w2.assignments[0]);
  ASSERT_TRUE(Drive(w2, [&] { return !w2.acks.empty(); }));
  EXPECT_EQ(store_->jobs().Progress(job, NowMs())->done, 1);
}

TEST_F(FarmServerTest, HeartbeatsKeepALeaseAliveAndSilenceAboutItLosesIt) {
  StartServer();
  FakeWorker w(options_.bus, "w1", 1);
  const std::string job = SubmitEpisodes(1);
  ASSERT_TRUE(Drive(w, [&] { return !w.assignments.empty(); }));
  // Three lease lengths of heartbeats that list the episode: still leased to w1.
  Drive(w, [] { return false; }, 3 * options_.lease);
  EXPECT_TRUE(store_->leases().HoldsLease(w.assignments[0].episode_id, 1, "w1"));
  // The worker keeps heartbeating but no longer lists it (it lost the episode): the lease
  // expires and the episode is assigned again.
  w.running.clear();
  ASSERT_TRUE(WaitFor([&] {
    w.status.running.clear();
    w.bus.Publish(w.status);
    w.Pump();
    return w.assignments.size() >= 2;
  }));
  EXPECT_EQ(w.assignments[1].attempt, 2);
  EXPECT_EQ(store_->jobs().Progress(job, NowMs())->leased, 1);
}

TEST_F(FarmServerTest, CancelTellsWorkersToStop) {
  StartServer();
  FakeWorker w(options_.bus, "w1", 1);
  const std::string job = SubmitEpisodes(3);
  ASSERT_TRUE(Drive(w, [&] { return !w.assignments.empty(); }));
  EXPECT_TRUE(server_->Cancel(job));
  ASSERT_TRUE(Drive(w, [&] {
    return std::any_of(w.events.begin(), w.events.end(), [&](const api::JobEvent& e) {
      return e.kind == "cancelled" && e.job_id == job;
    });
  }));
  EXPECT_EQ(store_->jobs().Progress(job, NowMs())->state, "cancelled");
  EXPECT_FALSE(server_->Cancel("jnothing"));
}

TEST_F(FarmServerTest, ARestartedServerKeepsLeasesItsWorkersStillRun) {
  StartServer();
  FakeWorker w(options_.bus, "w1", 1);
  const std::string job = SubmitEpisodes(2);
  ASSERT_TRUE(Drive(w, [&] { return !w.assignments.empty(); }));
  server_.reset();  // server gone; the worker keeps running its episode
  StartServer();    // same database
  // The heartbeat renews the lease under the new server; the result is accepted.
  Drive(w, [] { return false; }, 2 * options_.lease);
  EXPECT_TRUE(store_->leases().HoldsLease(w.assignments[0].episode_id, 1, "w1"));
  w.Finish(w.assignments[0]);
  ASSERT_TRUE(Drive(w, [&] { return w.assignments.size() == 2; })) << "the second episode";
  w.Finish(w.assignments[1]);
  ASSERT_TRUE(Drive(w, [&] { return store_->jobs().Progress(job, NowMs())->state == "done"; }));
  EXPECT_EQ(store_->queries().Results(job).size(), 2u);
  EXPECT_EQ(store_->jobs().Progress(job, NowMs())->failed, 0);
}

// The server died before its worker received an assignment: the restarted server re-sends it,
// so the lease is run under its first attempt instead of running out unrun.
TEST_F(FarmServerTest, ARestartedServerResendsAnAssignmentItsWorkerNeverReceived) {
  options_.lease = 5000ms;
  StartServer();
  FakeWorker w(options_.bus, "w1", 1);
  const std::string job = SubmitEpisodes(1);
  ASSERT_TRUE(Drive(w, [&] { return !w.assignments.empty(); }));
  const api::Assignment lost = w.assignments[0];
  w.assignments.clear();  // it never arrived
  w.running.clear();
  server_.reset();
  StartServer();
  ASSERT_TRUE(Drive(w, [&] { return !w.assignments.empty(); }, 3000ms))
      << "the held lease was not re-sent";
  EXPECT_EQ(w.assignments[0].episode_id, lost.episode_id);
  EXPECT_EQ(w.assignments[0].attempt, 1) << "no attempt spent";
  w.Finish(w.assignments[0]);
  ASSERT_TRUE(Drive(w, [&] { return store_->jobs().Progress(job, NowMs())->state == "done"; }));
  EXPECT_EQ(store_->jobs().Episodes(job)[0].attempts, 1);
}

}  // namespace
}  // namespace enavi::server
