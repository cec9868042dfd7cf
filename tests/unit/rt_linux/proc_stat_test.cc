#include "navstack/runtime/proc_stat.h"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <future>
#include <thread>

namespace enavi::navstack {
namespace {

TEST(ProcStatTest, CpuPercentIsCpuOverWallInPercentOfOneCore) {
  ThreadCpuTimes a, b;
  a.sum_exec_ns = 1'000'000'000;
  a.sampled_ns = 5'000'000'000;
  b.sum_exec_ns = 1'750'000'000;
  b.sampled_ns = 6'000'000'000;
  EXPECT_DOUBLE_EQ(CpuPercent(a, b), 75.0);
  EXPECT_DOUBLE_EQ(CpuPercent(a, a), 0.0) << "no elapsed time -> 0, not a division by zero";
}

TEST(ProcStatTest, FallsBackToClockTicksWithoutSchedstat) {
  ThreadCpuTimes a, b;
  a.sampled_ns = 0;
  b.sampled_ns = 2'000'000'000;
  const long hz = sysconf(_SC_CLK_TCK);
  b.utime_ticks = static_cast<std::uint64_t>(hz);  // 1 s user
  b.stime_ticks = 0;
  b.sum_exec_ns = 123;  // ignored: a has no schedstat
  EXPECT_NEAR(CpuPercent(a, b), 50.0, 1e-9);
}

TEST(ProcStatTest, ReadsNameWithSpacesAndParentheses) {
  std::promise<void> done;
  std::promise<pid_t> tid;
  std::thread t([&] {
    pthread_setname_np(pthread_self(), "a) b (c");
    tid.set_value(gettid());
    done.get_future().wait();
  });
  const pid_t id = tid.get_future().get();
  const auto times = ReadThreadCpu(getpid(), id);
  done.set_value();
  t.join();
  ASSERT_TRUE(times.has_value());
  EXPECT_EQ(times->comm, "a) b (c");
  EXPECT_EQ(times->tid, id);
}

TEST(ProcStatTest, StatLineFieldsCountFromTheLastParenthesis) {
  const auto line = ParseProcStatLine("42 (a) b (c) S 1 2 3");
  ASSERT_TRUE(line.has_value());
  EXPECT_EQ(line->comm, "a) b (c");
  ASSERT_NE(line->Field(3), nullptr);
  EXPECT_EQ(*line->Field(3), "S");
  ASSERT_NE(line->Field(6), nullptr);
  EXPECT_EQ(*line->Field(6), "3");
  EXPECT_EQ(line->Field(7), nullptr) << "past the end of the line";
  EXPECT_EQ(line->Field(2), nullptr) << "the name is not a field of the list";
  EXPECT_FALSE(ParseProcStatLine("42 no name S 1").has_value());
}

TEST(ProcStatTest, StartTimeNamesALiveProcessAndNotAZombie) {
  const auto self = ProcessStartTime(getpid());
  ASSERT_TRUE(self.has_value());
  EXPECT_EQ(ProcessStartTime(getpid()), self) << "the start time of a process does not change";
  EXPECT_FALSE(ProcessStartTime(0x7ffffff0).has_value());
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) _exit(0);
  // Until it is reaped the child is a zombie: gone for the purpose of owning a cgroup.
  bool zombie = false;
  for (int i = 0; i < 500 && !zombie; ++i) {
    zombie = !ProcessStartTime(child).has_value();
    if (!zombie) usleep(1000);
  }
  EXPECT_TRUE(zombie);
  int status = 0;
  waitpid(child, &status, 0);
}

TEST(ProcStatTest, ThreadGroupOfAThreadIsItsProcess) {
  std::promise<pid_t> tid;
  std::promise<void> done;
  std::thread t([&] {
    tid.set_value(gettid());
    done.get_future().wait();
  });
  const pid_t id = tid.get_future().get();
  const pid_t group = ThreadGroupOf(id);
  done.set_value();
  t.join();
  EXPECT_NE(id, getpid());
  EXPECT_EQ(group, getpid());
  EXPECT_EQ(ThreadGroupOf(0x7ffffff0), 0);
}

TEST(ProcStatTest, MissingThreadIsNullopt) {
  EXPECT_FALSE(ReadThreadCpu(getpid(), 0x7ffffff0).has_value());
  EXPECT_TRUE(ListThreads(0x7ffffff0).empty());
}

TEST(ProcStatTest, BusyThreadAgreesWithKernelAccountingAndIsNearOneCore) {
  std::promise<pid_t> tid2;
  std::atomic<bool> stop2{false};
  std::thread busy2([&] {
    tid2.set_value(gettid());
    volatile std::uint64_t x = 0;
    while (!stop2.load()) x = x + 1;
  });
  const pid_t id2 = tid2.get_future().get();
  const auto s0 = ReadThreadCpu(getpid(), id2);
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  const auto s1 = ReadThreadCpu(getpid(), id2);
  stop2 = true;
  busy2.join();
  ASSERT_TRUE(s0 && s1);
  const double pct = CpuPercent(*s0, *s1);
  // The CPU share of a spinning thread depends on host load; what it did not run it waited
  // for a CPU, so running + waiting covers the whole interval (100 % on an idle host).
  const double cpu = s1->CpuSeconds() - s0->CpuSeconds();
  const double wall = static_cast<double>(s1->sampled_ns - s0->sampled_ns) * 1e-9;
  EXPECT_NEAR(pct, 100.0 * cpu / wall, 1e-6);
  const double wait = WaitPercent(*s0, *s1);
  ASSERT_GE(wait, 0.0) << "kernel without schedstat";
  EXPECT_NEAR(pct + wait, 100.0, 5.0) << "cpu " << pct << " % + waiting " << wait << " %";
  EXPECT_LE(pct, 101.0) << "one thread cannot use more than one core";
}

TEST(ProcStatTest, SleepingThreadIsNearZero) {
  std::promise<pid_t> tid;
  std::promise<void> go;
  std::thread idle([&] {
    tid.set_value(gettid());
    go.get_future().wait();
  });
  const pid_t id = tid.get_future().get();
  const auto s0 = ReadThreadCpu(getpid(), id);
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  const auto s1 = ReadThreadCpu(getpid(), id);
  go.set_value();
  idle.join();
  ASSERT_TRUE(s0 && s1);
  EXPECT_LT(CpuPercent(*s0, *s1), 2.0);
}

TEST(ProcStatTest, MonitorSeparatesBusyAndIdleThreadsOfAProcess) {
  std::atomic<bool> stop{false};
  std::promise<pid_t> busy_tid, idle_tid;
  std::thread busy([&] {
    pthread_setname_np(pthread_self(), "enavi-busy");
    busy_tid.set_value(gettid());
    volatile std::uint64_t x = 0;
    while (!stop.load()) x = x + 1;
  });
  std::thread idle([&] {
    pthread_setname_np(pthread_self(), "enavi-idle");
    idle_tid.set_value(gettid());
    while (!stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  });
  const pid_t b = busy_tid.get_future().get();
  const pid_t i = idle_tid.get_future().get();
  ThreadCpuMonitor monitor(getpid());
  EXPECT_TRUE(monitor.Sample().empty()) << "the first sample only sets the baseline";
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  const auto util = monitor.Sample();
  stop = true;
  busy.join();
  idle.join();
  double busy_pct = -1, busy_wait = -1, idle_pct = -1;
  for (const ThreadUtilisation& u : util) {
    if (u.tid == b) {
      busy_pct = u.percent;
      busy_wait = u.wait_percent;
      EXPECT_EQ(u.comm, "enavi-busy");
    }
    if (u.tid == i) idle_pct = u.percent;
  }
  ASSERT_GE(busy_pct, 0.0) << "busy thread not reported";
  ASSERT_GE(idle_pct, 0.0) << "idle thread not reported";
  EXPECT_NEAR(busy_pct + busy_wait, 100.0, 5.0) << "busy: running or waiting all the time";
  EXPECT_LT(idle_pct, 5.0);
  EXPECT_GE(monitor.TotalPercent(), busy_pct + idle_pct - 1e-9);
}

}  // namespace
}  // namespace enavi::navstack
