// The virtual clock: exact sim-time schedules (finish instants, preemption, rate changes, costs).
// The rules both clocks keep are in executor_contract_test.cc.
#include "navstack/runtime/virtual_executor.h"

#include <vector>

#include <gtest/gtest.h>

namespace enavi::navstack {
namespace {

// Prices one kPixel as 1 ms of board time, so a test job costs exactly what it reports.
WorkCountCostModel MillisecondPerPixel() {
  WorkCountCostModel::Coefficients c;
  c.ns_per_unit[static_cast<int>(WorkUnit::kPixel)] = 1e6;
  return WorkCountCostModel(c);
}

JobFn FixedCost(double ms, std::vector<double>* starts = nullptr, std::vector<double>* commits = nullptr,
                const VirtualExecutor* clock = nullptr) {
  return [=]() {
    if (starts) starts->push_back(clock->now());
    JobOutput out;
    out.work.Add(WorkUnit::kPixel, static_cast<std::int64_t>(ms));
    if (commits) out.commit = [=] { commits->push_back(clock->now()); };
    return out;
  };
}

void AdvanceInSteps(VirtualExecutor& ex, double until, double step = 0.001) {
  for (double t = ex.now() + step; t <= until + 1e-9; t += step) ex.AdvanceTo(t);
}

TEST(VirtualExecutorTest, PeriodicTaskUtilisationMatchesCostTimesRate) {
  const auto cost = MillisecondPerPixel();
  VirtualExecutor ex(1, cost);
  ex.Register(TaskId::kPerception, FixedCost(10));
  ex.SetRate(TaskId::kPerception, 30);
  AdvanceInSteps(ex, 3.0);
  const TaskStats& s = ex.stats(TaskId::kPerception);
  EXPECT_EQ(s.released, 91) << "releases at 0, 1/30, ..., 3.0 inclusive";
  EXPECT_EQ(s.misses(), 0);
  EXPECT_NEAR(s.busy_s / 3.0, 0.30, 1e-6);
}

TEST(VirtualExecutorTest, AJobThatCountedNoWorkTakesNoBoardTimeDespiteTheTasksOverhead) {
  // A 100 Hz timer whose jobs mostly find nothing to do (Ego-Planner's FSM tick): the per-job
  // overhead is the fixed part of a job that works, not a price for returning at once.
  WorkCountCostModel::Coefficients c;
  c.ns_per_unit[static_cast<int>(WorkUnit::kPixel)] = 1e6;
  c.ns_per_job[static_cast<int>(TaskId::kPlanning)] = 2e6;
  const WorkCountCostModel cost(c);
  VirtualExecutor ex(1, cost);
  int ticks = 0;
  ex.Register(TaskId::kPlanning, [&ticks]() {
    JobOutput out;
    if (++ticks % 10 == 0) out.work.Add(WorkUnit::kPixel, 3);  // every tenth tick plans: 2 + 3 ms
    return out;
  });
  ex.SetRate(TaskId::kPlanning, 100);
  AdvanceInSteps(ex, 1.0);
  const TaskStats& s = ex.stats(TaskId::kPlanning);
  EXPECT_EQ(s.released, 101);
  EXPECT_NEAR(s.busy_s, 10 * 0.005, 1e-9) << "ten working jobs of 5 ms; the 91 idle ones are free";
}

TEST(VirtualExecutorTest, CommitTakesEffectAtSimulatedFinish) {
  const auto cost = MillisecondPerPixel();
  VirtualExecutor ex(1, cost);
  std::vector<double> starts, commits;
  ex.Register(TaskId::kPlanning, FixedCost(40, &starts, &commits, &ex));
  ex.SetRate(TaskId::kPlanning, 10);
  AdvanceInSteps(ex, 0.25);
  ASSERT_EQ(starts.size(), 3u);
  ASSERT_EQ(commits.size(), 3u);
  for (std::size_t i = 0; i < starts.size(); ++i) {
    EXPECT_NEAR(starts[i], 0.1 * i, 1e-9);
    EXPECT_NEAR(commits[i], 0.1 * i + 0.040, 1e-9) << "job " << i;
  }
}

TEST(VirtualExecutorTest, OverrunSkipsReleasesAndCountsMisses) {
  const auto cost = MillisecondPerPixel();
  VirtualExecutor ex(1, cost);
  ex.Register(TaskId::kPerception, FixedCost(50));  // 50 ms job, 33 ms period
  ex.SetRate(TaskId::kPerception, 30);
  AdvanceInSteps(ex, 1.0);
  const TaskStats& s = ex.stats(TaskId::kPerception);
  EXPECT_GT(s.skipped, 0);
  EXPECT_GT(s.late, 0);
  EXPECT_EQ(s.released, 31);
  // Every other release is dropped: a job runs 50 ms, the core idles until the next release.
  EXPECT_EQ(s.skipped, 15);
  EXPECT_EQ(s.completed, 15);
  EXPECT_EQ(s.late, 15);
  EXPECT_NEAR(s.busy_s, 0.75, 1e-9) << "15 finished jobs x 50 ms; the 16th starts at t = 1 s";
}

TEST(VirtualExecutorTest, ShortDeadlineJobPreemptsLongJob) {
  const auto cost = MillisecondPerPixel();
  VirtualExecutor ex(1, cost);
  std::vector<double> plan_commits, col_commits;
  ex.Register(TaskId::kPlanning, FixedCost(30, nullptr, &plan_commits, &ex));
  ex.Register(TaskId::kCollision, FixedCost(5, nullptr, &col_commits, &ex));
  ex.Trigger(TaskId::kPlanning, 0.200);
  ex.AdvanceTo(0.010);
  ex.Trigger(TaskId::kCollision, 0.010);
  AdvanceInSteps(ex, 0.1);
  ASSERT_EQ(col_commits.size(), 1u);
  ASSERT_EQ(plan_commits.size(), 1u);
  EXPECT_NEAR(col_commits[0], 0.015, 1e-9) << "collision check preempts planning";
  EXPECT_NEAR(plan_commits[0], 0.035, 1e-9) << "planning resumes and loses 5 ms";
}

TEST(VirtualExecutorTest, FifoPolicyNeverPreempts) {
  // The same arrivals as ShortDeadlineJobPreemptsLongJob, on a single-threaded spinner.
  const auto cost = MillisecondPerPixel();
  VirtualExecutor ex(1, cost, SchedulingPolicy::kFifoNonPreemptive);
  std::vector<double> plan_commits, col_commits;
  ex.Register(TaskId::kPlanning, FixedCost(30, nullptr, &plan_commits, &ex));
  ex.Register(TaskId::kCollision, FixedCost(5, nullptr, &col_commits, &ex));
  ex.Trigger(TaskId::kPlanning, 0.200);
  ex.AdvanceTo(0.010);
  ex.Trigger(TaskId::kCollision, 0.010);
  AdvanceInSteps(ex, 0.1);
  ASSERT_EQ(col_commits.size(), 1u);
  ASSERT_EQ(plan_commits.size(), 1u);
  EXPECT_NEAR(plan_commits[0], 0.030, 1e-9) << "planning keeps the core";
  EXPECT_NEAR(col_commits[0], 0.035, 1e-9) << "the collision check waits and misses its deadline";
  EXPECT_EQ(ex.stats(TaskId::kCollision).late, 1);
}

TEST(VirtualExecutorTest, RateChangeAppliesFromNextRelease) {
  const auto cost = MillisecondPerPixel();
  VirtualExecutor ex(1, cost);
  std::vector<double> starts;
  ex.Register(TaskId::kPerception, FixedCost(1, &starts, nullptr, &ex));
  ex.SetRate(TaskId::kPerception, 10);
  AdvanceInSteps(ex, 0.35);  // releases at 0, 0.1, 0.2, 0.3
  ex.SetRate(TaskId::kPerception, 2);
  AdvanceInSteps(ex, 1.5);  // next at 0.3 + 0.5 = 0.8, then 1.3
  ASSERT_EQ(starts.size(), 6u);
  EXPECT_NEAR(starts[4], 0.8, 1e-9);
  EXPECT_NEAR(starts[5], 1.3, 1e-9);
  ex.SetRate(TaskId::kPerception, 0);
  AdvanceInSteps(ex, 3.0);
  EXPECT_EQ(starts.size(), 6u) << "rate 0 stops releases";
}

TEST(VirtualExecutorTest, MeasuredCostScalesHostCpuTime) {
  MeasuredCostModel cost(1000.0);  // a board 1000x slower than the host
  VirtualExecutor ex(1, cost);
  ex.Register(TaskId::kDifference, [] {
    volatile double x = 0;
    for (int i = 0; i < 2'000'000; ++i) x = x + 1e-9 * i;
    return JobOutput{};
  });
  ex.Trigger(TaskId::kDifference, 10.0);
  ex.AdvanceTo(0.0);
  const TaskStats& s = ex.stats(TaskId::kDifference);
  ASSERT_EQ(s.started, 1);
  EXPECT_GT(s.host_cpu_s, 0.0);
  EXPECT_DOUBLE_EQ(s.cost_sum_s, s.host_cpu_s * 1000.0);
}

TEST(VirtualExecutorTest, SameScheduleTwiceIsIdentical) {
  auto run = [] {
    const auto cost = MillisecondPerPixel();
    VirtualExecutor ex(2, cost);
    std::vector<double> commits;
    ex.Register(TaskId::kPerception, FixedCost(13, nullptr, &commits, &ex));
    ex.Register(TaskId::kPlanning, FixedCost(37, nullptr, &commits, &ex));
    ex.Register(TaskId::kCollision, FixedCost(3, nullptr, &commits, &ex));
    ex.SetRate(TaskId::kPerception, 30);
    ex.SetRate(TaskId::kPlanning, 20);
    ex.SetRate(TaskId::kCollision, 15);
    AdvanceInSteps(ex, 2.0);
    return commits;
  };
  EXPECT_EQ(run(), run());
}

// A job that leaves a decision to be taken outside the stack (JobOutput::awaits_decision): the
// schedule stops at its start instant, after the other job dispatched with it has run its code
// and before anything finishes; AdvanceTo again goes on, and the schedule is the one without the
// stop, instant for instant.
TEST(VirtualExecutorTest, AJobAwaitingADecisionStopsTheScheduleAtItsInstantUntilAdvancedAgain) {
  const auto cost = MillisecondPerPixel();
  auto run = [&](bool stop, std::vector<double>* starts, std::vector<double>* commits, int* stops) {
    VirtualExecutor ex(2, cost);
    ex.Register(TaskId::kPerception, FixedCost(3, starts, commits, &ex));
    ex.Register(TaskId::kAdapter, [&ex, starts, commits, stop]() {
      starts->push_back(100 + ex.now());
      JobOutput out;
      out.work.Add(WorkUnit::kPixel, 2);
      out.awaits_decision = stop;
      out.commit = [&ex, commits] { commits->push_back(100 + ex.now()); };
      return out;
    });
    ex.SetRate(TaskId::kPerception, 50);
    ex.SetRate(TaskId::kAdapter, 5);
    for (double t = 0.001; t <= 0.5 + 1e-9; t += 0.001) {
      ex.AdvanceTo(t);
      while (ex.paused()) {
        ++*stops;
        // Stopped where the adapter's job started, both jobs' code run, nothing committed since.
        EXPECT_DOUBLE_EQ(100 + ex.now(), starts->back());
        EXPECT_LT(commits->empty() ? -1.0 : commits->back(), 100 + ex.now());
        ex.AdvanceTo(t);
      }
    }
  };
  std::vector<double> starts, commits, stopped_starts, stopped_commits;
  int stops = 0, none = 0;
  run(false, &starts, &commits, &none);
  run(true, &stopped_starts, &stopped_commits, &stops);
  EXPECT_EQ(none, 0);
  EXPECT_EQ(stops, 3) << "adapter jobs at 0.0, 0.2 and 0.4 s";
  EXPECT_EQ(stopped_starts, starts);
  EXPECT_EQ(stopped_commits, commits);
}

}  // namespace
}  // namespace enavi::navstack
