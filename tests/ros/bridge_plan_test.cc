// The ROS bridge's parts that need no master (workers/ros): how a stack is started, what its
// commands mean to the controller, and how its processes are named in the results.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include <gtest/gtest.h>

#include "api/fixed.h"
#include "workers/ros/launch_plan.h"
#include "workers/ros/setpoint.h"
#include "workers/ros/stack_cpu.h"

namespace enavi::ros {
namespace {

TEST(LaunchPlanTest, OnlyTopLevelArgsOfALaunchFileAreDeclared) {
  const std::string xml = R"xml(<launch>
  <arg name="map_size_x" default="40"/>
  <arg   name='goal_x'/>
  <!-- <arg name="commented_out"/> -->
  <include file="$(find pkg)/launch/inner.launch">
    <arg name="passed_to_include" value="$(arg goal_x)"/>
  </include>
  <node pkg="p" type="t" name="n">
    <param name="not_an_arg" value="1"/>
  </node>
  <group ns="g"><arg name="in_group" default="1"/></group>
</launch>)xml";
  EXPECT_EQ(DeclaredLaunchArgs(xml), (std::set<std::string>{"map_size_x", "goal_x", "in_group"}));
}

TEST(LaunchPlanTest, ALaunchFileGetsTheStacksArgsThenTheEpisodesItDeclares) {
  api::RosStack stack;
  stack.launch = "/ws/ego.launch";
  stack.args = {{"max_vel", "2.0"}, {"enavi_goal_x", "99"}};
  EpisodeGeometry g;
  g.start = {0, 0, 1};
  g.goal = {30, 2, 1};
  g.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-5, -8, 0), Eigen::Vector3d(35, 8, 4));
  g.camera = navstack::CameraIntrinsics::DefaultStream();
  g.seed = 42;
  const std::string xml = "<launch><arg name=\"enavi_goal_x\"/><arg name=\"enavi_map_size_x\"/>"
                          "<arg name=\"enavi_cx\"/><arg name=\"enavi_seed\"/><arg name=\"max_vel\"/></launch>";
  const std::vector<std::string> cmd = StackCommand(stack, xml, EpisodeLaunchArgs(g), "http://127.0.0.1:1234/");
  const std::vector<std::string> expected = {"roslaunch", "--screen", "--skip-log-check", "/ws/ego.launch",
                                             "enavi_goal_x:=99",  // the stack's own value wins
                                             "max_vel:=2.0",
                                             "enavi_cx:=" + api::Fixed(g.camera.cx - 0.5, 4),
                                             "enavi_map_size_x:=70.0000",  // 2 x |35|: a map centred on 0
                                             "enavi_seed:=42"};
  EXPECT_EQ(cmd, expected);
}

TEST(LaunchPlanTest, AWorkspaceIsSourcedFirstAndOurMasterWinsOverItsScripts) {
  api::RosStack stack;
  stack.run = {"rosrun", "pkg", "node"};
  stack.workspace = "/ws/devel/setup.bash";
  const auto cmd = StackCommand(stack, "", {}, "http://127.0.0.1:1234/");
  ASSERT_EQ(cmd.size(), 7u);
  EXPECT_EQ(cmd[0], "/bin/bash");
  EXPECT_NE(cmd[2].find("source \"$0\""), std::string::npos);
  EXPECT_NE(cmd[2].find("export ROS_MASTER_URI=http://127.0.0.1:1234/"), std::string::npos);
  EXPECT_EQ(cmd[3], "/ws/devel/setup.bash");
  EXPECT_EQ(std::vector<std::string>(cmd.begin() + 4, cmd.end()), stack.run);
}

TEST(LaunchPlanTest, TheEnvironmentDropsTheCallersRosSettingsAndPutsDebiansPythonFirst) {
  api::RosStack stack;
  stack.package_path = {"/ws/src"};
  const EpisodeFiles f = FilesIn("/tmp/ep", "");
  const auto env = EpisodeEnvironment({"HOME=/root", "PATH=/root/.pyenv/shims:/usr/bin", "ROS_MASTER_URI=http://x:11311",
                                       "ROS_PACKAGE_PATH=/opt/other"},
                                      stack, "http://127.0.0.1:1234/", f);
  auto has = [&](const std::string& e) { return std::find(env.begin(), env.end(), e) != env.end(); };
  EXPECT_TRUE(has("HOME=/root"));
  EXPECT_TRUE(has("PATH=/usr/bin:/root/.pyenv/shims:/usr/bin"));
  EXPECT_TRUE(has("ROS_MASTER_URI=http://127.0.0.1:1234/"));
  EXPECT_FALSE(has("ROS_MASTER_URI=http://x:11311"));
  EXPECT_TRUE(has("ROS_PACKAGE_PATH=/ws/src:/opt/other"));
  EXPECT_TRUE(has("ROS_LOG_DIR=/tmp/ep/ros_log"));
  EXPECT_TRUE(has("ROS_HOSTNAME=127.0.0.1"));
}

TEST(LaunchPlanTest, TheLogTailIsTheLastLinesOfTheFile) {
  const std::string path = std::filesystem::temp_directory_path() / "launch_plan_test.log";
  {
    std::ofstream out(path);
    for (int i = 0; i < 100; ++i) out << "line " << i << "\n";
  }
  EXPECT_EQ(LogTail(path, 3), "line 97\nline 98\nline 99\n");
  EXPECT_EQ(LogTail(path + ".none"), "");
  std::filesystem::remove(path);
}

Command OnePoint(double x, double v = 0) {
  Setpoint s;
  s.p = {x, 0, 1};
  s.v = {v, 0, 0};
  return {"quadrotor_msgs/PositionCommand", {s}};
}

TEST(SetpointTest, BrokenCommandsAreNamedAndSaneOnesPass) {
  CommandLimits limits;
  limits.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(0, -5, 0), Eigen::Vector3d(30, 5, 5));
  EXPECT_FALSE(CheckCommand(OnePoint(10, 2), limits).has_value());
  EXPECT_FALSE(CheckCommand(OnePoint(31.5), limits).has_value()) << "within the 2 m margin";
  EXPECT_EQ(*CheckCommand(OnePoint(std::numeric_limits<double>::quiet_NaN()), limits), "position is not finite");
  EXPECT_EQ(CheckCommand(OnePoint(40), limits)->rfind("position (40.000, 0.000, 1.000) is more than 2.0 m outside", 0), 0u);
  EXPECT_EQ(*CheckCommand(OnePoint(10, 31), limits), "velocity 31.00 m/s is above 30 m/s");
  Command back = OnePoint(1);
  back.points.push_back(back.points[0]);
  back.points[0].t = 2.0;
  back.points[1].t = 1.0;
  EXPECT_EQ(*CheckCommand(back, limits), "point 1: time goes backwards");
  EXPECT_EQ(*CheckCommand(Command{"x", {}}, limits), "x with no points");
}

TEST(SetpointTest, ATrajectoryIsInterpolatedAndHeldAtItsEnds) {
  Command c{"trajectory_msgs/MultiDOFJointTrajectory", {}};
  for (int i = 0; i < 3; ++i) {
    Setpoint s;
    s.t = 10.0 + i;
    s.p = {double(i), 0, 1};
    s.yaw = i == 2 ? -3.0 : 3.0;  // crosses +-pi between the last two
    c.points.push_back(s);
  }
  EXPECT_DOUBLE_EQ(SampleCommand(c, 9.0).p.x(), 0.0);
  EXPECT_DOUBLE_EQ(SampleCommand(c, 10.5).p.x(), 0.5);
  EXPECT_DOUBLE_EQ(SampleCommand(c, 99).p.x(), 2.0);
  // Halfway from 3 rad to -3 rad the short way is through pi, not through 0.
  EXPECT_NEAR(std::abs(SampleCommand(c, 11.5).yaw), M_PI, 1e-9);
  EXPECT_NEAR(YawOf(Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()))), 0.7, 1e-12);
}

TEST(StackCpuTest, ProcessesAreNamedByTheirRosNodeElseTheirProgram) {
  EXPECT_EQ(ProcessDisplayName({"/ws/devel/lib/ego_planner/ego_planner_node", "__name:=ego_planner_node", "__log:=x"}),
            "ego_planner_node");
  EXPECT_EQ(ProcessDisplayName({"/usr/bin/python3", "/usr/bin/roslaunch", "--screen", "a.launch"}), "roslaunch");
  EXPECT_EQ(ProcessDisplayName({"/bin/bash", "-c", "source x"}), "bash");
  EXPECT_EQ(ProcessDisplayName({"/opt/bin/planner"}), "planner");
  EXPECT_EQ(ProcessDisplayName({}), "?");
}

}  // namespace
}  // namespace enavi::ros
