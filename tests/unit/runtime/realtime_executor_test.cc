// The emulated clock's executor with fake jobs: what only it does (locking, measured costs, sim
// time from wall time, failures). The rules both clocks keep (EDF and FIFO order, overrun skips,
// trigger coalescing, cores, deadlines) are in executor_contract_test.cc. Nothing here asserts on
// durations.
#include "navstack/runtime/realtime_executor.h"

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "navstack/common/cpu_time.h"
#include "tests/unit/runtime/test_gate.h"

namespace enavi::navstack {
namespace {

using namespace std::chrono_literals;

TEST(RealtimeExecutorTest, CommitsRunUnderTheExclusiveLockWhileNoJobRuns) {
  RealtimeExecutorOptions o;
  o.threads = 2;
  std::atomic<int> inside{0};
  std::atomic<int> overlaps{0}, commits{0}, try_lock_succeeded{0};
  RealtimeExecutor* self = nullptr;
  o.after_commit = [&](TaskId) {
    if (self->job_lock().try_lock()) ++try_lock_succeeded;  // we hold it: must fail
  };
  RealtimeExecutor ex(o);
  self = &ex;
  // Perception: job code that takes a while; collision: a short job with a commit.
  ex.Register(TaskId::kPerception, [&] {
    ++inside;
    const double t0 = ThreadCpuSeconds();
    while (ThreadCpuSeconds() - t0 < 0.0005) {
    }
    --inside;
    return JobOutput{};
  });
  ex.Register(TaskId::kCollision, [&] {
    ++inside;
    --inside;
    JobOutput out;
    out.commit = [&] {
      if (inside.load() != 0) ++overlaps;
      ++commits;
    };
    return out;
  });
  ex.SetRate(TaskId::kPerception, 300.0);
  ex.SetRate(TaskId::kCollision, 300.0);
  ex.Start();
  ASSERT_TRUE(Eventually([&] { return commits.load() >= 30; }));
  ex.Stop();
  EXPECT_EQ(overlaps.load(), 0) << "a commit ran while job code was inside the shared section";
  EXPECT_EQ(try_lock_succeeded.load(), 0) << "after_commit must run with the exclusive lock still held";
  EXPECT_GE(ex.lock_stats().commits, 30);
}

TEST(RealtimeExecutorTest, WriterWaitsForARunningJob) {
  RealtimeExecutorOptions o;
  RealtimeExecutor ex(o);
  Gate gate;
  std::atomic<bool> running{false};
  ex.Register(TaskId::kPlanning, [&] {
    running = true;
    gate.Wait();
    return JobOutput{};
  });
  ex.Start();
  ex.Trigger(TaskId::kPlanning, 1.0);
  ASSERT_TRUE(Eventually([&] { return running.load(); }));
  EXPECT_FALSE(ex.job_lock().try_lock()) << "frames and odometry must not be written under a running job";
  gate.Open();
  ASSERT_TRUE(Eventually([&] { return ex.stats(TaskId::kPlanning).completed == 1; }));
  EXPECT_TRUE(ex.job_lock().try_lock());
  ex.job_lock().unlock();
}

TEST(RealtimeExecutorTest, BoardTimeIsThreadCpuTimesHostToBoard) {
  RealtimeExecutorOptions o;
  o.host_to_board = 2.5;
  RealtimeExecutor ex(o);
  ex.Register(TaskId::kPerception, [] {
    const double t0 = ThreadCpuSeconds();
    while (ThreadCpuSeconds() - t0 < 0.002) {
    }
    return JobOutput{};
  });
  ex.Start();
  for (int i = 0; i < 3; ++i) {
    ex.Trigger(TaskId::kPerception, 1.0);
    ASSERT_TRUE(Eventually([&] { return ex.stats(TaskId::kPerception).completed == i + 1; }));
  }
  ex.Stop();
  const TaskStats s = ex.stats(TaskId::kPerception);
  EXPECT_GE(s.host_cpu_s, 3 * 0.002);
  EXPECT_NEAR(s.busy_s, 2.5 * s.host_cpu_s, 1e-12);
  EXPECT_NEAR(s.cost_sum_s, s.busy_s, 1e-12);
  EXPECT_GE(s.cost_max_s, 2.5 * 0.002);
}

TEST(RealtimeExecutorTest, SimTimeIsWallTimeOverDilationAndStartsAtTheEpoch) {
  RealtimeExecutorOptions o;
  const auto clock = std::make_shared<DilatedSteadyClock>(4.0);
  o.clock = clock;
  RealtimeExecutor ex(o);
  clock->SetEpoch(std::chrono::steady_clock::now() - std::chrono::seconds(8));
  EXPECT_EQ(ex.now(), 0.0) << "before Start()";
  ex.Start();
  const double t = ex.now();
  EXPECT_GE(t, 2.0) << "8 wall seconds at k = 4 are at least 2 sim seconds";
  EXPECT_LT(t, 3.0);
}

// ROS time (our ROS node): the clock moves only when /clock steps it, and a job's board time is
// the sim time its code took (JobTiming::kElapsed), as a node on a real board measures it.
TEST(RealtimeExecutorTest, OnASteppedClockReleasesWaitForItsStepsAndJobsCostTheirElapsedSimTime) {
  RealtimeExecutorOptions o;
  const auto clock = std::make_shared<SteppedClock>();
  o.clock = clock;
  o.timing = JobTiming::kElapsed;
  o.host_to_board = 1000.0;  // ignored with kElapsed
  RealtimeExecutor ex(o);
  Gate gate;
  std::atomic<int> started{0};
  ex.Register(TaskId::kPerception, [&] {
    if (++started == 1) gate.Wait();
    return JobOutput{};
  });
  clock->Set(1.0);
  EXPECT_EQ(ex.now(), 0.0) << "before Start()";
  ex.Start();
  EXPECT_DOUBLE_EQ(ex.now(), 1.0);
  ex.SetRate(TaskId::kPerception, 10.0);  // releases at 1.0, 1.1, ...
  ASSERT_TRUE(Eventually([&] { return started.load() == 1; }));
  clock->Set(1.25);  // the job holds its worker for 0.25 s of sim time; 1.1 and 1.2 find it active
  ASSERT_TRUE(Eventually([&] { return ex.stats(TaskId::kPerception).skipped == 2; }));
  gate.Open();
  ASSERT_TRUE(Eventually([&] { return ex.stats(TaskId::kPerception).completed == 1; }));
  std::this_thread::sleep_for(30ms);  // wall time passes, sim time does not: nothing is released
  EXPECT_EQ(ex.stats(TaskId::kPerception).released, 3);
  clock->Set(1.3);
  ASSERT_TRUE(Eventually([&] { return ex.stats(TaskId::kPerception).completed == 2; }));
  ex.Stop();
  const TaskStats s = ex.stats(TaskId::kPerception);
  EXPECT_EQ(s.released, 4);
  EXPECT_DOUBLE_EQ(s.cost_max_s, 0.25) << "the first job ran from 1.0 to 1.25 of ROS time";
  EXPECT_LT(s.busy_s - s.cost_max_s, 1e-12) << "the second ran within one step";
  EXPECT_EQ(s.late, 1) << "its deadline was 1.1";
}

TEST(RealtimeExecutorTest, AdvanceToBlocksUntilTheSteppedClockGetsThere) {
  RealtimeExecutorOptions o;
  const auto clock = std::make_shared<SteppedClock>();
  o.clock = clock;
  RealtimeExecutor ex(o);
  ex.Start();
  std::atomic<bool> returned{false};
  std::thread waiter([&] {
    ex.AdvanceTo(0.5);
    returned = true;
  });
  clock->Set(0.2);
  std::this_thread::sleep_for(20ms);
  EXPECT_FALSE(returned.load()) << "0.2 < 0.5";
  clock->Set(0.5);
  EXPECT_TRUE(Eventually([&] { return returned.load(); }));
  waiter.join();
  ex.Stop();
}

TEST(RealtimeExecutorTest, AThrowingJobStopsDispatchAndIsReported) {
  RealtimeExecutorOptions o;
  RealtimeExecutor ex(o);
  std::atomic<int> other_runs{0};
  ex.Register(TaskId::kPlanning, []() -> JobOutput { throw std::runtime_error("planner exploded"); });
  ex.Register(TaskId::kCollision, [&] {
    ++other_runs;
    return JobOutput{};
  });
  ex.Start();
  ex.Trigger(TaskId::kPlanning, 1.0);
  ASSERT_TRUE(Eventually([&] { return !ex.error().empty(); }));
  EXPECT_NE(ex.error().find("planner exploded"), std::string::npos) << ex.error();
  ex.Trigger(TaskId::kCollision, 1.0);
  std::this_thread::sleep_for(20ms);
  ex.Stop();
  EXPECT_EQ(other_runs.load(), 0) << "after a failure no job may start";
}

TEST(RealtimeExecutorTest, StopAppliesTheCommitOfTheRunningJob) {
  RealtimeExecutorOptions o;
  RealtimeExecutor ex(o);
  Gate gate;
  std::atomic<bool> running{false}, committed{false};
  ex.Register(TaskId::kPlanning, [&] {
    running = true;
    gate.Wait();
    JobOutput out;
    out.commit = [&] { committed = true; };
    return out;
  });
  ex.Start();
  ex.Trigger(TaskId::kPlanning, 1.0);
  ASSERT_TRUE(Eventually([&] { return running.load(); }));
  std::thread opener([&] {
    std::this_thread::sleep_for(5ms);
    gate.Open();
  });
  ex.Stop();
  opener.join();
  EXPECT_TRUE(committed.load());
}

TEST(RealtimeExecutorTest, RejectsBadOptions) {
  RealtimeExecutorOptions o;
  o.threads = 0;
  EXPECT_THROW(RealtimeExecutor{o}, std::invalid_argument);
  o.threads = 1;
  o.host_to_board = -1;
  EXPECT_THROW(RealtimeExecutor{o}, std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack
