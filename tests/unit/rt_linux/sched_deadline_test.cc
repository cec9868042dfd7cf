#include "navstack/runtime/sched_deadline.h"

#include <gtest/gtest.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <barrier>
#include <cerrno>
#include <stdexcept>
#include <thread>
#include <vector>

namespace enavi::navstack {
namespace {

constexpr int kSchedOther = 0;
constexpr int kSchedDeadline = 6;

// Runs fn on a fresh thread, so scheduling changes never leak into the test runner's thread.
template <typename Fn>
void OnFreshThread(Fn fn) {
  std::thread t(fn);
  t.join();
}

bool AffinitySpansAllCpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) != 0) return false;
  return CPU_COUNT(&set) == static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));
}

TEST(SchedDeadlineTest, SpeedServerRuntimeIsRateTimesPeriod) {
  const DeadlineParams p = SpeedServerParams(0.3, 10'000'000);
  EXPECT_EQ(p.runtime_ns, 3'000'000);
  EXPECT_EQ(p.deadline_ns, 10'000'000);
  EXPECT_EQ(p.period_ns, 10'000'000);
}

TEST(SchedDeadlineTest, BadParamsAreRefusedWithInvalidArgument) {
  EXPECT_THROW(SpeedServerParams(1.5), std::invalid_argument);
  EXPECT_THROW(SpeedServerParams(0.5, 50'000), std::invalid_argument);
}

TEST(SchedDeadlineTest, RootThreadEntersDeadlineAndKernelReportsIt) {
  if (geteuid() != 0) GTEST_SKIP() << "SCHED_DEADLINE needs root (CAP_SYS_NICE)";
  if (!AffinitySpansAllCpus()) GTEST_SKIP() << "test runs with a narrowed CPU affinity";
  OnFreshThread([] {
    const DeadlineParams asked = SpeedServerParams(0.25, 20'000'000);
    const DeadlineResult r = EnterDeadline(asked);
    ASSERT_TRUE(r.deadline) << r.reason;
    EXPECT_EQ(r.error, 0);
    EXPECT_TRUE(r.reason.empty());
    const auto attr = GetSchedAttr(0);
    ASSERT_TRUE(attr.has_value()) << "sched_getattr failed, errno " << errno;
    EXPECT_EQ(attr->policy, kSchedDeadline);
    EXPECT_EQ(attr->runtime_ns, asked.runtime_ns);
    EXPECT_EQ(attr->deadline_ns, asked.deadline_ns);
    EXPECT_EQ(attr->period_ns, asked.period_ns);
    ASSERT_TRUE(EnterOther());
    EXPECT_EQ(GetSchedAttr(0)->policy, kSchedOther);
  });
}

TEST(SchedDeadlineTest, RuntimeLongerThanDeadlineFallsBackToOther) {
  OnFreshThread([] {
    DeadlineParams bad;
    bad.runtime_ns = 20'000'000;
    bad.deadline_ns = 10'000'000;
    bad.period_ns = 10'000'000;
    const DeadlineResult r = EnterDeadline(bad);
    EXPECT_FALSE(r.deadline);
    EXPECT_EQ(r.error, EINVAL);
    EXPECT_NE(r.reason.find("EINVAL"), std::string::npos) << r.reason;
    EXPECT_NE(r.reason.find("SCHED_OTHER"), std::string::npos) << r.reason;
    EXPECT_EQ(GetSchedAttr(0)->policy, kSchedOther);
  });
}

TEST(SchedDeadlineTest, FailedChangeOfADeadlineThreadReturnsItToOther) {
  if (geteuid() != 0) GTEST_SKIP() << "SCHED_DEADLINE needs root (CAP_SYS_NICE)";
  if (!AffinitySpansAllCpus()) GTEST_SKIP() << "test runs with a narrowed CPU affinity";
  OnFreshThread([] {
    ASSERT_TRUE(EnterDeadline(SpeedServerParams(0.2)).deadline);
    DeadlineParams bad = SpeedServerParams(0.2);
    bad.runtime_ns = bad.deadline_ns + 1;
    const DeadlineResult r = EnterDeadline(bad);
    EXPECT_FALSE(r.deadline);
    EXPECT_EQ(GetSchedAttr(0)->policy, kSchedOther)
        << "the kernel keeps the old DL policy on refusal; the fallback must leave it";
  });
}

TEST(SchedDeadlineTest, UnprivilegedAttemptIsRefusedWithEpermAndReported) {
  // Drop to nobody in a child process (as root), or just try (as a normal user).
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    if (geteuid() == 0 && setresuid(65534, 65534, 65534) != 0) _exit(10);
    const DeadlineResult r = EnterDeadline(SpeedServerParams(0.1));
    if (r.deadline) _exit(11);
    if (r.error != EPERM) _exit(12);
    if (r.reason.find("CAP_SYS_NICE") == std::string::npos) _exit(13);
    if (GetSchedAttr(0)->policy != kSchedOther) _exit(14);
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0)
      << "10 setresuid failed, 11 DL granted, 12 errno not EPERM, 13 reason, 14 policy";
}

TEST(SchedDeadlineTest, AffinityNarrowerThanRootDomainIsRefusedWithEperm) {
  if (geteuid() != 0) GTEST_SKIP() << "SCHED_DEADLINE needs root (CAP_SYS_NICE)";
  if (sysconf(_SC_NPROCESSORS_ONLN) < 2) GTEST_SKIP() << "needs >= 2 CPUs";
  if (!AffinitySpansAllCpus()) GTEST_SKIP() << "test runs with a narrowed CPU affinity";
  OnFreshThread([] {
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(0, &one);
    ASSERT_EQ(sched_setaffinity(0, sizeof(one), &one), 0);
    const DeadlineResult r = EnterDeadline(SpeedServerParams(0.1));
    EXPECT_FALSE(r.deadline) << "a DL task must be free to run on its whole root domain";
    EXPECT_EQ(r.error, EPERM);
    EXPECT_NE(r.reason.find("root domain"), std::string::npos) << r.reason;
  });
}

TEST(SchedDeadlineTest, AdmissionControlRefusalIsReportedAsBusy) {
  if (geteuid() != 0) GTEST_SKIP() << "SCHED_DEADLINE needs root (CAP_SYS_NICE)";
  if (!AffinitySpansAllCpus()) GTEST_SKIP() << "test runs with a narrowed CPU affinity";
  // ncpu + 1 reservations of 90 % each can never fit under the 95 % per-CPU DL limit.
  const int n = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN)) + 1;
  std::atomic<int> granted{0};
  std::atomic<int> busy{0};
  std::string busy_reason;
  std::mutex reason_mutex;
  std::barrier all_asked(n);
  std::vector<std::thread> threads;
  for (int i = 0; i < n; ++i) {
    threads.emplace_back([&] {
      DeadlineOptions options;
      options.ebusy_retries = 0;
      const DeadlineResult r = EnterDeadline(SpeedServerParams(0.9, 100'000'000), options);
      if (r.deadline) ++granted;
      if (!r.deadline && r.error == EBUSY) {
        ++busy;
        std::lock_guard lock(reason_mutex);
        busy_reason = r.reason;
      }
      all_asked.arrive_and_wait();  // hold the reservations until everyone has asked
      EnterOther();
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_GE(busy.load(), 1) << "granted " << granted.load() << " of " << n;
  EXPECT_NE(busy_reason.find("admission"), std::string::npos) << busy_reason;
}

}  // namespace
}  // namespace enavi::navstack
