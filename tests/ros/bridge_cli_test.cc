// Bad ROS input at the command line (docs/ros.md): every case exits 2 with a message naming the
// file, line, field and reason, before anything flies. No root or master needed.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "tests/integration/loop_test_util.h"

namespace enavi::integration {
namespace {

namespace fs = std::filesystem;

struct Case {
  std::string stack;     ///< the stack file's text
  std::string args;      ///< further arguments of `enavi fly`
  std::string expected;  ///< in the message, after the file's name
};

TEST(RosBridgeCliTest, BadStacksAndClocksAreRefusedWithExitTwoNamingWhy) {
  TempDir dir;
  const std::vector<Case> cases = {
      {"name: x\nlaunch: missing.launch\n", "", ":2: launch: 'missing.launch': no such file"},
      {"name: x\nrun: [a]\ntopics: {lidar: /scan}\n", "", ":3: topics.lidar: unknown topic role"},
      {"name: fixed\nrun: [a]\n", "", ":1: name: 'fixed' is a registered method's name"},
      {"name: x\nrun: [a]\n", "--clock virtual", "clock: method 'x' is a ROS stack: it runs on the emulated clock only"},
      {"name: x\nrun: [a]\n", "--set planner.v_max=1", "overrides: method 'x' is a ROS stack: it has no tunables"},
      {"name: x\nrun: [a]\n", "--method enavi", "--method: 'enavi' is not the ROS stack's name 'x'"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const fs::path stack = dir.path() / ("stack" + std::to_string(i) + ".yaml");
    std::ofstream(stack) << cases[i].stack;
    const CliRun r = Enavi(dir, "fly --world empty --ros-stack " + stack.string() + " " + cases[i].args);
    EXPECT_EQ(r.code, 2) << cases[i].stack << cases[i].args << "\n" << r.err;
    EXPECT_NE(r.err.find(cases[i].expected), std::string::npos) << r.err;
  }
  // --rosbag belongs to a ROS stack.
  const CliRun r = Enavi(dir, "fly --world empty --rosbag");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--rosbag: records the topics of a ROS stack"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace enavi::integration
