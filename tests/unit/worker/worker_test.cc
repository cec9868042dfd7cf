#include "workers/worker/worker.h"

#include <unistd.h>

#include <filesystem>
#include <thread>

#include <gtest/gtest.h>

#include "tests/unit/api/farm_test_util.h"

namespace enavi::worker {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using testing::WaitFor;

// A worker running in a thread against a test-driven ServerBus; fake_episode is the episode.
class WorkerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("worker_test-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    bus_ = testing::TestBus();
    server_ = std::make_unique<api::ServerBus>(bus_);
    options_.bus = bus_;
    options_.worker_id = "w1";
    options_.slots = 1;
    options_.boards = {"tx2"};
    options_.clocks = {"virtual", "emulated"};
    options_.episode_command = {std::string(ENAVI_BINARY_DIR) + "/tests/fake_episode"};
    options_.spool_dir = dir_ / "spool";
    options_.work_dir = dir_ / "work";
    options_.heartbeat = 100ms;
    options_.ack_grace = 0s;
    options_.drain_timeout = 0s;
  }
  void TearDown() override {
    StopWorker();
    server_.reset();
    fs::remove_all(dir_);
  }

  void StartWorker() {
    worker_ = std::make_unique<Worker>(options_);
    thread_ = std::thread([this] { worker_->Run(); });
    ASSERT_TRUE(WaitFor([&] {
      Pump();
      return !statuses_.empty();
    })) << "no heartbeat from the worker";
  }
  void StopWorker() {
    if (!worker_) return;
    worker_->RequestStop(/*abandon=*/true);
    thread_.join();
    worker_.reset();
  }

  void Pump() {
    auto in = server_->Wait(20ms);
    for (auto& s : in.statuses) statuses_.push_back(std::move(s));
    for (auto& r : in.results) results_.push_back(std::move(r));
    for (auto& g : in.workers_left) left_.push_back(std::move(g));
  }
  bool WaitForResults(std::size_t n) {
    return WaitFor([&] {
      Pump();
      return results_.size() >= n;
    });
  }

  api::Assignment Assign(const std::string& episode, int attempt = 1) {
    api::Assignment a;
    a.worker_id = "w1";
    a.episode_id = episode;
    a.attempt = attempt;
    a.job_id = "j1";
    a.lease_ms = 15000;
    a.spec.board = "tx2";
    a.spec.seed = 2;
    return a;
  }

  fs::path dir_;
  api::BusOptions bus_;
  std::unique_ptr<api::ServerBus> server_;
  WorkerOptions options_;
  std::unique_ptr<Worker> worker_;
  std::thread thread_;
  std::vector<api::WorkerStatus> statuses_;
  std::vector<api::ResultMessage> results_;
  std::vector<std::string> left_;
};

TEST_F(WorkerTest, AnnouncesItselfWithItsCapabilities) {
  options_.slots = 3;
  options_.boards = {"tx2", "nx"};
  options_.calibration_id = "cal-1";
  StartWorker();
  const api::WorkerStatus& s = statuses_.front();
  EXPECT_EQ(s.worker_id, "w1");
  EXPECT_EQ(s.slots, 3);
  EXPECT_EQ(s.free_slots, 3);
  EXPECT_EQ(s.boards, (std::vector<std::string>{"tx2", "nx"}));
  EXPECT_EQ(s.clocks, (std::vector<std::string>{"virtual", "emulated"}));
  EXPECT_EQ(s.calibration_id, "cal-1");
}

TEST_F(WorkerTest, RunsAnAssignmentAndForgetsTheResultOnlyWhenAcknowledged) {
  StartWorker();
  server_->Publish(Assign("j1-00000"));
  ASSERT_TRUE(WaitForResults(1));
  const api::ResultMessage& r = results_.front();
  EXPECT_EQ(r.status, api::ResultStatus::kOk) << r.error;
  EXPECT_EQ(r.episode_id, "j1-00000");
  EXPECT_EQ(r.result.spec.seed, 2u);
  // Until acknowledged the result is spooled and counted in the heartbeat.
  EXPECT_TRUE(fs::exists(options_.spool_dir / "j1-00000.1.result.json"));
  ASSERT_TRUE(WaitFor([&] {
    Pump();
    return statuses_.back().unacked_results == 1;
  }));
  server_->Publish(api::ResultAck{"w1", "j1-00000", 1, api::AckStatus::kStored, ""});
  ASSERT_TRUE(WaitFor([&] { return worker_->stats().results_acked == 1; }));
  EXPECT_FALSE(fs::exists(options_.spool_dir / "j1-00000.1.result.json"));
}

TEST_F(WorkerTest, RejectsAssignmentsBeyondItsSlots) {
  StartWorker();
  auto busy = Assign("j1-00000");
  busy.spec.overrides["fake.hang"] = 1;
  server_->Publish(busy);
  ASSERT_TRUE(WaitFor([&] {
    Pump();
    return !statuses_.back().running.empty();
  }));
  server_->Publish(Assign("j1-00001"));
  ASSERT_TRUE(WaitForResults(1));
  EXPECT_EQ(results_.front().episode_id, "j1-00001");
  EXPECT_EQ(results_.front().status, api::ResultStatus::kRejected);
  EXPECT_EQ(results_.front().error, "no free slot");
}

TEST_F(WorkerTest, CrashingEpisodeIsReportedAndTheWorkerCarriesOn) {
  StartWorker();
  auto crash = Assign("j1-00000");
  crash.spec.overrides["fake.crash_attempts"] = 1;
  server_->Publish(crash);
  ASSERT_TRUE(WaitForResults(1));
  EXPECT_EQ(results_[0].status, api::ResultStatus::kError);
  EXPECT_NE(results_[0].error.find("killed by signal 6"), std::string::npos) << results_[0].error;
  server_->Publish(Assign("j1-00001"));
  ASSERT_TRUE(WaitForResults(2));
  EXPECT_EQ(results_[1].status, api::ResultStatus::kOk);
}

TEST_F(WorkerTest, CancelledJobStopsItsRunningEpisodeWithoutAResult) {
  StartWorker();
  auto hang = Assign("j1-00000");
  hang.spec.overrides["fake.hang"] = 1;
  server_->Publish(hang);
  ASSERT_TRUE(WaitFor([&] {
    Pump();
    return !statuses_.back().running.empty();
  }));
  server_->Publish(api::JobEvent{"j1", "cancelled", "", 0, 0, 1, "job cancelled", 0});
  ASSERT_TRUE(WaitFor([&] { return worker_->stats().aborted == 1; }));
  ASSERT_TRUE(WaitFor([&] {
    Pump();
    return statuses_.back().running.empty() && statuses_.back().free_slots == 1;
  }));
  EXPECT_TRUE(results_.empty()) << "a cancelled episode must not report";
}

TEST_F(WorkerTest, StoppingHandsBackAnAbandonedEpisodeAndLeaves) {
  StartWorker();
  auto hang = Assign("j1-00000");
  hang.spec.overrides["fake.hang"] = 1;
  server_->Publish(hang);
  ASSERT_TRUE(WaitFor([&] {
    Pump();
    return !statuses_.back().running.empty();
  }));
  worker_->RequestStop(/*abandon=*/true);
  ASSERT_TRUE(WaitForResults(1));
  EXPECT_EQ(results_.front().status, api::ResultStatus::kRejected);
  EXPECT_EQ(results_.front().error, "worker stopped before the episode finished");
  thread_.join();
  worker_.reset();
  ASSERT_TRUE(WaitFor([&] {
    Pump();
    return !left_.empty();
  })) << "the server must see the worker leave";
}

TEST_F(WorkerTest, UnacknowledgedResultIsSentAgainAfterARestart) {
  StartWorker();
  server_->Publish(Assign("j1-00000"));
  ASSERT_TRUE(WaitForResults(1));
  StopWorker();  // no ack was sent: the result stays in the spool
  ASSERT_TRUE(fs::exists(options_.spool_dir / "j1-00000.1.result.json"));
  results_.clear();
  // A fresh server (restarted) and the worker restarted on the same spool.
  server_ = std::make_unique<api::ServerBus>(bus_);
  StartWorker();
  ASSERT_TRUE(WaitForResults(1));
  EXPECT_EQ(results_.front().episode_id, "j1-00000");
  EXPECT_EQ(results_.front().status, api::ResultStatus::kOk);
}

TEST_F(WorkerTest, BadOptionsAreRejected) {
  options_.slots = 0;
  EXPECT_THROW(Worker w(options_), std::invalid_argument);
  options_.slots = 1;
  options_.boards = {};
  EXPECT_THROW(Worker w(options_), std::invalid_argument);
  options_.boards = {"tx2"};
  options_.clocks = {};
  EXPECT_THROW(Worker w(options_), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::worker
