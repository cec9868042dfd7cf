#include "workers/worker/process.h"

#include <signal.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>

namespace enavi::worker {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

class ProcessTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("process_test-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs `sh -c script` to completion and returns its status and stdout.
  std::pair<ExitStatus, std::string> Sh(const std::string& script, SpawnOptions o = {}) {
    o.argv = {"/bin/sh", "-c", script};
    o.stdout_file = dir_ / "out.txt";
    ChildProcess child = ChildProcess::Spawn(o);
    const auto status = child.Wait(std::chrono::milliseconds::max());
    std::ifstream in(dir_ / "out.txt");
    std::string out((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return {*status, out};
  }

  fs::path dir_;
};

TEST_F(ProcessTest, ExitCodeAndOutputAreCaptured) {
  const auto [status, out] = Sh("echo hello; exit 3");
  EXPECT_TRUE(status.exited);
  EXPECT_EQ(status.code, 3);
  EXPECT_FALSE(status.ok());
  EXPECT_EQ(status.Describe(), "exit code 3");
  EXPECT_EQ(out, "hello\n");
}

TEST_F(ProcessTest, DeathBySignalIsReported) {
  const auto [status, out] = Sh("kill -SEGV $$");
  EXPECT_FALSE(status.exited);
  EXPECT_EQ(status.signal, SIGSEGV);
  EXPECT_EQ(status.Describe().rfind("killed by signal 11", 0), 0u) << status.Describe();
}

TEST_F(ProcessTest, MemoryAndCpuLimitsAreApplied) {
  if (!kAddressSpaceLimitApplies) GTEST_SKIP() << kAddressSpaceLimitOff;
  SpawnOptions o;
  o.memory_limit_bytes = std::int64_t{512} << 20;
  o.cpu_limit_s = 77;
  // ulimit -v prints KiB, ulimit -t seconds (the soft limits).
  const auto [status, out] = Sh("ulimit -v; ulimit -t", o);
  ASSERT_TRUE(status.ok()) << status.Describe();
  EXPECT_EQ(out, "524288\n77\n");
}

// The sanitizer build's rule: the CPU limit still applies, the address-space limit does not (the
// test's own process has none, so the child's is unlimited).
TEST_F(ProcessTest, UnderAddressSanitizerOnlyTheCpuLimitIsApplied) {
  if (kAddressSpaceLimitApplies) GTEST_SKIP() << "not an AddressSanitizer build";
  SpawnOptions o;
  o.memory_limit_bytes = std::int64_t{512} << 20;
  o.cpu_limit_s = 77;
  const auto [status, out] = Sh("ulimit -v; ulimit -t", o);
  ASSERT_TRUE(status.ok()) << status.Describe();
  EXPECT_EQ(out, "unlimited\n77\n");
}

TEST_F(ProcessTest, EnvironmentAndWorkingDirectoryAreSet) {
  SpawnOptions o;
  o.env = {"ENAVI_PROBE=42"};
  o.cwd = dir_;
  const auto [status, out] = Sh("echo $ENAVI_PROBE; pwd", o);
  ASSERT_TRUE(status.ok());
  EXPECT_EQ(out, "42\n" + fs::canonical(dir_).string() + "\n");
}

TEST_F(ProcessTest, TerminateKillsTheWholeProcessGroup) {
  SpawnOptions o;
  // The shell starts a grandchild, records its pid and ignores SIGTERM itself.
  o.argv = {"/bin/sh", "-c",
            "trap '' TERM; sleep 300 & echo $! > " + (dir_ / "grandchild").string() + "; wait"};
  ChildProcess child = ChildProcess::Spawn(o);
  pid_t grandchild = 0;
  for (int i = 0; i < 500 && grandchild == 0; ++i) {
    std::ifstream in(dir_ / "grandchild");
    in >> grandchild;
    if (grandchild == 0) std::this_thread::sleep_for(10ms);
  }
  ASSERT_GT(grandchild, 0);
  const ExitStatus status = child.Terminate(200ms);
  EXPECT_EQ(status.signal, SIGKILL) << "the shell ignored SIGTERM, so SIGKILL ended it";
  // The grandchild was in the group: it is gone too (or a zombie about to be reaped by init).
  bool gone = false;
  for (int i = 0; i < 500 && !gone; ++i) {
    std::ifstream stat("/proc/" + std::to_string(grandchild) + "/stat");
    std::string pid, comm, state;
    gone = !(stat >> pid >> comm >> state) || state == "Z";
    if (!gone) std::this_thread::sleep_for(10ms);
  }
  EXPECT_TRUE(gone) << "grandchild " << grandchild << " survived";
}

TEST_F(ProcessTest, DestroyingARunningChildKillsIt) {
  pid_t pid = 0;
  {
    SpawnOptions o;
    o.argv = {"/bin/sleep", "300"};
    ChildProcess child = ChildProcess::Spawn(o);
    pid = child.pid();
    EXPECT_TRUE(child.running());
  }
  EXPECT_NE(kill(pid, 0), 0) << "child still exists after its owner was destroyed";
}

TEST_F(ProcessTest, MissingProgramFailsBeforeForking) {
  SpawnOptions o;
  o.argv = {"/nonexistent/enavi-episode"};
  EXPECT_THROW(ChildProcess::Spawn(o), std::runtime_error);
  o.argv = {"enavi-surely-not-in-path"};
  EXPECT_THROW(ChildProcess::Spawn(o), std::runtime_error);
}

TEST_F(ProcessTest, WaitWithTimeoutReturnsNothingWhileRunning) {
  SpawnOptions o;
  o.argv = {"/bin/sleep", "300"};
  ChildProcess child = ChildProcess::Spawn(o);
  EXPECT_FALSE(child.Wait(20ms).has_value());
  EXPECT_FALSE(child.Poll().has_value());
  child.Signal(SIGKILL);
  const auto status = child.Wait(std::chrono::milliseconds::max());
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(status->signal, SIGKILL);
}

TEST(SplitCommandTest, SplitsOnWhitespaceAndHonoursQuotes) {
  EXPECT_EQ(SplitCommand("  /usr/bin/enavi fly "), (std::vector<std::string>{"/usr/bin/enavi", "fly"}));
  EXPECT_EQ(SplitCommand("prog 'a b' \"c d\" e''"),
            (std::vector<std::string>{"prog", "a b", "c d", "e"}));
  EXPECT_THROW(SplitCommand("prog 'open"), std::invalid_argument);
  EXPECT_THROW(SplitCommand("   "), std::invalid_argument);
}

TEST(SelfExecutableTest, PointsAtThisTestBinary) {
  EXPECT_EQ(SelfExecutable().filename(), "process_test");
}

}  // namespace
}  // namespace enavi::worker
