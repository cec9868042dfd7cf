// The Ego-Planner example (examples/ros/ego_planner, docs/ros.md section 7): what of it is ours.
// Ego-Planner itself is not in this repository, so no test here flies it; these check that the
// stack file loads as a user's would, and that its launch file gets every episode argument it
// uses from the bridge and listens on the bridge's topics.
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include <gtest/gtest.h>

#include "api/ros_stack.h"
#include "tests/unit/worlds/test_util.h"
#include "workers/ros/launch_plan.h"

namespace enavi::ros {
namespace {

namespace fs = std::filesystem;
using worlds::testing::TempDir;

const std::string kDir = ENAVI_SOURCE_DIR "/examples/ros/ego_planner";
const std::vector<std::string> kRegistered = {"baseline", "fixed", "enavi"};

std::string Read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// HOME for one test: the example names the user's workspace as ~/ego_ws/devel/setup.bash.
class ScopedHome {
 public:
  explicit ScopedHome(const std::string& home) {
    if (const char* h = std::getenv("HOME")) old_ = h;
    setenv("HOME", home.c_str(), 1);
  }
  ~ScopedHome() { old_.empty() ? unsetenv("HOME") : setenv("HOME", old_.c_str(), 1); }

 private:
  std::string old_;
};

// The enavi_* arguments a launch file substitutes somewhere ($(arg enavi_...)).
std::set<std::string> UsedEpisodeArgs(const std::string& xml) {
  static const std::regex use("\\$\\(arg\\s+(enavi_[A-Za-z0-9_]+)\\s*\\)");
  std::set<std::string> out;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), use); it != std::sregex_iterator(); ++it)
    out.insert((*it)[1].str());
  return out;
}

// Top-level arguments without a default or value: roslaunch refuses to start without them.
std::set<std::string> RequiredArgs(const std::string& xml) {
  static const std::regex arg("<arg\\s([^>]*)>");
  static const std::regex name("name\\s*=\\s*[\"']([^\"']+)[\"']");
  static const std::regex has_value("\\b(default|value)\\s*=");
  const std::set<std::string> declared = DeclaredLaunchArgs(xml);
  std::set<std::string> out;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), arg); it != std::sregex_iterator(); ++it) {
    const std::string attrs = (*it)[1].str();
    std::smatch n;
    if (std::regex_search(attrs, n, name) && declared.count(n[1].str()) && !std::regex_search(attrs, has_value))
      out.insert(n[1].str());
  }
  return out;
}

// The default of a top-level argument, or "" when it has none.
std::string ArgDefault(const std::string& xml, const std::string& arg) {
  const std::regex r("<arg\\s+name=\"" + arg + "\"\\s+default=\"([^\"]*)\"");
  std::smatch m;
  return std::regex_search(xml, m, r) ? m[1].str() : "";
}

// An episode like the bridge's for s1 (the values do not matter, the names do).
EpisodeGeometry SomeEpisode() {
  EpisodeGeometry g;
  g.start = {-22, 0, 1.5};
  g.goal = {22, -0.5, 1.5};
  g.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-30, -16, 0), Eigen::Vector3d(30, 16, 8));
  g.camera = navstack::CameraIntrinsics::DefaultStream();
  g.cores = 4;
  return g;
}

TEST(EgoPlannerExampleTest, StackFileLoadsWithTheUsersWorkspace) {
  TempDir home;
  const fs::path setup = home.Write("ego_ws/devel/setup.bash", "# a catkin workspace's setup\n");
  const ScopedHome scoped(home.path().string());
  const api::RosStack s = api::LoadRosStack(kDir + "/ego_planner.yaml", kRegistered);
  EXPECT_EQ(s.name, "ego_planner");
  EXPECT_EQ(s.launch, fs::weakly_canonical(kDir + "/ego_planner.launch").string());
  EXPECT_EQ(s.workspace, fs::weakly_canonical(setup).string());
  EXPECT_TRUE(s.run.empty());
  // grid_map reads uint16 millimetres (k_depth_scaling_factor 1000 in the launch file); the FSM
  // reads Odometry.twist as world-frame velocity.
  EXPECT_EQ(s.depth_encoding, "16UC1");
  EXPECT_EQ(s.odometry_twist, "world");
  EXPECT_NE(Read(s.launch).find("\"grid_map/k_depth_scaling_factor\" value=\"1000.0\""), std::string::npos);
}

TEST(EgoPlannerExampleTest, WithoutTheWorkspaceTheStackFileNamesTheField) {
  TempDir home;  // no ego_ws in it
  const ScopedHome scoped(home.path().string());
  try {
    api::LoadRosStack(kDir + "/ego_planner.yaml", kRegistered);
    FAIL() << "loaded without its workspace";
  } catch (const api::RosStackError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("ego_planner.yaml:"), std::string::npos) << what;
    EXPECT_NE(what.find("workspace: '~/ego_ws/devel/setup.bash': no such file"), std::string::npos) << what;
  }
}

TEST(EgoPlannerExampleTest, LaunchFileDeclaresEveryEpisodeArgumentItUsesAndTheBridgeOffersThem) {
  const std::string xml = Read(kDir + "/ego_planner.launch");
  const std::set<std::string> used = UsedEpisodeArgs(xml);
  // The goal as its one waypoint, the map's size, the depth camera's intrinsics.
  for (const char* a : {"enavi_goal_x", "enavi_goal_y", "enavi_goal_z", "enavi_map_size_x", "enavi_map_size_y",
                        "enavi_map_size_z", "enavi_fx", "enavi_fy", "enavi_cx", "enavi_cy"})
    EXPECT_TRUE(used.count(a)) << a;
  const std::set<std::string> declared = DeclaredLaunchArgs(xml);
  const auto offered = EpisodeLaunchArgs(SomeEpisode());
  for (const std::string& a : used) {
    EXPECT_TRUE(declared.count(a)) << a << " is used but not declared: the bridge would not pass it";
    EXPECT_TRUE(offered.count(a)) << a << " is no argument the bridge offers";
  }

  // roslaunch starts: every argument without a default is on the command line the bridge builds.
  api::RosStack stack;
  stack.launch = kDir + "/ego_planner.launch";
  const std::vector<std::string> cmd = StackCommand(stack, xml, offered, "http://127.0.0.1:1234/");
  const std::set<std::string> required = RequiredArgs(xml);
  EXPECT_EQ(required, used);
  for (const std::string& a : required) {
    const std::string prefix = a + ":=";
    EXPECT_TRUE(std::any_of(cmd.begin(), cmd.end(), [&](const std::string& w) { return w.rfind(prefix, 0) == 0; }))
        << a;
  }
}

TEST(EgoPlannerExampleTest, TheChecksSeeAnArgumentUsedButNotDeclared) {
  std::string xml = Read(kDir + "/ego_planner.launch");
  const std::string decl = "<arg name=\"enavi_fx\"/>";
  const std::size_t at = xml.find(decl);
  ASSERT_NE(at, std::string::npos);
  xml.erase(at, decl.size());
  EXPECT_TRUE(UsedEpisodeArgs(xml).count("enavi_fx"));
  EXPECT_FALSE(DeclaredLaunchArgs(xml).count("enavi_fx"));
  EXPECT_FALSE(RequiredArgs(xml).count("enavi_fx"));
}

TEST(EgoPlannerExampleTest, LaunchFileRemapsEgoPlannersTopicsToTheStackFilesRoles) {
  TempDir home;
  home.Write("ego_ws/devel/setup.bash", "");
  const ScopedHome scoped(home.path().string());
  const api::RosStack s = api::LoadRosStack(kDir + "/ego_planner.yaml", kRegistered);
  const std::string xml = Read(s.launch);
  EXPECT_EQ(ArgDefault(xml, "odom_topic"), s.Topic("odom"));
  EXPECT_EQ(ArgDefault(xml, "depth_topic"), s.Topic("depth"));
  EXPECT_EQ(ArgDefault(xml, "camera_pose_topic"), s.Topic("camera_pose"));
  EXPECT_EQ(ArgDefault(xml, "command_topic"), s.Topic("command"));
  // Ego-Planner's own names, each remapped to one of those.
  for (const char* from : {"/odom_world", "/grid_map/odom", "/grid_map/pose", "/grid_map/depth", "/position_cmd"})
    EXPECT_NE(xml.find(std::string("<remap from=\"") + from + "\" to=\"$(arg "), std::string::npos) << from;
  // The camera's pose from the PoseStamped (1), not from the odometry and a fixed mount (2).
  EXPECT_NE(xml.find("\"grid_map/pose_type\" value=\"1\""), std::string::npos);
}

}  // namespace
}  // namespace enavi::ros
