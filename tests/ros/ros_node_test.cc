// Our methods as a ROS node through the bridge, end to end (docs/ros.md, "Our own stacks as ROS
// nodes"): `fixed` as enavi_ros_node, started by our launch file, reaches the goal in s1 and s2
// on tx2 through `enavi fly --ros-stack`, with its CPU in the result per node, and the same
// flight natively on the emulated clock (--method fixed --clock emulated) takes a flight time
// within 10 % of it. A bad parameter ends the node at once with exit code 2 and its reason in the
// result. Needs root (cgroups), ROS and a host calibration (made for the suite when none is
// stored); skipped otherwise, saying why.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/integration/loop_test_util.h"
#include "tests/integration/suite_calibration.h"
#include "workers/emulation/cgroup_layout.h"

namespace enavi::integration {
namespace {

namespace fs = std::filesystem;

const std::string kNode = std::string(ENAVI_BINARY_DIR) + "/ros/node/pkg/enavi/enavi_ros_node";
const std::string kLaunch = std::string(ENAVI_SOURCE_DIR) + "/ros/launch/enavi_node.launch";
const std::string kPackages = std::string(ENAVI_BINARY_DIR) + "/ros/node/pkg";

class RosNodeTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (geteuid() != 0 || emulation::DetectCgroups().version == emulation::CgroupVersion::kNone) return;
    calibration_ = SuiteCalibration::Make("ros-node-test");
  }
  static void TearDownTestSuite() { calibration_.Remove(); }
  void SetUp() override {
    if (geteuid() != 0) GTEST_SKIP() << "the bridge runs stacks on the emulated clock, which needs root (cgroups)";
    const emulation::CgroupLayout layout = emulation::DetectCgroups();
    if (layout.version == emulation::CgroupVersion::kNone) GTEST_SKIP() << "no writable cgroup hierarchy: " << layout.problem;
    if (!fs::exists("/usr/bin/rosmaster") || !fs::exists("/usr/bin/roslaunch"))
      GTEST_SKIP() << "no rosmaster or roslaunch (Debian's python3-rosmaster, python3-roslaunch)";
    ASSERT_FALSE(calibration_.path.empty());
  }

  std::string Stack(const std::string& body) {
    const fs::path p = dir_.path() / ("stack" + std::to_string(stacks_++) + ".yaml");
    std::ofstream(p) << body;
    return p.string();
  }
  // `enavi fly ARGS` on tx2 with the suite's calibration, both ways at one dilation (2: tx2 on
  // 1.44 of this host's CPUs); the JSON record. Emulations of other processes may hold the host's
  // CPUs: a refused admission is retried for up to 5 minutes.
  nlohmann::json Fly(const std::string& args) {
    CliRun run;
    for (int attempt = 0; attempt < 10; ++attempt) {
      run = Enavi(dir_, "fly --seed 1 --board tx2 --dilation 2 --speed-probe off --calibration " + calibration_.path +
                            " --json " + args);
      if (run.code != 2 || run.err.find("admission refused") == std::string::npos) break;
      std::printf("admission refused, waiting 30 s: %s\n", run.err.c_str());
      std::this_thread::sleep_for(std::chrono::seconds(30));
    }
    EXPECT_EQ(run.code, 0) << run.err;
    if (run.code != 0) return nlohmann::json::object({{"end_reason", "exit " + std::to_string(run.code)}, {"notes", {}}});
    return nlohmann::json::parse(run.out);
  }

  TempDir dir_;
  int stacks_ = 0;
  static inline SuiteCalibration calibration_;
};

// A result's per-node CPU, "12.34 % of a board core"; -1 when absent.
double NodeCpu(const nlohmann::json& r, const std::string& node) {
  const std::string note = r["notes"].value("process." + node, "");
  return note.empty() ? -1.0 : std::stod(note);
}

TEST_F(RosNodeTest, FixedAsARosNodeReachesTheGoalInS1AndS2WithinTenPercentOfItsNativeFlightTime) {
  const std::string stack = Stack("name: fixed_ros\nlaunch: " + kLaunch + "\npackage_path: [" + kPackages +
                                  "]\nargs: {method: fixed}\n");
  for (const std::string world : {"s1", "s2"}) {
    const nlohmann::json native = Fly("--world " + world + " --method fixed --clock emulated");
    const nlohmann::json ros = Fly("--world " + world + " --ros-stack " + stack);
    ASSERT_EQ(native["end_reason"], "goal_reached") << world << " natively: " << native.dump();
    ASSERT_EQ(ros["end_reason"], "goal_reached") << world << " as a ROS node: " << ros.dump();
    EXPECT_EQ(ros["method"], "fixed_ros");
    const double node_cpu = NodeCpu(ros, "enavi_node");
    EXPECT_GT(node_cpu, 0.0) << "the node's CPU is in the result by its launch name: " << ros["notes"].dump();
    const double t_native = native["flight_time_s"].get<double>(), t_ros = ros["flight_time_s"].get<double>();
    std::printf("%s on tx2: native %.2f s, nav CPU %.1f %% (%s); ROS node %.2f s, %s\n", world.c_str(), t_native,
                native["nav_cpu_util_pct"].get<double>(), native["notes"].value("emulation.proc_util", "").c_str(),
                t_ros, ros["notes"].value("ros.cpu", "").c_str());
    EXPECT_LE(std::abs(t_ros - t_native), 0.10 * t_native)
        << world << ": the ROS node's flight time " << t_ros << " s against " << t_native << " s natively";
  }
}

TEST_F(RosNodeTest, ABadParameterEndsTheNodeWithExitCode2AndItsReason) {
  const nlohmann::json r =
      Fly("--world empty --timeout 20 --ros-stack " + Stack("name: badnode\nrun: [" + kNode + ", \"_planner/v_max:=20\"]\n"));
  EXPECT_EQ(r["end_reason"], "stack_crashed") << r.dump();
  EXPECT_NE(r["notes"].value("end_detail", "").find("exit code 2"), std::string::npos) << r["notes"].dump();
  EXPECT_NE(r["notes"].value("ros.stack_log_tail", "").find("planner.v_max: 20 is outside [0.2, 10]"), std::string::npos)
      << r["notes"].dump();
}

}  // namespace
}  // namespace enavi::integration
