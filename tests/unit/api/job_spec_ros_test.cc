// ROS methods in stack files and job specs (api/ros_stack.h): what a user writes, what an episode
// carries, and every bad input named by file, line and field. No ROS needed: this is the contract.
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "api/job_spec.h"
#include "api/ros_stack.h"

namespace enavi::api {
namespace {

namespace fs = std::filesystem;

class RosJobSpecTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("ros_job_spec_test-" + std::to_string(getpid()) + "-" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(root_ / "stacks/launch");
    std::ofstream(root_ / "stacks/launch/ego.launch") << "<launch><arg name=\"goal_x\"/></launch>\n";
    std::ofstream(root_ / "stacks/ego.yaml") << "name: ego\nlaunch: launch/ego.launch\n"
                                                "topics: {command: /planning/pos_cmd, depth: /camera/depth}\n"
                                                "depth_encoding: 16UC1\nargs: {max_vel: 2.0}\n";
    options_.allowed_roots = {root_};
    options_.catalog.methods = {{"baseline", "", {{"planner.v_max", 0.2, 10.0, false}}},
                                {"fixed", "", {{"planner.v_max", 0.2, 10.0, false}}},
                                {"enavi", "", {{"planner.v_max", 0.2, 10.0, false}}}};
    options_.catalog.boards = {"pi4b", "tx2"};
    options_.catalog.scenarios = {"s1", "s2"};
    options_.catalog.clocks = {"virtual", "emulated"};
  }
  void TearDown() override { fs::remove_all(root_); }

  JobSpec Parse(const std::string& yaml) { return ParseJobSpec(yaml, "job.yaml", options_); }
  std::string Error(const std::string& yaml) {
    try {
      Parse(yaml);
    } catch (const JobSpecError& e) {
      return e.what();
    }
    ADD_FAILURE() << "spec was accepted:\n" << yaml;
    return "";
  }
  std::string StackError(const std::string& yaml) {
    std::ofstream(root_ / "stacks/bad.yaml") << yaml;
    try {
      LoadRosStack((root_ / "stacks/bad.yaml").string(), {"baseline", "fixed", "enavi"});
    } catch (const RosStackError& e) {
      return std::string(e.what()).substr((root_ / "stacks/bad.yaml").string().size());
    }
    ADD_FAILURE() << "stack was accepted:\n" << yaml;
    return "";
  }

  fs::path root_;
  JobSpecOptions options_;
};

TEST_F(RosJobSpecTest, AStackFileNamesItsLaunchFileArgsAndTopicsTheRestAreDefaults) {
  const RosStack s = LoadRosStack((root_ / "stacks/ego.yaml").string(), {"baseline"});
  EXPECT_EQ(s.name, "ego");
  EXPECT_EQ(s.launch, fs::weakly_canonical(root_ / "stacks/launch/ego.launch").string()) << "relative to the stack file";
  EXPECT_EQ(s.args.at("max_vel"), "2.0");
  EXPECT_EQ(s.Topic("command"), "/planning/pos_cmd");
  EXPECT_EQ(s.Topic("depth"), "/camera/depth");
  EXPECT_EQ(s.Topic("odom"), "/enavi/odom") << "a role the file does not rename keeps its default";
  EXPECT_EQ(s.depth_encoding, "16UC1");
  EXPECT_EQ(s.clock_hz, 1000.0);
  EXPECT_EQ(s.topics.size(), RosTopicRoles().size());
  // What crosses to a worker: the JSON round trip keeps every field.
  const RosStack back = nlohmann::json(s).get<RosStack>();
  EXPECT_EQ(nlohmann::json(back), nlohmann::json(s));
}

TEST_F(RosJobSpecTest, AJobFliesItsRosMethodsByNameOnTheEmulatedClock) {
  const JobSpec job = Parse(R"(boards: [tx2, pi4b]
scenarios: [s1, s2]
methods: [ego, enavi]
seeds: 1
clock: emulated
rosbag: bags
ros_methods:
  ego: stacks/ego.yaml
)");
  ASSERT_EQ(job.ros_methods.count("ego"), 1u);
  const std::vector<EpisodeSpec> episodes = ExpandJob(job);
  ASSERT_EQ(episodes.size(), 8u);
  int ros = 0;
  for (const EpisodeSpec& e : episodes) {
    if (e.method == "ego") {
      ++ros;
      ASSERT_TRUE(e.ros.has_value());
      EXPECT_EQ(e.ros->name, "ego");
      EXPECT_EQ(e.rosbag_dir, fs::weakly_canonical(root_ / "bags").string());
    } else {
      EXPECT_FALSE(e.ros.has_value()) << e.method;
      EXPECT_TRUE(e.rosbag_dir.empty());
    }
    // The episode record carries the stack to the worker.
    EXPECT_EQ(nlohmann::json(e).get<EpisodeSpec>().ros.has_value(), e.method == "ego");
  }
  EXPECT_EQ(ros, 4);
}

TEST_F(RosJobSpecTest, AStackMayBeWrittenInlineAndTheJobsKeyNamesIt) {
  const JobSpec job = Parse(R"(boards: tx2
scenarios: s1
methods: [mine]
seeds: 1
clock: emulated
ros_methods:
  mine: {run: [rosrun, my_pkg, planner], topics: {command: /cmd}}
)");
  const RosStack& s = job.ros_methods.at("mine");
  EXPECT_EQ(s.name, "mine");
  EXPECT_EQ(s.run, (std::vector<std::string>{"rosrun", "my_pkg", "planner"}));
  EXPECT_EQ(s.Topic("command"), "/cmd");
}

TEST_F(RosJobSpecTest, ARosMethodOnTheVirtualClockIsRefusedWithTheReason) {
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: [ego]\nseeds: 1\nros_methods: {ego: stacks/ego.yaml}\n"),
            "job.yaml:3: clock: method 'ego' is a ROS stack: it runs on the emulated clock only (its processes run "
            "in real time inside the board's cgroup); set clock: emulated");
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: [ego]\nseeds: 1\nclock: virtual\n"
                  "ros_methods: {ego: stacks/ego.yaml}\n")
                .rfind("job.yaml:5: clock: method 'ego' is a ROS stack", 0),
            0u);
}

TEST_F(RosJobSpecTest, BadRosMethodsInAJobAreNamedByLineAndField) {
  const std::string head = "boards: tx2\nscenarios: s1\nseeds: 1\nclock: emulated\n";
  // Defined but not flown, flown but not defined.
  EXPECT_EQ(Error(head + "methods: [enavi]\nros_methods: {ego: stacks/ego.yaml}\n"),
            "job.yaml:6: ros_methods.ego: defined but not listed in methods");
  EXPECT_EQ(Error(head + "methods: [ego]\n").rfind("job.yaml:5: methods: unknown method 'ego'", 0), 0u);
  // A ROS stack has no tunables of ours: a job-wide override cannot apply to it.
  EXPECT_EQ(Error(head + "methods: [ego, enavi]\nros_methods: {ego: stacks/ego.yaml}\noverrides: {planner.v_max: 1.0}\n"),
            "job.yaml:7: overrides.planner.v_max: method ego is a ROS stack: it has no tunables (its launch "
            "arguments are ros_methods.ego.args)");
  // A registered method's name is taken.
  EXPECT_EQ(Error(head + "methods: [fixed]\nros_methods: {fixed: stacks/ego.yaml}\n"),
            "job.yaml:6: ros_methods.fixed: 'fixed' is a registered method's name");
  // A missing stack file, a stack file's own error (named by that file), an inline one (by the job).
  EXPECT_EQ(Error(head + "methods: [ego]\nros_methods: {ego: stacks/none.yaml}\n"),
            "job.yaml:6: ros_methods.ego: 'stacks/none.yaml': no such file");
  std::ofstream(root_ / "stacks/broken.yaml") << "name: broken\nlaunch: launch/missing.launch\n";
  const std::string broken = Error(head + "methods: [ego]\nros_methods: {ego: stacks/broken.yaml}\n");
  EXPECT_NE(broken.find("broken.yaml:2: launch: 'launch/missing.launch': no such file"), std::string::npos) << broken;
  EXPECT_EQ(Error(head + "methods: [ego]\nros_methods:\n  ego: {run: [x], topics: {lidar: /scan}}\n"),
            "job.yaml:7: ros_methods.ego.topics.lidar: unknown topic role (known: depth, camera_info, camera_pose, "
            "odom, cloud, goal, goal_path, command)");
  EXPECT_EQ(Error(head + "methods: [enavi]\nrosbag: bags\n"),
            "job.yaml:6: rosbag: records the topics of ROS methods; this job has none");
}

TEST_F(RosJobSpecTest, BadStackFilesAreNamedByLineAndField) {
  EXPECT_EQ(StackError("launch: launch/ego.launch\n"), ":1: name: missing (required: the method's name in tables)");
  EXPECT_EQ(StackError("name: Ego Planner\nlaunch: launch/ego.launch\n"),
            ":1: name: 'Ego Planner': 1..64 characters of [a-z0-9_-], starting with a letter");
  EXPECT_EQ(StackError("name: enavi\nlaunch: launch/ego.launch\n"), ":1: name: 'enavi' is a registered method's name");
  EXPECT_EQ(StackError("name: x\n"), ":1: launch: give a launch file or run: [command, args...], one of them");
  EXPECT_EQ(StackError("name: x\nlaunch: launch/ego.launch\nrun: [a]\n"),
            ":1: launch: give a launch file or run: [command, args...], one of them");
  EXPECT_NE(StackError("name: x\nlaunch: nope.launch\n").find(":2: launch: 'nope.launch': no such file"),
            std::string::npos);
  EXPECT_NE(StackError("name: x\nlaunch: launch/ego.launch\nworkspace: ws/devel/setup.bash\n")
                .find(":3: workspace: 'ws/devel/setup.bash': no such file"),
            std::string::npos);
  EXPECT_EQ(StackError("name: x\nlaunch: launch/ego.launch\ntopics: {command: 'two words'}\n"),
            ":3: topics.command: 'two words' is not a ROS topic name");
  EXPECT_EQ(StackError("name: x\nlaunch: launch/ego.launch\ndepth_encoding: 8UC1\n"),
            ":3: depth_encoding: '8UC1' (known: 32FC1, 16UC1)");
  EXPECT_EQ(StackError("name: x\nrun: [a]\nargs: {k: v}\n"),
            ":3: args: launch arguments need a launch file (a command takes its own)");
  EXPECT_EQ(StackError("name: x\nrun: [a]\nclock_hz: 5000\n").rfind(":3: clock_hz: ", 0), 0u);
  EXPECT_EQ(StackError("name: x\nrun: [a]\nspeed: 2\n").rfind(":3: speed: unknown key", 0), 0u);
}

TEST_F(RosJobSpecTest, AnEpisodeRecordWhoseMethodIsNotItsStacksIsRefused) {
  EpisodeSpec spec;
  spec.method = "ego";
  spec.clock = "emulated";
  spec.ros = LoadRosStack((root_ / "stacks/ego.yaml").string(), {});
  nlohmann::json j = spec;
  j["method"] = "other";
  EXPECT_THROW(j.get<EpisodeSpec>(), std::invalid_argument);
  j["method"] = "ego";
  j["ros"]["topics"].erase("command");
  EXPECT_THROW(j.get<EpisodeSpec>(), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::api
