// cgroup control against the running kernel (root only; skipped otherwise). Every test leaves
// no cgroup with "enavi" in its name behind, checked in TearDown, also when it fails.
#include <gtest/gtest.h>

#include "tests/unit/emulation/cgroup_test_util.h"
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "workers/emulation/cgroup_manager.h"

namespace enavi::emulation {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;

using testing::ReadControlFile;

// Every directory with "enavi" in its name under /sys/fs/cgroup.
std::vector<std::string> EnaviCgroups() {
  std::vector<std::string> found;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator("/sys/fs/cgroup",
                                                  fs::directory_options::skip_permission_denied, ec);
       it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (ec) break;
    if (it->is_directory(ec) && it->path().filename().string().find("enavi") != std::string::npos) {
      found.push_back(it->path().string());
    }
  }
  return found;
}

// CPU seconds a process has used (schedstat of its threads, ns resolution).
double ProcessCpuSeconds(pid_t pid) {
  double total = 0;
  for (const auto& task : fs::directory_iterator("/proc/" + std::to_string(pid) + "/task")) {
    std::ifstream in(task.path() / "schedstat");
    long long ns = 0;
    if (in >> ns) total += static_cast<double>(ns) * 1e-9;
  }
  return total;
}

// A child that spins on `threads` threads until killed; it starts spinning only when `go`
// gets a byte, so it can be placed first.
struct BusyChild {
  pid_t pid = -1;
  int go = -1;
};

[[noreturn]] void Spin() {
  volatile unsigned long x = 0;
  while (true) x = x + 1;
}

BusyChild SpawnBusy(int threads) {
  int fds[2];
  if (pipe(fds) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[1]);
    char c;
    if (read(fds[0], &c, 1) != 1) _exit(3);
    std::vector<std::thread> spin;
    for (int i = 1; i < threads; ++i) {
      spin.emplace_back(Spin);
    }
    Spin();
  }
  close(fds[0]);
  return {pid, fds[1]};
}

void Go(BusyChild& c) {
  const char byte = 1;
  ASSERT_EQ(write(c.go, &byte, 1), 1);
  close(c.go);
  c.go = -1;
}

void KillAndReap(pid_t pid) {
  if (pid <= 0) return;
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
}

class KernelCgroupTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (geteuid() != 0) GTEST_SKIP() << "needs root to create cgroups";
    const CgroupLayout layout = DetectCgroups();
    if (layout.version == CgroupVersion::kNone) {
      GTEST_SKIP() << "no usable cgroup hierarchy: " << layout.problem;
    }
    ASSERT_TRUE(EnaviCgroups().empty()) << "leftover enavi cgroups before the test";
  }
  void TearDown() override {
    for (pid_t p : children_) KillAndReap(p);
    if (geteuid() != 0) return;
    EXPECT_TRUE(EnaviCgroups().empty()) << "cgroups left behind: " << EnaviCgroups().front();
    // Last resort so one failing test does not poison the next: reap through a fresh manager.
    if (!EnaviCgroups().empty()) CgroupManager::Open();
  }

  std::vector<pid_t> children_;
};

TEST_F(KernelCgroupTest, EpisodeGroupIsCreatedWithItsQuotaAndRemoved) {
  auto open = CgroupManager::Open();
  ASSERT_TRUE(open.ok()) << open.error;
  const BoardQuota quota = ComputeBoardQuota({4, 0.3}, {});
  EpisodeLimits limits;
  limits.memory_bytes = 256LL << 20;
  auto created = open.manager->CreateEpisode(quota, limits);
  ASSERT_TRUE(created.ok()) << created.refusal;
  const fs::path cpu = created.group->cpu_dir();
  ASSERT_TRUE(fs::is_directory(cpu));
  if (open.manager->layout().version == CgroupVersion::kV1) {
    EXPECT_EQ(ReadControlFile(cpu / "cpu.cfs_quota_us"), "24000");
    EXPECT_EQ(ReadControlFile(cpu / "cpu.cfs_period_us"), "20000");
    EXPECT_EQ(ReadControlFile(fs::path(open.manager->layout().memory_base) / "enavi" / created.group->name() /
                   "memory.limit_in_bytes"),
              "268435456");
  } else {
    EXPECT_EQ(ReadControlFile(cpu / "cpu.max"), "24000 20000");
  }
  EXPECT_NEAR(open.manager->ReservedCpus(), 1.2, 1e-9);
  const CgroupStatus removed = created.group->Remove();
  EXPECT_TRUE(removed.ok) << removed.message;
  EXPECT_FALSE(fs::exists(cpu));
}

TEST_F(KernelCgroupTest, SingleThreadRunsAtOneSlowCoreEvenOnAManyCoreBoard) {
  // 6 cores x 0.25: the board may use 1.5 host CPUs, but one thread only 0.25 of one.
  auto open = CgroupManager::Open();
  ASSERT_TRUE(open.ok()) << open.error;
  auto created = open.manager->CreateEpisode(ComputeBoardQuota({6, 0.25}, {}));
  ASSERT_TRUE(created.ok()) << created.refusal;
  BusyChild child = SpawnBusy(1);
  children_.push_back(child.pid);
  ASSERT_TRUE(created.group->AddProcess(child.pid).ok);
  EXPECT_EQ(created.group->SweepThreads(), 1);
  Go(child);
  std::this_thread::sleep_for(milliseconds(200));  // settle
  const double cpu0 = ProcessCpuSeconds(child.pid);
  const auto t0 = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(milliseconds(1200));
  const double share = (ProcessCpuSeconds(child.pid) - cpu0) /
                       std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_NEAR(share, 0.25, 0.05) << "a busy thread must be held to one board core's speed";
}

TEST_F(KernelCgroupTest, BoardCapBindsManyThreads) {
  // 2 cores x 0.3 = 0.6 host CPUs for 4 spinning threads (each could have 0.3).
  auto open = CgroupManager::Open();
  ASSERT_TRUE(open.ok()) << open.error;
  auto created = open.manager->CreateEpisode(ComputeBoardQuota({2, 0.3}, {}));
  ASSERT_TRUE(created.ok()) << created.refusal;
  BusyChild child = SpawnBusy(4);
  children_.push_back(child.pid);
  ASSERT_TRUE(created.group->AddProcess(child.pid).ok);
  Go(child);
  std::this_thread::sleep_for(milliseconds(100));  // threads exist now: give each its group
  created.group->SweepThreads();
  std::this_thread::sleep_for(milliseconds(200));
  const double cpu0 = ProcessCpuSeconds(child.pid);
  const auto t0 = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(milliseconds(1200));
  const double share = (ProcessCpuSeconds(child.pid) - cpu0) /
                       std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_NEAR(share, 0.6, 0.08);
  EXPECT_GT(created.group->ReadCpuStat().nr_throttled, 0) << "the board group itself throttled";
}

TEST_F(KernelCgroupTest, RemoveKillsTheNavstackStillInside) {
  auto open = CgroupManager::Open();
  ASSERT_TRUE(open.ok()) << open.error;
  auto created = open.manager->CreateEpisode(ComputeBoardQuota({2, 0.3}, {}));
  ASSERT_TRUE(created.ok()) << created.refusal;
  BusyChild child = SpawnBusy(2);
  ASSERT_TRUE(created.group->AddProcess(child.pid).ok);
  Go(child);
  const CgroupStatus removed = created.group->Remove();
  EXPECT_TRUE(removed.ok) << removed.message;
  int status = 0;
  ASSERT_EQ(waitpid(child.pid, &status, 0), child.pid);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
}

TEST_F(KernelCgroupTest, GroupIsRemovedAfterSigkillOfTheProcessInside) {
  auto open = CgroupManager::Open();
  ASSERT_TRUE(open.ok()) << open.error;
  auto created = open.manager->CreateEpisode(ComputeBoardQuota({2, 0.3}, {}));
  ASSERT_TRUE(created.ok()) << created.refusal;
  BusyChild child = SpawnBusy(2);
  ASSERT_TRUE(created.group->AddProcess(child.pid).ok);
  created.group->SweepThreads();
  Go(child);
  std::this_thread::sleep_for(milliseconds(50));
  kill(child.pid, SIGKILL);  // the navstack crashes; the worker is alive and cleans up
  int status = 0;
  ASSERT_EQ(waitpid(child.pid, &status, 0), child.pid);
  const CgroupStatus removed = created.group->Remove();
  EXPECT_TRUE(removed.ok) << removed.message;
  EXPECT_FALSE(fs::exists(created.group->cpu_dir()));
}

TEST_F(KernelCgroupTest, ReaperRemovesGroupsOfAWorkerKilledBySigkill) {
  // A worker process creates an episode with a busy navstack inside and is SIGKILLed. The
  // orphaned navstack keeps spinning in the stale group until the next worker reaps it.
  ASSERT_EQ(prctl(PR_SET_CHILD_SUBREAPER, 1), 0);  // orphans come to us, not to init
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t worker = fork();
  ASSERT_GE(worker, 0);
  if (worker == 0) {
    close(ready[0]);
    auto open = CgroupManager::Open();
    if (!open.ok()) _exit(2);
    auto created = open.manager->CreateEpisode(ComputeBoardQuota({2, 0.3}, {}));
    if (!created.ok()) _exit(3);
    BusyChild navstack = SpawnBusy(2);
    if (!created.group->AddProcess(navstack.pid).ok) _exit(4);
    Go(navstack);
    const pid_t p = navstack.pid;
    if (write(ready[1], &p, sizeof(p)) != sizeof(p)) _exit(5);
    pause();
    _exit(0);
  }
  children_.push_back(worker);
  close(ready[1]);
  pid_t navstack = -1;
  ASSERT_EQ(read(ready[0], &navstack, sizeof(navstack)), static_cast<ssize_t>(sizeof(navstack)));
  close(ready[0]);
  children_.push_back(navstack);
  ASSERT_FALSE(EnaviCgroups().empty());
  KillAndReap(worker);
  ASSERT_EQ(kill(navstack, 0), 0) << "the orphan is still running";

  auto open = CgroupManager::Open();  // reaps at start
  ASSERT_TRUE(open.ok()) << open.error;
  EXPECT_EQ(open.reaped.size(), 1u) << open.reap_errors;
  int status = 0;
  ASSERT_EQ(waitpid(navstack, &status, 0), navstack) << "the reaper killed the orphan";
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
  open.manager.reset();
  prctl(PR_SET_CHILD_SUBREAPER, 0);
  EXPECT_TRUE(EnaviCgroups().empty());
}

TEST_F(KernelCgroupTest, OwnThreadGoesHomeInsteadOfBeingKilled) {
  if (DetectCgroups().version != CgroupVersion::kV1) GTEST_SKIP() << "per-thread moves are v1";
  auto open = CgroupManager::Open();
  ASSERT_TRUE(open.ok()) << open.error;
  auto created = open.manager->CreateEpisode(ComputeBoardQuota({2, 0.5}, {}));
  ASSERT_TRUE(created.ok()) << created.refusal;
  std::atomic<bool> stop{false};
  std::atomic<pid_t> tid{0};
  std::thread helper([&] {
    tid = gettid();
    while (!stop) std::this_thread::sleep_for(milliseconds(1));
  });
  while (tid == 0) std::this_thread::yield();
  ASSERT_TRUE(created.group->AddThread(tid).ok);
  const std::string in_group = ReadControlFile("/proc/self/task/" + std::to_string(tid) + "/cgroup");
  EXPECT_NE(in_group.find(created.group->name()), std::string::npos) << in_group;
  const CgroupStatus removed = created.group->Remove();
  EXPECT_TRUE(removed.ok) << removed.message;
  const std::string after = ReadControlFile("/proc/self/task/" + std::to_string(tid) + "/cgroup");
  EXPECT_EQ(after.find("enavi"), std::string::npos) << after;
  stop = true;
  helper.join();
}

TEST_F(KernelCgroupTest, SecondBoardIsRefusedWhenTheHostIsFull) {
  auto open = CgroupManager::Open();
  ASSERT_TRUE(open.ok()) << open.error;
  const double free_cpus = open.manager->HostCpus() - 0.25;
  QuotaOptions o;
  o.period_us = 20'000;
  auto big = open.manager->CreateEpisode(ComputeBoardQuota({1, 1.0}, o));
  ASSERT_TRUE(big.ok()) << big.refusal;
  auto rest = open.manager->CreateEpisode(
      ComputeBoardQuota({static_cast<int>(free_cpus * 2), 0.5}, o));  // ~free_cpus, > what is left
  ASSERT_FALSE(rest.ok());
  EXPECT_NE(rest.refusal.find("admission refused"), std::string::npos) << rest.refusal;
}

}  // namespace
}  // namespace enavi::emulation
