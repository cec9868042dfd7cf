// The ROS bridge end to end through `enavi fly --ros-stack` (docs/ros.md): a ROS test stack
// (test_stack.cc) flies to the goal with each command type and through a launch file, and every
// way it can misbehave ends the episode with its reason; afterwards no process, cgroup or port of
// the episode is left, also when the stack hangs, forks orphans or the simulator is killed.
// Needs root (cgroups), ROS and a host calibration (made for the suite when none is stored);
// skipped otherwise, saying why.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <thread>

#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include "tests/integration/loop_test_util.h"
#include "tests/integration/suite_calibration.h"
#include "workers/emulation/cgroup_layout.h"

namespace enavi::integration {
namespace {

namespace fs = std::filesystem;

const std::string kTestStack = std::string(ENAVI_BINARY_DIR) + "/tests/ros/pkg/enavi_test/enavi_test_stack";

// Every process whose command line mentions `text`.
std::vector<std::string> ProcessesMentioning(const std::string& text) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string pid = e.path().filename();
    if (pid.find_first_not_of("0123456789") != std::string::npos || std::to_string(getpid()) == pid) continue;
    std::ifstream in(e.path() / "cmdline", std::ios::binary);
    std::string cmd((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::replace(cmd.begin(), cmd.end(), '\0', ' ');
    std::ifstream comm_in(e.path() / "comm");
    std::string comm;
    std::getline(comm_in, comm);
    if (cmd.find(text) != std::string::npos || comm == text) out.push_back(pid + " " + comm + ": " + cmd);
  }
  return out;
}

// Episode groups of processes that no longer run: what a dead simulator would leave.
std::vector<std::string> StaleEpisodeGroups() {
  std::vector<std::string> out;
  const fs::path parent = "/sys/fs/cgroup/cpu/enavi";
  if (!fs::exists(parent)) return out;
  static const std::regex name("ep-(\\d+)-\\d+-\\d+");
  for (const auto& e : fs::directory_iterator(parent)) {
    std::smatch m;
    const std::string n = e.path().filename();
    if (std::regex_match(n, m, name) && !fs::exists("/proc/" + m[1].str())) out.push_back(n);
  }
  return out;
}

int MasterPort(const nlohmann::json& r) {
  std::smatch m;
  const std::string note = r["notes"].value("ros.master", "");
  static const std::regex port(":(\\d+)/");
  return std::regex_search(note, m, port) ? std::stoi(m[1]) : 0;
}

bool PortListens(int port) {
  std::ifstream tcp("/proc/net/tcp");
  char hex[8];
  std::snprintf(hex, sizeof hex, ":%04X", port);
  for (std::string line; std::getline(tcp, line);)
    if (line.find(hex) != std::string::npos && line.find(" 0A ") != std::string::npos) return true;  // LISTEN
  return false;
}

// Nothing of a finished episode may be left: the stack's processes (and its orphans), the
// master and its port, the episode's groups.
void ExpectNothingLeft(const nlohmann::json& r) {
  for (int i = 0; i < 100; ++i) {  // the kernel reaps within a few ms; allow up to 1 s
    if (ProcessesMentioning(kTestStack).empty() && ProcessesMentioning("enavi-orphan").empty()) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(ProcessesMentioning(kTestStack).empty()) << ::testing::PrintToString(ProcessesMentioning(kTestStack));
  EXPECT_TRUE(ProcessesMentioning("enavi-orphan").empty()) << "an orphan of the stack survived";
  const int port = MasterPort(r);
  if (port > 0) {
    EXPECT_FALSE(PortListens(port)) << "the master's port " << port << " still listens";
    EXPECT_TRUE(ProcessesMentioning("rosmaster --core -p " + std::to_string(port)).empty());
  }
  EXPECT_TRUE(StaleEpisodeGroups().empty()) << ::testing::PrintToString(StaleEpisodeGroups());
}

class RosBridgeTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (geteuid() != 0 || emulation::DetectCgroups().version == emulation::CgroupVersion::kNone) return;
    suite_calibration_ = SuiteCalibration::Make("ros-bridge-test");
    calibration_ = suite_calibration_.path;
  }
  static void TearDownTestSuite() { suite_calibration_.Remove(); }
  void SetUp() override {
    if (geteuid() != 0) GTEST_SKIP() << "the bridge runs stacks on the emulated clock, which needs root (cgroups)";
    const emulation::CgroupLayout layout = emulation::DetectCgroups();
    if (layout.version == emulation::CgroupVersion::kNone) GTEST_SKIP() << "no writable cgroup hierarchy: " << layout.problem;
    if (!fs::exists("/usr/bin/rosmaster")) GTEST_SKIP() << "no rosmaster (Debian's python3-rosmaster)";
    ASSERT_FALSE(calibration_.empty());
  }

  // A stack file in the test's directory; returns its path.
  std::string Stack(const std::string& body) {
    const fs::path p = dir_.path() / ("stack" + std::to_string(stacks_++) + ".yaml");
    std::ofstream(p) << body;
    return p.string();
  }
  std::string TestStack(const std::string& mode, const std::string& extra = "") {
    return Stack("name: teststack\nrun: [" + kTestStack + ", --mode, \"" + mode + "\"]\n" + extra);
  }
  // Flies a stack file in the empty world on `board`; the JSON record.
  nlohmann::json Fly(const std::string& stack, const std::string& extra = "", const std::string& board = "tx2") {
    const CliRun run = Enavi(dir_, "fly --world empty --seed 1 --board " + board + " --speed-probe off --calibration " +
                                       calibration_ + " --ros-stack " + stack + " --json " + extra);
    EXPECT_EQ(run.code, 0) << run.err;
    if (run.code != 0) return nlohmann::json::object({{"end_reason", "exit " + std::to_string(run.code)}, {"notes", {}}});
    return nlohmann::json::parse(run.out);
  }

  TempDir dir_;
  int stacks_ = 0;
  static inline SuiteCalibration suite_calibration_;
  static inline std::string calibration_;
};

TEST_F(RosBridgeTest, EachCommandTypeFliesTheTestStackToTheGoal) {
  for (const std::string type : {"position", "pose", "trajectory"}) {
    const nlohmann::json r = Fly(TestStack(type, "command_timeout_s: 5\n"), "--param length=8");
    EXPECT_EQ(r["end_reason"], "goal_reached") << type << ": " << r.dump();
    EXPECT_EQ(r["method"], "teststack");
    EXPECT_EQ(r["clock"], "emulated");
    const std::string commands = r["notes"].value("ros.commands", "");
    const std::map<std::string, std::string> types = {{"position", "quadrotor_msgs/PositionCommand"},
                                                      {"pose", "geometry_msgs/PoseStamped"},
                                                      {"trajectory", "trajectory_msgs/MultiDOFJointTrajectory"}};
    EXPECT_NE(commands.find(types.at(type)), std::string::npos) << commands;
    // The stack's CPU is measured per process and is the navigation CPU.
    ASSERT_TRUE(r["notes"].contains("process.enavi_test_stack")) << r["notes"].dump();
    EXPECT_GT(r["nav_cpu_util_pct"].get<double>(), 0.0);
    ExpectNothingLeft(r);
  }
}

TEST_F(RosBridgeTest, EachWayAStackFailsEndsTheEpisodeWithItsReason) {
  struct Case {
    std::string mode, extra, reason, detail;
  };
  const std::vector<Case> cases = {
      {"exit:0@2", "", "stack_exited", "exit code 0"},
      {"exit:3@2", "", "stack_crashed", "exit code 3"},
      {"segv@2", "", "stack_crashed", "signal 11"},
      {"silent", "command_timeout_s: 3\n", "no_command", "within 3.0 s"},
      {"nan@2", "", "bad_command", "position is not finite"},
      {"far@2", "", "bad_command", "outside the world's bounds"},
      {"wrong_type", "", "command_wrong_type", "std_msgs/String"},
  };
  for (const Case& c : cases) {
    const nlohmann::json r = Fly(TestStack(c.mode, c.extra), "--timeout 20");
    EXPECT_EQ(r["end_reason"], c.reason) << c.mode << ": " << r.dump();
    const std::string detail = r["notes"].value("end_detail", "");
    EXPECT_NE(detail.find(c.detail), std::string::npos) << c.mode << ": " << detail;
    EXPECT_FALSE(r["success"].get<bool>());
    if (c.reason == "stack_crashed" || c.reason == "stack_exited") {
      EXPECT_NE(r["notes"].value("ros.stack_log_tail", "").find("enavi_test_stack:"), std::string::npos)
          << "the result keeps the tail of the stack's log: " << r["notes"].dump();
    }
    ExpectNothingLeft(r);
  }
  // A stack that never advertises its command topic.
  const nlohmann::json r = Fly(Stack("name: sleeper\nrun: [sleep, \"1000\"]\nstartup_timeout_s: 2\n"));
  EXPECT_EQ(r["end_reason"], "stack_not_ready") << r.dump();
  EXPECT_TRUE(ProcessesMentioning("sleep 1000").empty());
  ExpectNothingLeft(r);
}

TEST_F(RosBridgeTest, AStackThatIgnoresSignalsOrLeavesOrphansIsGoneAfterTheEpisode) {
  for (const std::string mode : {"hang", "fork"}) {
    const nlohmann::json r = Fly(TestStack(mode), "--param length=6 --timeout 3");
    EXPECT_EQ(r["end_reason"], "timeout") << mode;
    ExpectNothingLeft(r);
  }
}

TEST_F(RosBridgeTest, KillingTheSimulatorLeavesNothingBehind) {
  const std::string stack = TestStack("fork");
  const std::string calibration = calibration_;
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, 1);
    dup2(null, 2);
    const std::string enavi = std::string(ENAVI_BINARY_DIR) + "/bin/enavi";
    execl(enavi.c_str(), enavi.c_str(), "fly", "--world", "empty", "--board", "tx2", "--speed-probe", "off",
          "--calibration", calibration.c_str(), "--ros-stack", stack.c_str(), "--timeout", "60", nullptr);
    _exit(127);
  }
  // Kill it once its stack (and the stack's orphan) run.
  bool running = false;
  for (int i = 0; i < 600 && !running; ++i) {
    running = !ProcessesMentioning("enavi-orphan").empty();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_TRUE(running) << "the stack never started";
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  // The supervisor ends everything within its 10 s of grace for the recorder.
  for (int i = 0; i < 300; ++i) {
    if (ProcessesMentioning(kTestStack).empty() && ProcessesMentioning("enavi-orphan").empty() &&
        StaleEpisodeGroups().empty())
      break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ExpectNothingLeft(nlohmann::json::object({{"notes", nlohmann::json::object()}}));
  EXPECT_TRUE(ProcessesMentioning("rosmaster --core").empty());
}

TEST_F(RosBridgeTest, ALaunchFileFromAPackageGetsTheEpisodesArgsAndABagIsRecorded) {
  const fs::path launch = dir_.path() / "teststack.launch";
  // A launch file as a user writes one: its own argument, and the episode's goal it declares.
  std::ofstream(launch) << R"xml(<launch>
  <arg name="speed" default="1.0"/>
  <arg name="enavi_goal_x"/>
  <node pkg="enavi_test" type="enavi_test_stack" name="planner" output="screen"
        args="--mode position --speed $(arg speed)"/>
  <param name="goal_x_seen" value="$(arg enavi_goal_x)"/>
</launch>
)xml";
  const std::string stack = Stack("name: launched\nlaunch: " + launch.string() + "\npackage_path: [" +
                                  std::string(ENAVI_BINARY_DIR) + "/tests/ros/pkg]\nargs: {speed: \"2.0\"}\n");
  const fs::path out = dir_.path() / "out";
  const nlohmann::json r = Fly(stack, "--param length=8 --rosbag --out " + out.string());
  EXPECT_EQ(r["end_reason"], "goal_reached") << r.dump();
  EXPECT_TRUE(r["notes"].contains("process.planner")) << "the node is named as roslaunch named it: " << r["notes"].dump();
  EXPECT_NE(r["notes"].value("ros.command", "").find("enavi_goal_x:="), std::string::npos) << r["notes"].dump();
  EXPECT_TRUE(fs::exists(out / "ros" / "stack.log"));
  // The bag: closed (not .active), with the depth stream at the camera's rate.
  ASSERT_TRUE(fs::exists(out / "episode.bag")) << r["notes"].dump();
  const CliRun info = [&] {
    CliRun c;
    const std::string cmd = "/usr/bin/rosbag info " + (out / "episode.bag").string() + " > " +
                            (dir_.path() / "info.txt").string() + " 2>&1";
    c.code = std::system(cmd.c_str());
    c.out = ReadFile(dir_.path() / "info.txt");
    return c;
  }();
  ASSERT_EQ(info.code, 0) << info.out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(info.out, m, std::regex("/enavi/depth/image\\s+(\\d+) msgs"))) << info.out;
  const double frames = std::stod(m[1]);
  const double flight = r["flight_time_s"].get<double>();
  EXPECT_NEAR(frames, 30.0 * flight, 0.1 * 30.0 * flight) << info.out;
  EXPECT_NE(info.out.find("quadrotor_msgs/PositionCommand"), std::string::npos) << info.out;
  ExpectNothingLeft(r);
}

// Issue 42's farm case: a job of 2 boards x 2 scenarios x (a ROS method, enavi) on `enavi eval`
// with 2 workers; compare and the dashboard's API name the ROS method as the tables do.
TEST_F(RosBridgeTest, AJobOfARosMethodAndEnaviRunsOnEvalWithTwoWorkers) {
  const std::string stack = TestStack("position", "command_timeout_s: 5\n");
  const fs::path db = dir_.path() / "eval.db";
  // The suite's host calibration from the environment, as a user's batch would run (eval's
  // workers start `enavi episode`, which reads ENAVI_CALIBRATION; a fresh machine has none stored).
  ASSERT_EQ(setenv("ENAVI_CALIBRATION", calibration_.c_str(), 1), 0);
  const CliRun eval = Enavi(dir_, "eval --ros-stack " + stack + " --methods enavi --boards tx2,pi4b --scenarios empty,s1 "
                                  "--workers 2 --timeout 4 --speed-probe off --name rosjob --db " + db.string());
  ASSERT_EQ(eval.code, 0) << eval.out << eval.err;
  EXPECT_NE(eval.out.find("teststack"), std::string::npos) << "the table names the ROS method:\n" << eval.out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(eval.err, m, std::regex("\\(job (j[0-9a-f]+)"))) << eval.err;
  const std::string job = m[1];
  const std::string ref = db.string() + ":" + job;
  const CliRun compare = Enavi(dir_, "compare " + ref + " " + ref + " --format json");
  ASSERT_EQ(compare.code, 0) << compare.err;
  EXPECT_NE(compare.out.find("\"teststack\""), std::string::npos) << compare.out.substr(0, 2000);

  // The dashboard (read-only) serves the job with the method by its name.
  const fs::path ready = dir_.path() / "ready";
  const pid_t dash = fork();
  ASSERT_GE(dash, 0);
  if (dash == 0) {
    const std::string enavi = std::string(ENAVI_BINARY_DIR) + "/bin/enavi";
    execl(enavi.c_str(), enavi.c_str(), "dashboard", "--db", db.c_str(), "--http", "127.0.0.1:0", "--ready-file",
          ready.c_str(), nullptr);
    _exit(127);
  }
  std::string url;
  for (int i = 0; i < 200 && url.empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    url = ReadFile(ready);
  }
  url.erase(url.find_last_not_of(" \n") + 1);
  ASSERT_FALSE(url.empty()) << "the dashboard never became ready";
  httplib::Client client(url);
  const auto summary = client.Get("/api/jobs/" + job + "/summary");
  kill(dash, SIGTERM);
  waitpid(dash, nullptr, 0);
  ASSERT_TRUE(summary) << "no reply from " << url;
  EXPECT_EQ(summary->status, 200);
  EXPECT_NE(summary->body.find("\"teststack\""), std::string::npos) << summary->body.substr(0, 2000);
  ExpectNothingLeft(nlohmann::json::object({{"notes", nlohmann::json::object()}}));
}

// Part 3 of the issue: the stack's group has the board's capacity and no thread more than one
// board core, so a busy single-threaded node runs at one board core whatever the board's cores,
// and four busy threads at four. Measured from each thread's CPU time in /proc.
TEST_F(RosBridgeTest, NoThreadOfTheStackGetsMoreThanOneBoardCore) {
  const std::regex busy("enavi_test_stack/busy-\\d+ ([0-9.]+) %");
  for (const std::string board : {"tx2", "pi4b"}) {
    for (const int threads : {1, 4}) {
      const nlohmann::json r = Fly(TestStack("busy:" + std::to_string(threads)), "--timeout 10", board);
      ASSERT_EQ(r["end_reason"], "timeout") << r.dump();
      const std::string note = r["notes"].value("ros.threads", "");
      double sum = 0;
      int seen = 0;
      for (auto it = std::sregex_iterator(note.begin(), note.end(), busy); it != std::sregex_iterator(); ++it) {
        sum += std::stod((*it)[1]);
        ++seen;
      }
      std::printf("%s, %d busy thread(s): %.1f %% of a board core (%s; %s)\n", board.c_str(), threads, sum,
                  note.c_str(), r["notes"].value("emulation.dilation", "").c_str());
      EXPECT_EQ(seen, threads) << note;
      EXPECT_NEAR(sum, 100.0 * threads, 10.0 * threads) << board << ", " << threads << " threads: " << note;
    }
  }
}

}  // namespace
}  // namespace enavi::integration
