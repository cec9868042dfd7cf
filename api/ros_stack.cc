#include "api/ros_stack.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "api/json_read.h"
#include "api/yaml_read.h"

namespace enavi::api {
namespace {

namespace fs = std::filesystem;

// A path as the user wrote it: ~ is their home, a relative path is relative to the stack file.
fs::path Resolve(const std::string& value, const std::string& base_dir) {
  fs::path p(value);
  if (value == "~" || value.rfind("~/", 0) == 0) {
    const char* home = std::getenv("HOME");
    p = fs::path(home ? home : "/") / value.substr(value.size() > 1 ? 2 : 1);
  }
  if (p.is_relative()) p = fs::path(base_dir) / p;
  return fs::weakly_canonical(p);
}

std::string ExistingFile(const YamlReader& r, const YAML::Node& n, const std::string& field,
                         const std::string& base_dir) {
  const std::string value = r.String(n, field, 4096);
  const fs::path p = Resolve(value, base_dir);
  if (!fs::is_regular_file(p)) r.Fail(n, field, "'" + value + "': no such file (" + p.string() + ")");
  return p.string();
}

bool IsMethodName(const std::string& s) {
  return !s.empty() && s.size() <= 64 && std::islower(static_cast<unsigned char>(s[0])) &&
         std::all_of(s.begin(), s.end(), [](char c) {
           return std::islower(static_cast<unsigned char>(c)) || std::isdigit(static_cast<unsigned char>(c)) ||
                  c == '_' || c == '-';
         });
}

// A ROS graph resource name (ros::names::validate): [/~]?[A-Za-z][A-Za-z0-9_/]*, no "//".
bool IsTopicName(const std::string& s) {
  if (s.empty() || s.size() > 256 || s.find("//") != std::string::npos || s.back() == '/') return false;
  std::size_t i = s[0] == '/' || s[0] == '~' ? 1 : 0;
  if (i >= s.size() || !std::isalpha(static_cast<unsigned char>(s[i]))) return false;
  return std::all_of(s.begin() + static_cast<long>(i), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/';
  });
}

std::string KnownRoles() {
  std::string out;
  for (const RosTopicRole& r : RosTopicRoles()) out += (out.empty() ? "" : ", ") + std::string(r.role);
  return out;
}

}  // namespace

const std::vector<RosTopicRole>& RosTopicRoles() {
  static const std::vector<RosTopicRole> roles = {
      {"depth", "/enavi/depth/image", "sensor_msgs/Image", "the depth frame at the camera rate (depth_encoding)"},
      {"camera_info", "/enavi/depth/camera_info", "sensor_msgs/CameraInfo", "its intrinsics, with every frame"},
      {"camera_pose", "/enavi/camera/pose", "geometry_msgs/PoseStamped", "the camera's pose in the world frame, with every frame"},
      {"odom", "/enavi/odom", "nav_msgs/Odometry", "the vehicle's odometry (world -> base_link) at odometry_hz"},
      {"cloud", "/enavi/depth/points", "sensor_msgs/PointCloud2", "the frame's points in the world frame (point_cloud: true)"},
      {"goal", "/move_base_simple/goal", "geometry_msgs/PoseStamped", "the goal, latched, from the start"},
      {"goal_path", "/enavi/goal_path", "nav_msgs/Path", "the goal as a one-pose path, latched"},
      {"command", "/enavi/cmd",
       "quadrotor_msgs/PositionCommand | geometry_msgs/PoseStamped | trajectory_msgs/MultiDOFJointTrajectory",
       "what the stack commands; the farm's controller tracks it"},
  };
  return roles;
}

std::map<std::string, std::string> DefaultRosTopics() {
  std::map<std::string, std::string> out;
  for (const RosTopicRole& role : RosTopicRoles()) out[role.role] = role.default_name;
  return out;
}

RosStack ParseRosStack(const YamlReader& r, const YAML::Node& node, const std::string& base_dir,
                       const std::string& name, const std::vector<std::string>& reserved) {
  const YamlReader::Map m(r, node, "",
                          {"name", "launch", "run", "workspace", "package_path", "args", "topics", "depth_encoding",
                           "odometry_hz", "odometry_twist", "clock_hz", "point_cloud", "startup_timeout_s", "command_timeout_s"});
  RosStack s;
  s.source = r.source();
  s.name = name;
  if (m.Has("name")) {
    const std::string own = r.String(m.Get("name"), "name", 64);
    if (s.name.empty()) s.name = own;
  }
  if (s.name.empty()) r.Fail(node, "name", "missing (required: the method's name in tables)");
  if (!IsMethodName(s.name))
    r.Fail(m.Has("name") ? m.Get("name") : node, "name",
           "'" + YamlReader::Shown(s.name) + "': 1..64 characters of [a-z0-9_-], starting with a letter");
  if (std::find(reserved.begin(), reserved.end(), s.name) != reserved.end())
    r.Fail(m.Has("name") ? m.Get("name") : node, "name", "'" + s.name + "' is a registered method's name");

  if (m.Has("launch") == m.Has("run")) r.Fail(node, "launch", "give a launch file or run: [command, args...], one of them");
  if (m.Has("launch")) {
    s.launch = ExistingFile(r, m.Get("launch"), "launch", base_dir);
  } else {
    for (const YAML::Node& item : r.Items(m.Get("run"), "run")) s.run.push_back(r.String(item, "run", 4096));
    if (s.run.empty()) r.Fail(m.Get("run"), "run", "empty command");
  }
  if (m.Has("workspace")) s.workspace = ExistingFile(r, m.Get("workspace"), "workspace", base_dir);
  if (m.Has("package_path")) {
    for (const YAML::Node& item : r.Items(m.Get("package_path"), "package_path")) {
      const std::string value = r.String(item, "package_path", 4096);
      const fs::path p = Resolve(value, base_dir);
      if (!fs::is_directory(p)) r.Fail(item, "package_path", "'" + value + "': no such directory (" + p.string() + ")");
      s.package_path.push_back(p.string());
    }
  }
  if (m.Has("args")) {
    const YAML::Node& args = m.Get("args");
    if (!args.IsMap()) r.Fail(args, "args", "expected a map of launch argument: value");
    r.CheckKeys(args, "args", {});
    if (!s.run.empty()) r.Fail(args, "args", "launch arguments need a launch file (a command takes its own)");
    for (const auto& kv : args) {
      const std::string key = r.String(kv.first, "args", 128);
      if (!IsTopicName(key) || key.find('/') != std::string::npos)
        r.Fail(kv.first, "args." + key, "launch argument names are identifiers");
      s.args[key] = r.Scalar(kv.second, "args." + key);
    }
  }
  if (m.Has("topics")) {
    const YAML::Node& topics = m.Get("topics");
    if (!topics.IsMap()) r.Fail(topics, "topics", "expected a map of role: topic name");
    r.CheckKeys(topics, "topics", {});
    for (const auto& kv : topics) {
      const std::string role = r.String(kv.first, "topics", 64);
      if (!s.topics.count(role))
        r.Fail(kv.first, "topics." + role, "unknown topic role (known: " + KnownRoles() + ")");
      const std::string topic = r.String(kv.second, "topics." + role, 256);
      if (!IsTopicName(topic))
        r.Fail(kv.second, "topics." + role, "'" + YamlReader::Shown(topic) + "' is not a ROS topic name");
      s.topics[role] = topic;
    }
  }
  if (m.Has("depth_encoding")) {
    s.depth_encoding = r.String(m.Get("depth_encoding"), "depth_encoding", 16);
    if (s.depth_encoding != kRosDepthEncodings[0] && s.depth_encoding != kRosDepthEncodings[1])
      r.Fail(m.Get("depth_encoding"), "depth_encoding", "'" + s.depth_encoding + "' (known: 32FC1, 16UC1)");
  }
  if (m.Has("odometry_hz")) s.odometry_hz = r.Range(m.Get("odometry_hz"), "odometry_hz", 1, 1000);
  if (m.Has("odometry_twist")) {
    s.odometry_twist = r.String(m.Get("odometry_twist"), "odometry_twist", 16);
    if (s.odometry_twist != "body" && s.odometry_twist != "world")
      r.Fail(m.Get("odometry_twist"), "odometry_twist", "'" + s.odometry_twist + "' (known: body, world)");
  }
  if (m.Has("clock_hz")) s.clock_hz = r.Range(m.Get("clock_hz"), "clock_hz", 10, 1000);
  if (m.Has("point_cloud")) s.point_cloud = r.Bool(m.Get("point_cloud"), "point_cloud");
  if (m.Has("startup_timeout_s")) s.startup_timeout_s = r.Range(m.Get("startup_timeout_s"), "startup_timeout_s", 1, 600);
  if (m.Has("command_timeout_s")) s.command_timeout_s = r.Range(m.Get("command_timeout_s"), "command_timeout_s", 0.1, 600);
  return s;
}

RosStack LoadRosStack(const std::string& path, const std::vector<std::string>& reserved) {
  const YamlReader reader(path, [](const std::string& source, int line, const std::string& field,
                                   const std::string& reason) {
    throw RosStackError(source + ":" + std::to_string(line > 0 ? line : 1) + ": " + field + ": " + reason);
  });
  std::ifstream in(path, std::ios::binary);
  if (!in) reader.FailAtLine(1, "file", "cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  const fs::path dir = fs::weakly_canonical(fs::absolute(path)).parent_path();
  return ParseRosStack(reader, reader.Load(text.str()), dir.string(), "", reserved);
}

void to_json(nlohmann::json& j, const RosStack& s) {
  j = {{"name", s.name},
       {"source", s.source},
       {"launch", s.launch},
       {"run", s.run},
       {"workspace", s.workspace},
       {"package_path", s.package_path},
       {"args", s.args},
       {"topics", s.topics},
       {"depth_encoding", s.depth_encoding},
       {"odometry_hz", s.odometry_hz},
       {"odometry_twist", s.odometry_twist},
       {"clock_hz", s.clock_hz},
       {"point_cloud", s.point_cloud},
       {"startup_timeout_s", s.startup_timeout_s},
       {"command_timeout_s", s.command_timeout_s}};
}

void from_json(const nlohmann::json& j, RosStack& s) {
  const JsonReader r("ros stack");
  const nlohmann::json& o = r.Object(j, "ros");
  auto str = [&](const char* key) { return r.String(r.Field(o, "ros", key), JsonReader::Join("ros", key)); };
  auto num = [&](const char* key) { return r.Number(r.Field(o, "ros", key), JsonReader::Join("ros", key)); };
  auto strings = [&](const char* key) {
    std::vector<std::string> out;
    const nlohmann::json& a = r.Array(r.Field(o, "ros", key), JsonReader::Join("ros", key));
    for (std::size_t i = 0; i < a.size(); ++i) out.push_back(r.String(a[i], JsonReader::Index(JsonReader::Join("ros", key), i)));
    return out;
  };
  auto string_map = [&](const char* key) {
    std::map<std::string, std::string> out;
    for (const auto& [k, v] : r.Object(r.Field(o, "ros", key), JsonReader::Join("ros", key)).items())
      out[k] = r.String(v, JsonReader::Join(JsonReader::Join("ros", key), k));
    return out;
  };
  s = RosStack{};
  s.name = str("name");
  s.source = str("source");
  s.launch = str("launch");
  s.run = strings("run");
  s.workspace = str("workspace");
  s.package_path = strings("package_path");
  s.args = string_map("args");
  s.topics = string_map("topics");
  for (const RosTopicRole& role : RosTopicRoles())
    if (!s.topics.count(role.role)) r.Fail("ros.topics", std::string("missing role ") + role.role);
  s.depth_encoding = str("depth_encoding");
  s.odometry_hz = num("odometry_hz");
  s.odometry_twist = str("odometry_twist");
  s.clock_hz = num("clock_hz");
  s.point_cloud = r.Bool(r.Field(o, "ros", "point_cloud"), "ros.point_cloud");
  s.startup_timeout_s = num("startup_timeout_s");
  s.command_timeout_s = num("command_timeout_s");
  if (s.name.empty() || (s.launch.empty() == s.run.empty())) r.Fail("ros", "a stack names itself and one of launch, run");
}

}  // namespace enavi::api
