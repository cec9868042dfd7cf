// The rules every TaskExecutor keeps (navstack/runtime/executor.h, docs/design.md "Time: two
// clocks"), one typed suite for both clocks: VirtualExecutor (sim-time schedule, cost model) and
// RealtimeExecutor (worker threads) on wall time and on ROS time (a clock stepped from outside). Each executor gets a harness with a "holding"
// job: on the virtual clock it costs 100 ms of board time, on the real-time one it blocks on a
// gate the test opens. Orders are made by releases while the hold keeps the only core busy, so
// nothing here asserts on durations.
#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include <gtest/gtest.h>

#include "navstack/runtime/realtime_executor.h"
#include "navstack/runtime/virtual_executor.h"
#include "tests/unit/runtime/test_gate.h"

namespace enavi::navstack {
namespace {

using namespace std::chrono_literals;

// Task starts in the order the executor started them.
class StartLog {
 public:
  void Add(TaskId t) {
    std::lock_guard l(m_);
    order_.push_back(t);
  }
  std::vector<TaskId> Get() const {
    std::lock_guard l(m_);
    return order_;
  }

 private:
  mutable std::mutex m_;
  std::vector<TaskId> order_;
};

constexpr double kHoldBoardMs = 100;  // virtual clock: what a holding job costs

// Prices one kPixel as 1 ms of board time, so a virtual job costs exactly what it reports.
WorkCountCostModel MillisecondPerPixel() {
  WorkCountCostModel::Coefficients c;
  c.ns_per_unit[static_cast<int>(WorkUnit::kPixel)] = 1e6;
  return WorkCountCostModel(c);
}

class VirtualHarness {
 public:
  VirtualHarness(int cores, SchedulingPolicy policy) : cost_(MillisecondPerPixel()), ex_(cores, cost_, policy) {}
  TaskExecutor& ex() { return ex_; }
  /// The task's first job holds a core (100 ms of board time); later jobs take 1 ms.
  void RegisterHolding(TaskId task, StartLog* log) {
    auto first = std::make_shared<bool>(true);
    ex_.Register(task, [this, task, log, first] {
      if (log) log->Add(task);
      if (*first) ++holding_;
      JobOutput out;
      out.work.Add(WorkUnit::kPixel, *first ? static_cast<std::int64_t>(kHoldBoardMs) : 1);
      *first = false;
      return out;
    });
  }
  /// 1 ms jobs that log their start.
  void RegisterShort(TaskId task, StartLog* log) {
    ex_.Register(task, [task, log] {
      log->Add(task);
      JobOutput out;
      out.work.Add(WorkUnit::kPixel, 1);
      return out;
    });
  }
  void Start() {}
  /// Starts with the schedule `late` seconds behind: the clock reaches every release instant of
  /// that span at once. The virtual clock never lags; it simply runs the span.
  void StartLate(double late) { ex_.AdvanceTo(late); }
  /// Until `n` holding jobs have started.
  bool WaitHolding(int n) { return RunUntil([&] { return holding_ >= n; }); }
  /// A distinct release instant.
  void Tick() { ex_.AdvanceTo(ex_.now() + 0.001); }
  /// Holding jobs end by themselves once their board time has passed.
  void ReleaseHolds() {}
  /// Until sim time has passed `t`.
  void PassSimTime(double t) { RunUntil([&] { return ex_.now() > t; }); }
  template <typename F>
  bool RunUntil(F done) {
    for (int i = 0; i < 10'000 && !done(); ++i) ex_.AdvanceTo(ex_.now() + 0.001);
    return done();
  }
  void Stop() {}

 private:
  WorkCountCostModel cost_;
  VirtualExecutor ex_;
  int holding_ = 0;
};

class RealtimeHarness {
 public:
  RealtimeHarness(int cores, SchedulingPolicy policy) : ex_(Options(cores, policy)) {}
  ~RealtimeHarness() {
    gate_.Open();
    ex_.Stop();
  }
  TaskExecutor& ex() { return ex_; }
  /// The task's first job holds a worker until ReleaseHolds(); later jobs return at once.
  void RegisterHolding(TaskId task, StartLog* log) {
    auto first = std::make_shared<std::atomic<bool>>(true);
    ex_.Register(task, [this, task, log, first] {
      if (log) log->Add(task);
      if (first->exchange(false)) {
        ++holding_;
        gate_.Wait();
      }
      return JobOutput{};
    });
  }
  void RegisterShort(TaskId task, StartLog* log) {
    ex_.Register(task, [task, log] {
      log->Add(task);
      return JobOutput{};
    });
  }
  void Start() {
    clock_->SetEpoch(std::chrono::steady_clock::now());
    ex_.Start();
  }
  /// Sim time 0 lies `late` seconds in the past: the release thread's first wake-up finds that
  /// span's instants all due, as after a stall on a loaded host.
  void StartLate(double late) {
    clock_->SetEpoch(std::chrono::steady_clock::now() -
                     std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(late)));
    ex_.Start();
  }
  bool WaitHolding(int n) { return RunUntil([&] { return holding_.load() >= n; }); }
  void Tick() { std::this_thread::sleep_for(2ms); }
  void ReleaseHolds() { gate_.Open(); }
  void PassSimTime(double t) { RunUntil([&] { return ex_.now() > t; }); }
  template <typename F>
  bool RunUntil(F done) {
    return Eventually(done);
  }
  void Stop() { ex_.Stop(); }

 private:
  RealtimeExecutorOptions Options(int cores, SchedulingPolicy policy) {
    RealtimeExecutorOptions o;
    o.threads = cores;
    o.policy = policy;
    o.clock = clock_;
    return o;
  }
  std::shared_ptr<DilatedSteadyClock> clock_ = std::make_shared<DilatedSteadyClock>(1.0);
  RealtimeExecutor ex_;
  Gate gate_;
  std::atomic<int> holding_{0};
};

// The real-time executor on ROS time (our ROS node): a SteppedClock the harness moves by 1 ms
// steps, as /clock does, while it waits for what it waits for.
class SteppedHarness {
 public:
  SteppedHarness(int cores, SchedulingPolicy policy) : ex_(Options(cores, policy)) {}
  ~SteppedHarness() {
    gate_.Open();
    ex_.Stop();
  }
  TaskExecutor& ex() { return ex_; }
  void RegisterHolding(TaskId task, StartLog* log) {
    auto first = std::make_shared<std::atomic<bool>>(true);
    ex_.Register(task, [this, task, log, first] {
      if (log) log->Add(task);
      if (first->exchange(false)) {
        ++holding_;
        gate_.Wait();
      }
      return JobOutput{};
    });
  }
  void RegisterShort(TaskId task, StartLog* log) {
    ex_.Register(task, [task, log] {
      log->Add(task);
      return JobOutput{};
    });
  }
  void Start() { ex_.Start(); }
  /// The clock stands at `late` when releases begin.
  void StartLate(double late) {
    clock_->Set(late);
    ex_.Start();
  }
  bool WaitHolding(int n) { return RunUntil([&] { return holding_.load() >= n; }); }
  void Tick() { Step(); }
  void ReleaseHolds() { gate_.Open(); }
  void PassSimTime(double t) { RunUntil([&] { return ex_.now() > t; }); }
  template <typename F>
  bool RunUntil(F done) {
    for (int i = 0; i < 10'000 && !done(); ++i) Step();
    return done();
  }
  void Stop() { ex_.Stop(); }

 private:
  RealtimeExecutorOptions Options(int cores, SchedulingPolicy policy) {
    RealtimeExecutorOptions o;
    o.threads = cores;
    o.policy = policy;
    o.clock = clock_;
    return o;
  }
  void Step() {
    clock_->Set(clock_->Now() + 0.001);
    std::this_thread::sleep_for(1ms);
  }
  std::shared_ptr<SteppedClock> clock_ = std::make_shared<SteppedClock>();
  RealtimeExecutor ex_;
  Gate gate_;
  std::atomic<int> holding_{0};
};

template <typename H>
class ExecutorContractTest : public ::testing::Test {};

using Harnesses = ::testing::Types<VirtualHarness, RealtimeHarness, SteppedHarness>;
class HarnessNames {
 public:
  template <typename T>
  static std::string GetName(int) {
    return std::is_same_v<T, VirtualHarness> ? "Virtual" : std::is_same_v<T, RealtimeHarness> ? "Realtime" : "Stepped";
  }
};
TYPED_TEST_SUITE(ExecutorContractTest, Harnesses, HarnessNames);

// The hold (perception, the earliest deadline of all, so no executor preempts it) keeps the only
// core; collision, difference and planning are released in that order with deadlines 0.3, 0.1
// and 0.2 s; then the hold ends.
template <typename H>
std::vector<TaskId> OrderAfterHold(SchedulingPolicy policy) {
  H h(1, policy);
  StartLog log;
  h.RegisterHolding(TaskId::kPerception, nullptr);
  for (TaskId t : {TaskId::kCollision, TaskId::kDifference, TaskId::kPlanning}) h.RegisterShort(t, &log);
  h.Start();
  h.ex().Trigger(TaskId::kPerception, 0.05);
  EXPECT_TRUE(h.WaitHolding(1));
  h.ex().Trigger(TaskId::kCollision, 0.3);
  h.Tick();
  h.ex().Trigger(TaskId::kDifference, 0.1);
  h.Tick();
  h.ex().Trigger(TaskId::kPlanning, 0.2);
  h.ReleaseHolds();
  EXPECT_TRUE(h.RunUntil([&] { return log.Get().size() == 3; }));
  h.Stop();
  return log.Get();
}

TYPED_TEST(ExecutorContractTest, EdfRunsTheEarliestDeadlineFirst) {
  EXPECT_EQ(OrderAfterHold<TypeParam>(SchedulingPolicy::kGlobalEdf),
            (std::vector<TaskId>{TaskId::kDifference, TaskId::kPlanning, TaskId::kCollision}))
      << "deadlines 0.1 (difference) < 0.2 (planning) < 0.3 (collision)";
}

TYPED_TEST(ExecutorContractTest, FifoRunsTheEarliestReleaseFirst) {
  EXPECT_EQ(OrderAfterHold<TypeParam>(SchedulingPolicy::kFifoNonPreemptive),
            (std::vector<TaskId>{TaskId::kCollision, TaskId::kDifference, TaskId::kPlanning}))
      << "released in the order collision, difference, planning";
}

TYPED_TEST(ExecutorContractTest, OverrunningTaskSkipsReleasesAndFinishesLate) {
  TypeParam h(1, SchedulingPolicy::kGlobalEdf);
  h.RegisterHolding(TaskId::kPerception, nullptr);
  h.ex().SetRate(TaskId::kPerception, 200.0);  // 5 ms period; the first job overruns it
  h.Start();
  ASSERT_TRUE(h.RunUntil([&] { return h.ex().stats(TaskId::kPerception).skipped >= 3; }))
      << "releases of a task whose job is still running must be dropped";
  h.ReleaseHolds();
  ASSERT_TRUE(h.RunUntil([&] { return h.ex().stats(TaskId::kPerception).completed >= 3; }));
  h.ex().SetRate(TaskId::kPerception, 0);
  h.Stop();
  const TaskStats s = h.ex().stats(TaskId::kPerception);
  EXPECT_GE(s.late, 1) << "the overrunning job finished after its deadline";
  const std::int64_t pending = s.released - s.completed - s.skipped;
  EXPECT_GE(pending, 0);
  EXPECT_LE(pending, 1) << "every release ran or was skipped; at most one job is still open";
  EXPECT_EQ(s.misses(), s.late + s.skipped);
}

// A deadline miss is the task's: a job finishing late or a release finding its job still active.
// Release instants the clock itself reached late, while no job of the task was active, are not
// (they were counted as skips on the emulated clock: the tx2 s1 deadline-miss disagreement).
TYPED_TEST(ExecutorContractTest, InstantsTheClockReachesLateAreNotTheTasksMisses) {
  TypeParam h(1, SchedulingPolicy::kFifoNonPreemptive);
  StartLog log;
  h.RegisterShort(TaskId::kCollision, &log);
  h.ex().SetRate(TaskId::kCollision, 20.0);  // 50 ms period, 1 ms (virtual) or ~us (real-time) jobs
  h.StartLate(0.5);
  const std::size_t first = log.Get().size();
  ASSERT_TRUE(h.RunUntil([&] { return log.Get().size() >= first + 2; })) << "the task keeps running";
  h.ex().SetRate(TaskId::kCollision, 0);
  h.Stop();
  const TaskStats s = h.ex().stats(TaskId::kCollision);
  EXPECT_EQ(s.skipped, 0) << "no job of the task was active at any release instant";
  EXPECT_EQ(s.misses(), 0);
  EXPECT_GE(s.completed, 2);
}

TYPED_TEST(ExecutorContractTest, TriggersDuringAJobAreCoalescedIntoOneMore) {
  TypeParam h(1, SchedulingPolicy::kGlobalEdf);
  StartLog log;
  h.RegisterHolding(TaskId::kPlanning, &log);
  h.Start();
  h.ex().Trigger(TaskId::kPlanning, 0.5);
  ASSERT_TRUE(h.WaitHolding(1));
  EXPECT_TRUE(h.ex().active(TaskId::kPlanning));
  h.ex().Trigger(TaskId::kPlanning, 0.5);  // kept, not queued twice
  h.ex().Trigger(TaskId::kPlanning, 0.5);
  h.ReleaseHolds();
  ASSERT_TRUE(h.RunUntil([&] { return h.ex().stats(TaskId::kPlanning).completed == 2; }));
  h.PassSimTime(h.ex().now() + 0.05);  // room for a third job, which must not come
  h.Stop();
  EXPECT_EQ(log.Get().size(), 2u);
  EXPECT_EQ(h.ex().stats(TaskId::kPlanning).released, 2);
  EXPECT_EQ(h.ex().stats(TaskId::kPlanning).skipped, 0);
}

TYPED_TEST(ExecutorContractTest, EachCoreRunsAJobAtTheSameTime) {
  TypeParam h(2, SchedulingPolicy::kGlobalEdf);
  h.RegisterHolding(TaskId::kPerception, nullptr);
  h.RegisterHolding(TaskId::kPlanning, nullptr);
  EXPECT_EQ(h.ex().cores(), 2);
  h.Start();
  h.ex().Trigger(TaskId::kPerception, 1.0);
  h.ex().Trigger(TaskId::kPlanning, 1.0);
  EXPECT_TRUE(h.WaitHolding(2)) << "two cores: the second holding job starts while the first holds";
  h.ReleaseHolds();
  ASSERT_TRUE(h.RunUntil([&] {
    return h.ex().stats(TaskId::kPerception).completed == 1 && h.ex().stats(TaskId::kPlanning).completed == 1;
  }));
  h.Stop();
}

TYPED_TEST(ExecutorContractTest, AJobFinishingAfterItsDeadlineIsLateAndOneBeforeIsNot) {
  TypeParam h(1, SchedulingPolicy::kGlobalEdf);
  StartLog log;
  h.RegisterHolding(TaskId::kPlanning, nullptr);
  h.RegisterShort(TaskId::kCollision, &log);
  h.Start();
  h.ex().Trigger(TaskId::kPlanning, 0.02);  // held past its 20 ms deadline
  // The deadline is relative to the release, which on the realtime clock may come well after
  // t = 0 (a loaded host, a sanitizer build): hold the job to 30 ms after now, not after 0.
  const double released_by = h.ex().now();
  ASSERT_TRUE(h.WaitHolding(1));
  h.PassSimTime(released_by + 0.03);
  h.ReleaseHolds();
  ASSERT_TRUE(h.RunUntil([&] { return h.ex().stats(TaskId::kPlanning).completed == 1; }));
  h.ex().Trigger(TaskId::kCollision, 5.0);  // ample time
  ASSERT_TRUE(h.RunUntil([&] { return h.ex().stats(TaskId::kCollision).completed == 1; }));
  h.Stop();
  EXPECT_EQ(h.ex().stats(TaskId::kPlanning).late, 1);
  EXPECT_EQ(h.ex().stats(TaskId::kPlanning).misses(), 1);
  EXPECT_EQ(h.ex().stats(TaskId::kCollision).late, 0);
  EXPECT_EQ(h.ex().stats(TaskId::kCollision).misses(), 0);
}

}  // namespace
}  // namespace enavi::navstack
