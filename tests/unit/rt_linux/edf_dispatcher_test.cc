#include <gtest/gtest.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <future>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

#include "navstack/runtime/sched_deadline.h"

namespace enavi::navstack {
namespace {

using std::chrono::milliseconds;
using Clock = std::chrono::steady_clock;

// Plain builders: designated initialisers that skip members warn under -Wextra.
EdfDispatcherOptions Workers(int n, std::function<void(int)> hook = {}) {
  EdfDispatcherOptions o;
  o.workers = n;
  o.on_worker_start = std::move(hook);
  return o;
}

PeriodicTask Task(std::string name, std::chrono::nanoseconds period,
                  std::function<void(const ReadyJob&)> body,
                  std::chrono::nanoseconds phase = std::chrono::nanoseconds{0},
                  std::chrono::nanoseconds deadline = std::chrono::nanoseconds{0}) {
  PeriodicTask t;
  t.name = std::move(name);
  t.period = period;
  t.relative_deadline = deadline;
  t.phase = phase;
  t.body = std::move(body);
  return t;
}

ReadyJob Job(int task, int release_ms, int deadline_ms) {
  const Clock::time_point t0{};
  return ReadyJob{task, 0, t0 + milliseconds(release_ms), t0 + milliseconds(deadline_ms)};
}

// Waits (bounded) until pred() holds; the bound only guards against a hung test.
template <typename Pred>
bool WaitFor(Pred pred) {
  for (int i = 0; i < 5000 && !pred(); ++i) std::this_thread::sleep_for(milliseconds(1));
  return pred();
}

TEST(EdfReadyQueueTest, PopsEarliestAbsoluteDeadlineFirst) {
  EdfReadyQueue q;
  q.Push(Job(0, 0, 50));
  q.Push(Job(1, 5, 20));
  q.Push(Job(2, 1, 33));
  std::vector<int> order;
  while (auto j = q.Pop()) order.push_back(j->task);
  EXPECT_EQ(order, (std::vector<int>{1, 2, 0}));
  EXPECT_FALSE(q.Pop().has_value());
}

TEST(EdfReadyQueueTest, EqualDeadlinesGoByReleaseThenTaskId) {
  EdfReadyQueue q;
  q.Push(Job(3, 2, 40));
  q.Push(Job(1, 2, 40));
  q.Push(Job(2, 1, 40));
  std::vector<int> order;
  while (auto j = q.Pop()) order.push_back(j->task);
  EXPECT_EQ(order, (std::vector<int>{2, 1, 3}));
}

TEST(EdfDispatcherTest, ReleasesAreStrictlyPeriodicWithImplicitDeadlines) {
  EdfDispatcher d(Workers(2));
  std::mutex m;
  std::vector<ReadyJob> seen;
  const auto period = milliseconds(4);
  const int task = d.AddTask(Task("per", period, [&](const ReadyJob& j) {
    std::lock_guard lock(m);
    seen.push_back(j);
  }));
  d.Start();
  ASSERT_TRUE(WaitFor([&] { return d.Stats(task).completed >= 5; }));
  d.Stop();
  std::lock_guard lock(m);
  ASSERT_GE(seen.size(), 5u);
  for (std::size_t i = 0; i < seen.size(); ++i) {
    EXPECT_EQ(seen[i].deadline - seen[i].release, period) << "job " << i;
    if (i > 0) {
      EXPECT_GT(seen[i].index, seen[i - 1].index);
      EXPECT_EQ(seen[i].release - seen[i - 1].release, (seen[i].index - seen[i - 1].index) * period)
          << "releases sit on the period grid even when some are skipped";
    }
  }
}

TEST(EdfDispatcherTest, QueuedJobsRunInDeadlineOrder) {
  // One worker, held by a gate job while a long-deadline and a short-deadline job are released.
  // The gate's 1 ms relative deadline makes it the first pick even when the worker thread starts
  // after the other two releases (a loaded CI machine), so it always holds the worker first.
  EdfDispatcher d(Workers(1));
  std::promise<void> gate;
  std::shared_future<void> gate_open = gate.get_future().share();
  std::mutex m;
  std::vector<std::string> order;
  auto record = [&](std::string name) {
    return [&, name](const ReadyJob&) {
      std::lock_guard lock(m);
      order.push_back(name);
    };
  };
  d.AddTask(Task("gate", std::chrono::hours(1), [gate_open](const ReadyJob&) { gate_open.wait(); },
                 milliseconds(0), milliseconds(1)));
  const int slow = d.AddTask(Task("slow", std::chrono::seconds(10), record("slow"), milliseconds(1)));
  const int fast = d.AddTask(Task("fast", milliseconds(500), record("fast"), milliseconds(2)));
  d.Start();
  ASSERT_TRUE(WaitFor([&] { return d.Stats(slow).released >= 1 && d.Stats(fast).released >= 1; }));
  gate.set_value();
  ASSERT_TRUE(WaitFor([&] { return d.Stats(slow).completed >= 1; }));
  d.Stop();
  std::lock_guard lock(m);
  ASSERT_GE(order.size(), 2u);
  EXPECT_EQ(order[0], "fast") << "deadline 502 ms beats 10001 ms although released later";
  EXPECT_EQ(order[1], "slow");
}

TEST(EdfDispatcherTest, OverrunningTaskSkipsReleasesInsteadOfQueueing) {
  EdfDispatcher d(Workers(2));
  std::atomic<int> running{0};
  std::atomic<int> max_running{0};
  const int task = d.AddTask(Task("overrun", milliseconds(2), [&](const ReadyJob&) {
    const int now = ++running;
    int prev = max_running.load();
    while (now > prev && !max_running.compare_exchange_weak(prev, now)) {
    }
    std::this_thread::sleep_for(milliseconds(7));
    --running;
  }));
  d.Start();
  ASSERT_TRUE(WaitFor([&] { return d.Stats(task).completed >= 3; }));
  d.Stop();
  const PeriodicTaskStats s = d.Stats(task);
  EXPECT_GE(s.skipped, 2) << "a 7 ms job with a 2 ms period covers >= 3 release instants";
  EXPECT_EQ(max_running.load(), 1) << "never two jobs of one task at once, even with 2 workers";
  EXPECT_GE(s.missed, 1) << "7 ms > 2 ms deadline";
  EXPECT_LT(s.cpu_time, milliseconds(7) * s.completed) << "sleeping jobs use little CPU";
  EXPECT_LE(s.completed, s.released);
}

TEST(EdfDispatcherTest, SetPeriodRespacesReleasesAfterTheNextOne) {
  EdfDispatcher d(Workers(1));
  std::mutex m;
  std::vector<ReadyJob> seen;
  int task = -1;
  task = d.AddTask(Task("adapt", milliseconds(6), [&](const ReadyJob& j) {
    {
      std::lock_guard lock(m);
      seen.push_back(j);
    }
    if (j.index == 1) d.SetPeriod(task, milliseconds(3));
  }));
  d.Start();
  ASSERT_TRUE(WaitFor([&] { return d.Stats(task).completed >= 6; }));
  d.Stop();
  std::lock_guard lock(m);
  ASSERT_GE(seen.size(), 6u);
  const ReadyJob& last = seen.back();
  const ReadyJob& before = seen[seen.size() - 2];
  EXPECT_EQ((last.release - before.release) / (last.index - before.index), milliseconds(3));
  EXPECT_EQ(last.deadline - last.release, milliseconds(3)) << "the implicit deadline follows";
}

TEST(EdfDispatcherTest, CpuTimeOfJobsIsChargedToTheirTask) {
  EdfDispatcher d(Workers(1));
  const int spin = d.AddTask(Task("spin", milliseconds(20), [](const ReadyJob&) {
    timespec ts{};
    auto cpu = [&ts] {
      clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
      return ts.tv_sec * 1'000'000'000LL + ts.tv_nsec;
    };
    const long long start = cpu();
    while (cpu() - start < 3'000'000) {
    }
  }));
  const int idle = d.AddTask(Task("idle", milliseconds(20), [](const ReadyJob&) {}));
  d.Start();
  ASSERT_TRUE(WaitFor([&] { return d.Stats(spin).completed >= 3 && d.Stats(idle).completed >= 3; }));
  d.Stop();
  const PeriodicTaskStats s = d.Stats(spin);
  EXPECT_GE(s.cpu_time, milliseconds(3) * s.completed) << "each job burns >= 3 ms of CPU";
  EXPECT_LT(d.Stats(idle).cpu_time, milliseconds(1) * d.Stats(idle).completed);
}

TEST(EdfDispatcherTest, WorkerHookRunsOncePerWorkerThread) {
  std::mutex m;
  std::set<int> indices;
  std::set<pid_t> tids;
  EdfDispatcher d(Workers(3, [&](int i) {
    std::lock_guard lock(m);
    indices.insert(i);
    tids.insert(gettid());
  }));
  d.Start();
  const std::vector<pid_t> worker_tids = d.WorkerTids();
  d.Stop();
  EXPECT_EQ(indices, (std::set<int>{0, 1, 2}));
  EXPECT_EQ(std::set<pid_t>(worker_tids.begin(), worker_tids.end()), tids);
  EXPECT_EQ(tids.count(getpid()), 0u) << "workers are their own kernel threads";
}

TEST(EdfDispatcherTest, BadTasksAreRefused) {
  EdfDispatcher d(Workers(1));
  const auto noop = [](const ReadyJob&) {};
  EXPECT_THROW(d.AddTask(Task("zero", milliseconds(0), noop)), std::invalid_argument);
  EXPECT_THROW(d.AddTask(Task("late", milliseconds(5), noop, milliseconds(0), milliseconds(6))),
               std::invalid_argument);
  EXPECT_THROW(d.AddTask(Task("nobody", milliseconds(5), nullptr)), std::invalid_argument);
  EXPECT_THROW(EdfDispatcher(Workers(0)), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack
