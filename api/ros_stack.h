#pragma once
// A user's ROS 1 navigation stack as a method of the farm (docs/ros.md): how to start it (a
// launch file or a command, the workspace to source, launch arguments) and which topics it
// speaks. Written as a stack file (YAML) or inline in a job spec:
//
//   name: ego                        # the method's name in tables, compare and the dashboard
//   launch: launch/ego.launch        # relative to this file; or run: [rosrun, pkg, node, ...]
//   workspace: ~/ws/devel/setup.bash # optional: sourced (bash) before the stack starts
//   package_path: [~/ws/src]         # optional: prepended to ROS_PACKAGE_PATH
//   args: {max_vel: "2.0"}           # launch arguments (name:=value)
//   topics: {command: /planning/pos_cmd, depth: /camera/depth}   # roles -> names (defaults below)
//   depth_encoding: 16UC1            # 32FC1 (metres) or 16UC1 (millimetres, the RealSense driver's)
//   odometry_hz: 100                 # nav_msgs/Odometry and TF rate
//   odometry_twist: body             # body (nav_msgs: the child frame) or world (the FAST-Lab stacks read it so)
//   clock_hz: 1000                   # /clock rate (Gazebo's ROS 1 plugin: every 1 ms physics step)
//   point_cloud: false               # also publish the depth frame as sensor_msgs/PointCloud2
//   startup_timeout_s: 60            # wall seconds for the stack to advertise its command topic
//   command_timeout_s: 10            # sim seconds after the start for its first command
//
// The episode runs it on the emulated clock only: its processes run in real time inside the
// board's cgroup (docs/ros.md, "How it runs").

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace YAML {
class Node;
}

namespace enavi::api {

class YamlReader;

/// A topic the bridge publishes or reads, by role.
struct RosTopicRole {
  const char* role;
  const char* default_name;
  const char* type;  ///< the ROS message type ("/"-separated), or several for the command
  const char* help;
};
/// Every role a stack file may rename, in a fixed order. /clock, /tf and /tf_static keep their
/// names (every ROS node expects them there).
const std::vector<RosTopicRole>& RosTopicRoles();

/// Every role with its default topic name.
std::map<std::string, std::string> DefaultRosTopics();

/// Depth image encodings the bridge publishes (sensor_msgs/image_encodings).
inline constexpr const char* kRosDepthEncodings[] = {"32FC1", "16UC1"};

struct RosStack {
  std::string name;                ///< the method's name
  std::string source;              ///< the stack file (or job spec) it was read from, for messages
  std::string launch;              ///< canonical path of the launch file, or empty with `run`
  std::vector<std::string> run;    ///< argv of a command instead of a launch file
  std::string workspace;           ///< canonical path of a setup.bash to source, or empty
  std::vector<std::string> package_path;  ///< canonical directories for ROS_PACKAGE_PATH
  std::map<std::string, std::string> args;    ///< launch arguments
  std::map<std::string, std::string> topics = DefaultRosTopics();  ///< every role of RosTopicRoles()
  std::string depth_encoding = "32FC1";
  double odometry_hz = 100;
  std::string odometry_twist = "body";  ///< the frame of Odometry.twist: body (base_link) or world
  double clock_hz = 1000;
  bool point_cloud = false;
  double startup_timeout_s = 60;
  double command_timeout_s = 10;

  const std::string& Topic(const std::string& role) const { return topics.at(role); }
};

/// Bad stack file: "FILE:LINE: field: reason".
class RosStackError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Reads a stack from `node` (a stack file's root, or a job spec's inline entry) with `reader`'s
/// error reporting. Relative paths resolve against `base_dir`; the launch file, the workspace
/// and the package_path directories must exist. `name` (the job spec's key) wins over a `name:`
/// field; one of them is required. Method names are lower-case identifiers that
/// `reserved` (the registered methods) must not contain.
RosStack ParseRosStack(const YamlReader& reader, const YAML::Node& node, const std::string& base_dir,
                       const std::string& name, const std::vector<std::string>& reserved);

/// Reads a stack file. @throws RosStackError naming the file, line, field and reason.
RosStack LoadRosStack(const std::string& path, const std::vector<std::string>& reserved);

void to_json(nlohmann::json& j, const RosStack& s);
void from_json(const nlohmann::json& j, RosStack& s);

}  // namespace enavi::api
