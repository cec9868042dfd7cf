// cgroup control against directory trees of plain files: detection, the files written, admission and
// reaping, without touching the kernel's cgroups.
#include <gtest/gtest.h>

#include "tests/unit/emulation/cgroup_test_util.h"
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "workers/emulation/cgroup_manager.h"

namespace enavi::emulation {
namespace {

namespace fs = std::filesystem;

using testing::ReadControlFile;

void Write(const fs::path& p, const std::string& value) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << value << "\n";
}

std::string OwnStartTime() {
  const std::string stat = ReadControlFile("/proc/self/stat");
  std::istringstream rest(stat.substr(stat.rfind(')') + 1));
  std::string field;
  for (int i = 3; i <= 22; ++i) rest >> field;
  return field;
}

// A pid that certainly belongs to no live process: a child that has been waited for.
pid_t DeadPid() {
  const pid_t child = fork();
  if (child == 0) _exit(0);
  int status = 0;
  waitpid(child, &status, 0);
  return child;
}

class PlainFilesCgroupTreeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/enavi-plain-cgroup-XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
    root_ = dir_ / "sys";
    fs::create_directories(root_);
    options_.root = root_;
    options_.self_cgroup_file = dir_ / "self_cgroup";
    options_.lock_file = dir_ / "lock";
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Hybrid host like the farm's: v1 cpu/cpuset/memory, an empty cgroup2 at unified/.
  void MakeV1(const std::string& cpus = "0-3") {
    Write(root_ / "cpu/cgroup.procs", "");
    Write(root_ / "cpu/cpu.cfs_quota_us", "-1");
    Write(root_ / "cpu/cpu.cfs_period_us", "100000");
    Write(root_ / "cpuset/cgroup.procs", "");
    Write(root_ / "cpuset/cpuset.cpus", cpus);
    Write(root_ / "cpuset/cpuset.mems", "0");
    Write(root_ / "memory/cgroup.procs", "");
    Write(root_ / "memory/memory.limit_in_bytes", "9223372036854771712");
    Write(root_ / "unified/cgroup.controllers", "");
    Write(root_ / "unified/cgroup.subtree_control", "");
    Write(options_.self_cgroup_file, "4:memory:/\n3:cpuset:/\n1:cpu:/\n0::/\n");
  }
  // Pure v2 with the worker in /worker and the controllers delegated to its subtree.
  void MakeV2(const std::string& subtree = "cpuset cpu memory") {
    Write(root_ / "cgroup.controllers", "cpuset cpu io memory pids");
    Write(root_ / "cgroup.subtree_control", "cpuset cpu io memory pids");
    Write(root_ / "worker/cgroup.procs", "");
    Write(root_ / "worker/cgroup.subtree_control", subtree);
    Write(root_ / "worker/cpuset.cpus.effective", "0-1");
    Write(options_.self_cgroup_file, "0::/worker\n");
  }

  fs::path dir_;
  fs::path root_;
  CgroupOptions options_;
};

TEST(CpuListTest, CountsRangesAndSingles) {
  EXPECT_EQ(CountCpuList("0-3"), 4);
  EXPECT_EQ(CountCpuList("0-2,5,8-9\n"), 6);
  EXPECT_EQ(CountCpuList(""), 0);
  EXPECT_EQ(CountCpuList("3-1"), -1);
  EXPECT_EQ(CountCpuList("a"), -1);
}

TEST_F(PlainFilesCgroupTreeTest, HybridHostWithoutV2ControllersUsesV1) {
  MakeV1();
  const CgroupLayout l = DetectCgroups(options_);
  ASSERT_EQ(l.version, CgroupVersion::kV1) << l.problem;
  EXPECT_EQ(l.cpu_base, (root_ / "cpu").string());
  EXPECT_EQ(l.cpuset_base, (root_ / "cpuset").string());
  EXPECT_EQ(l.memory_base, (root_ / "memory").string());
}

TEST_F(PlainFilesCgroupTreeTest, V2IsPreferredWhenItHasTheControllers) {
  MakeV1();
  Write(root_ / "unified/cgroup.controllers", "cpuset cpu memory");
  Write(root_ / "unified/cgroup.subtree_control", "cpuset cpu memory");
  const CgroupLayout l = DetectCgroups(options_);
  ASSERT_EQ(l.version, CgroupVersion::kV2) << l.problem;
  EXPECT_EQ(l.cpu_base, (root_ / "unified").string());
}

TEST_F(PlainFilesCgroupTreeTest, V2MissingMemoryFallsBackToV1) {
  MakeV1();
  Write(root_ / "unified/cgroup.controllers", "cpuset cpu");
  Write(root_ / "unified/cgroup.subtree_control", "cpuset cpu");
  EXPECT_EQ(DetectCgroups(options_).version, CgroupVersion::kV1);
  options_.use_memory = false;
  EXPECT_EQ(DetectCgroups(options_).version, CgroupVersion::kV2)
      << "without the memory requirement v2 qualifies";
}

TEST_F(PlainFilesCgroupTreeTest, PureV2UsesTheWorkersOwnCgroup) {
  MakeV2();
  const CgroupLayout l = DetectCgroups(options_);
  ASSERT_EQ(l.version, CgroupVersion::kV2) << l.problem;
  EXPECT_EQ(l.cpu_base, (root_ / "worker").string());
}

TEST_F(PlainFilesCgroupTreeTest, V1GroupsNestUnderTheWorkersOwnCgroups) {
  MakeV1();
  fs::create_directories(root_ / "memory/session/abc");
  Write(options_.self_cgroup_file, "4:memory:/session/abc\n3:cpuset:/\n1:cpu,cpuacct:/\n0::/\n");
  const CgroupLayout l = DetectCgroups(options_);
  ASSERT_EQ(l.version, CgroupVersion::kV1) << l.problem;
  EXPECT_EQ(l.memory_base, (root_ / "memory/session/abc").string());
  EXPECT_EQ(l.cpu_base, (root_ / "cpu").string()) << "combined 'cpu,cpuacct' line";
}

TEST_F(PlainFilesCgroupTreeTest, NothingUsableNamesWhatIsMissing) {
  Write(options_.self_cgroup_file, "0::/\n");
  const CgroupLayout l = DetectCgroups(options_);
  EXPECT_EQ(l.version, CgroupVersion::kNone);
  EXPECT_NE(l.problem.find("no unified hierarchy at " + root_.string()), std::string::npos)
      << l.problem;
  EXPECT_NE(l.problem.find("'cpu' controller"), std::string::npos) << l.problem;
  EXPECT_NE(l.problem.find("cpu.cfs_quota_us"), std::string::npos) << l.problem;
  const auto open = CgroupManager::Open(options_);
  EXPECT_FALSE(open.ok());
  EXPECT_NE(open.error.find("cgroup CPU emulation unavailable"), std::string::npos) << open.error;
}

TEST_F(PlainFilesCgroupTreeTest, V2WithoutDelegatedControllersSaysWhichFile) {
  MakeV2("pids");
  const CgroupLayout l = DetectCgroups(options_);
  EXPECT_EQ(l.version, CgroupVersion::kNone);
  EXPECT_NE(l.problem.find((root_ / "worker/cgroup.subtree_control").string()), std::string::npos)
      << l.problem;
  EXPECT_NE(l.problem.find("cpu cpuset memory"), std::string::npos) << l.problem;
}

TEST_F(PlainFilesCgroupTreeTest, UnprivilegedWorkerIsToldWhichPathIsNotWritable) {
  MakeV1();
  const auto read_only = fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                         fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec;
  for (const fs::path& p : {dir_, root_, root_ / "cpu", root_ / "cpuset", root_ / "memory"}) {
    fs::permissions(p, read_only);  // binds a normal user; root is dropped to nobody below
  }
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    if (geteuid() == 0 && setresuid(65534, 65534, 65534) != 0) _exit(10);
    const CgroupLayout l = DetectCgroups(options_);
    if (l.version != CgroupVersion::kNone) _exit(11);
    const std::string expected = (root_ / "cpu").string() + " is not writable by uid";
    if (l.problem.find(expected) == std::string::npos) _exit(12);
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  for (const fs::path& p : {dir_, root_, root_ / "cpu", root_ / "cpuset", root_ / "memory"}) {
    fs::permissions(p, fs::perms::owner_all);  // so TearDown can remove the tree
  }
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "10 setresuid, 11 detected usable, 12 message";
}

TEST_F(PlainFilesCgroupTreeTest, EpisodeGroupGetsQuotaCpusetAndMemoryAndIsRemoved) {
  MakeV1();
  auto open = CgroupManager::Open(options_);
  ASSERT_TRUE(open.ok()) << open.error;
  EXPECT_EQ(ReadControlFile(root_ / "cpu/enavi/cpu.shares"), "102400") << "parent weight 10000 -> shares";
  EXPECT_EQ(ReadControlFile(root_ / "cpuset/enavi/cpuset.cpus"), "0-3") << "copied from the worker's cpuset";
  EXPECT_EQ(ReadControlFile(root_ / "cpuset/enavi/cpuset.mems"), "0");

  QuotaOptions q;
  q.dilation = 2.0;
  const BoardQuota quota = ComputeBoardQuota({4, 0.5}, q);
  EpisodeLimits limits;
  limits.memory_bytes = 1LL << 30;
  auto created = open.manager->CreateEpisode(quota, limits);
  ASSERT_TRUE(created.ok()) << created.refusal;
  const std::string name = created.group->name();
  EXPECT_EQ(name.rfind("ep-" + std::to_string(getpid()) + "-" + OwnStartTime() + "-", 0), 0u) << name;
  const fs::path cpu = root_ / "cpu/enavi" / name;
  EXPECT_EQ(created.group->cpu_dir(), cpu.string());
  EXPECT_EQ(ReadControlFile(cpu / "cpu.cfs_period_us"), "20000");
  EXPECT_EQ(ReadControlFile(cpu / "cpu.cfs_quota_us"), "20000") << "4 x 0.5 / 2 = 1.0 CPU";
  EXPECT_EQ(ReadControlFile(root_ / "cpuset/enavi" / name / "cpuset.cpus"), "0-3");
  EXPECT_EQ(ReadControlFile(root_ / "cpuset/enavi" / name / "cpuset.mems"), "0");
  EXPECT_EQ(ReadControlFile(root_ / "memory/enavi" / name / "memory.limit_in_bytes"), "1073741824");

  ASSERT_TRUE(created.group->AddProcess(4242).ok);
  EXPECT_EQ(ReadControlFile(cpu / "cgroup.procs"), "4242");
  EXPECT_EQ(ReadControlFile(root_ / "memory/enavi" / name / "cgroup.procs"), "4242");
  ASSERT_TRUE(created.group->AddThread(4243).ok);
  EXPECT_EQ(ReadControlFile(cpu / "t-4243/cpu.cfs_quota_us"), "5000") << "one core: 0.5 / 2 of 20 ms";
  EXPECT_EQ(ReadControlFile(cpu / "t-4243/tasks"), "4243");

  const CgroupStatus removed = created.group->Remove();
  EXPECT_TRUE(removed.ok) << removed.message;
  EXPECT_FALSE(fs::exists(cpu));
  EXPECT_FALSE(fs::exists(root_ / "memory/enavi" / name));
  EXPECT_TRUE(fs::exists(root_ / "cpu/enavi")) << "the parent stays while the manager lives";
  open.manager.reset();
  EXPECT_FALSE(fs::exists(root_ / "cpu/enavi"));
  EXPECT_FALSE(fs::exists(root_ / "cpuset/enavi"));
  EXPECT_FALSE(fs::exists(root_ / "memory/enavi"));
}

TEST_F(PlainFilesCgroupTreeTest, SweepGivesEveryThreadOfTheBoardGroupItsOwnGroup) {
  MakeV1();
  auto open = CgroupManager::Open(options_);
  ASSERT_TRUE(open.ok()) << open.error;
  auto created = open.manager->CreateEpisode(ComputeBoardQuota({2, 0.3}, {}));
  ASSERT_TRUE(created.ok()) << created.refusal;
  const fs::path cpu = created.group->cpu_dir();
  Write(cpu / "tasks", "101\n102");
  CgroupStatus status;
  EXPECT_EQ(created.group->SweepThreads(&status), 2);
  EXPECT_TRUE(status.ok) << status.message;
  for (const char* t : {"t-101", "t-102"}) {
    EXPECT_EQ(ReadControlFile(cpu / t / "cpu.cfs_quota_us"), "6000") << t;
    EXPECT_EQ(ReadControlFile(cpu / t / "cpu.cfs_period_us"), "20000") << t;
  }
}

TEST_F(PlainFilesCgroupTreeTest, V2EpisodeUsesCpuMaxAndThreadedChildren) {
  MakeV2();
  auto open = CgroupManager::Open(options_);
  ASSERT_TRUE(open.ok()) << open.error;
  EXPECT_EQ(ReadControlFile(root_ / "worker/enavi/cgroup.subtree_control"), "+cpu +cpuset +memory");
  EXPECT_EQ(ReadControlFile(root_ / "worker/enavi/cpu.weight"), "10000");
  EpisodeLimits limits;
  limits.cpus = "1";
  limits.memory_bytes = 512LL << 20;
  auto created = open.manager->CreateEpisode(ComputeBoardQuota({3, 0.4}, {}), limits);
  ASSERT_TRUE(created.ok()) << created.refusal;
  const fs::path ep = created.group->cpu_dir();
  EXPECT_EQ(ep.parent_path(), root_ / "worker/enavi");
  EXPECT_EQ(ReadControlFile(ep / "cpu.max"), "24000 20000");
  EXPECT_EQ(ReadControlFile(ep / "cpuset.cpus"), "1");
  EXPECT_EQ(ReadControlFile(ep / "memory.max"), "536870912");
  ASSERT_TRUE(created.group->AddThread(77).ok);
  EXPECT_EQ(ReadControlFile(ep / "t-77/cgroup.type"), "threaded");
  EXPECT_EQ(ReadControlFile(ep / "cgroup.subtree_control"), "+cpu");
  EXPECT_EQ(ReadControlFile(ep / "t-77/cpu.max"), "8000 20000");
  EXPECT_EQ(ReadControlFile(ep / "t-77/cgroup.threads"), "77");
}

TEST_F(PlainFilesCgroupTreeTest, AdmissionRefusesWhatTheHostCannotHold) {
  MakeV1("0-1");  // 2 CPUs, 0.25 kept for the simulator
  auto open = CgroupManager::Open(options_);
  ASSERT_TRUE(open.ok()) << open.error;
  EXPECT_DOUBLE_EQ(open.manager->HostCpus(), 2.0);
  auto first = open.manager->CreateEpisode(ComputeBoardQuota({5, 0.3}, {}));  // 1.5 CPUs
  ASSERT_TRUE(first.ok()) << first.refusal;
  EXPECT_DOUBLE_EQ(open.manager->ReservedCpus(), 1.5);
  auto second = open.manager->CreateEpisode(ComputeBoardQuota({2, 0.25}, {}));  // 0.5 CPUs
  ASSERT_FALSE(second.ok());
  EXPECT_NE(second.refusal.find("admission refused"), std::string::npos) << second.refusal;
  EXPECT_NE(second.refusal.find("1.500 held by running emulations"), std::string::npos)
      << second.refusal;
  first.group.reset();
  auto third = open.manager->CreateEpisode(ComputeBoardQuota({2, 0.25}, {}));
  EXPECT_TRUE(third.ok()) << "the reservation ends with the group: " << third.refusal;
}

TEST_F(PlainFilesCgroupTreeTest, ReaperRemovesOnlyGroupsOfWorkersThatAreGone) {
  MakeV1();
  const std::string dead = "ep-" + std::to_string(DeadPid()) + "-5-0";
  const std::string reused = "ep-" + std::to_string(getpid()) + "-1-0";  // our pid, other start
  const std::string live = "ep-" + std::to_string(getpid()) + "-" + OwnStartTime() + "-900";
  for (const char* h : {"cpu", "cpuset", "memory"}) {
    for (const std::string& n : {dead, reused, live}) fs::create_directories(root_ / h / "enavi" / n);
  }
  fs::create_directories(root_ / "cpu/enavi" / dead / "t-77");
  Write(root_ / "cpu/enavi" / dead / "cpu.cfs_quota_us", "5000");
  fs::create_directories(root_ / "cpu/enavi/not-an-episode");

  auto open = CgroupManager::Open(options_);  // reaps
  ASSERT_TRUE(open.ok()) << open.error;
  EXPECT_EQ(open.reaped.size(), 2u);
  EXPECT_TRUE(open.reap_errors.empty()) << open.reap_errors;
  for (const char* h : {"cpu", "cpuset", "memory"}) {
    EXPECT_FALSE(fs::exists(root_ / h / "enavi" / dead)) << h;
    EXPECT_FALSE(fs::exists(root_ / h / "enavi" / reused)) << h << ": pid reused by another process";
    EXPECT_TRUE(fs::exists(root_ / h / "enavi" / live)) << h << ": its worker (we) is alive";
  }
  EXPECT_TRUE(fs::exists(root_ / "cpu/enavi/not-an-episode")) << "never touch what is not ours";
  EXPECT_TRUE(open.manager->ReapStale().empty()) << "nothing left to reap";
}

}  // namespace
}  // namespace enavi::emulation
