#include "workers/ros/launch_plan.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <fstream>
#include <regex>
#include <sstream>

#include "api/fixed.h"

namespace enavi::ros {
namespace {

std::string Number(double v) { return api::Fixed(v, 4); }

// Removes every `<tag ...>...</tag>` (and `<tag .../>`) element of a kind from XML text.
std::string StripElements(std::string xml, const std::string& tag) {
  for (std::size_t at = xml.find("<" + tag); at != std::string::npos; at = xml.find("<" + tag, at)) {
    const char after = at + tag.size() + 1 < xml.size() ? xml[at + tag.size() + 1] : '>';
    if (!std::isspace(static_cast<unsigned char>(after)) && after != '>' && after != '/') {
      ++at;
      continue;
    }
    const std::size_t open_end = xml.find('>', at);
    if (open_end == std::string::npos) return xml.substr(0, at);
    std::size_t end = open_end + 1;
    if (xml[open_end - 1] != '/') {
      const std::size_t close = xml.find("</" + tag, open_end);
      end = close == std::string::npos ? xml.size() : xml.find('>', close) + 1;
    }
    xml.erase(at, end - at);
  }
  return xml;
}

}  // namespace

EpisodeFiles FilesIn(const std::string& dir, const std::string& bag_name) {
  EpisodeFiles f;
  f.dir = dir;
  f.ros_log = dir + "/ros_log";
  f.ros_home = dir + "/ros_home";
  f.master_log = dir + "/master.log";
  f.stack_log = dir + "/stack.log";
  f.bag_log = dir + "/rosbag.log";
  f.supervisor_log = dir + "/supervisor.log";
  if (!bag_name.empty()) f.bag = dir + "/" + bag_name;
  return f;
}

std::vector<std::string> EpisodeEnvironment(const std::vector<std::string>& base, const api::RosStack& stack,
                                            const std::string& master_uri, const EpisodeFiles& files) {
  std::vector<std::string> env;
  std::string path = "/usr/bin:/bin", package_path;
  for (const std::string& e : base) {
    if (e.rfind("ROS_", 0) == 0 || e.rfind("PYTHONUNBUFFERED=", 0) == 0) {
      if (e.rfind("ROS_PACKAGE_PATH=", 0) == 0) package_path = e.substr(17);
      continue;
    }
    if (e.rfind("PATH=", 0) == 0) {
      path = "/usr/bin:" + e.substr(5);
      continue;
    }
    env.push_back(e);
  }
  std::string packages;
  for (const std::string& p : stack.package_path) packages += (packages.empty() ? "" : ":") + p;
  if (!package_path.empty()) packages += (packages.empty() ? "" : ":") + package_path;
  env.push_back("PATH=" + path);
  env.push_back("ROS_MASTER_URI=" + master_uri);
  env.push_back("ROS_HOSTNAME=127.0.0.1");
  env.push_back("ROS_LOG_DIR=" + files.ros_log);
  env.push_back("ROS_HOME=" + files.ros_home);
  if (!packages.empty()) env.push_back("ROS_PACKAGE_PATH=" + packages);
  env.push_back("PYTHONUNBUFFERED=1");
  env.push_back("ROSCONSOLE_STDOUT_LINE_BUFFERED=1");
  return env;
}

std::vector<std::string> MasterCommand(int port) { return {"rosmaster", "--core", "-p", std::to_string(port)}; }

std::vector<std::string> BagCommand(const api::RosStack& stack, const std::string& bag) {
  std::vector<std::string> argv = {"rosbag", "record", "--tcpnodelay", "-O", bag, "/clock", "/tf", "/tf_static"};
  for (const api::RosTopicRole& role : api::RosTopicRoles()) {
    if (std::string(role.role) == "cloud" && !stack.point_cloud) continue;
    argv.push_back(stack.Topic(role.role));
  }
  argv.push_back("__name:=enavi_rosbag");
  return argv;
}

std::set<std::string> DeclaredLaunchArgs(const std::string& launch_xml) {
  static const std::regex comment("<!--[\\s\\S]*?-->");
  std::string xml = std::regex_replace(launch_xml, comment, "");
  xml = StripElements(xml, "include");
  xml = StripElements(xml, "node");
  static const std::regex arg("<arg\\s[^>]*?name\\s*=\\s*[\"']([^\"']+)[\"']");
  std::set<std::string> out;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), arg); it != std::sregex_iterator(); ++it)
    out.insert((*it)[1].str());
  return out;
}

std::map<std::string, std::string> EpisodeLaunchArgs(const EpisodeGeometry& g) {
  std::map<std::string, std::string> a;
  const char* axes[] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    const std::string ax = axes[i];
    a["enavi_start_" + ax] = Number(g.start[i]);
    a["enavi_goal_" + ax] = Number(g.goal[i]);
    a["enavi_bounds_min_" + ax] = Number(g.bounds.min()[i]);
    a["enavi_bounds_max_" + ax] = Number(g.bounds.max()[i]);
    // A map centred on the origin in x and y, from the ground up in z, that holds the world.
    const double reach = std::max(std::abs(g.bounds.min()[i]), std::abs(g.bounds.max()[i]));
    a["enavi_map_size_" + ax] = Number(i < 2 ? 2.0 * reach : g.bounds.max()[i]);
  }
  a["enavi_start_yaw"] = Number(g.start_yaw);
  a["enavi_cores"] = std::to_string(g.cores);
  a["enavi_seed"] = std::to_string(g.seed);
  a["enavi_width"] = std::to_string(g.camera.width);
  a["enavi_height"] = std::to_string(g.camera.height);
  a["enavi_fx"] = Number(g.camera.fx);
  a["enavi_fy"] = Number(g.camera.fy);
  // ROS puts pixel centres at integer coordinates (CameraInfo), our intrinsics at +0.5.
  a["enavi_cx"] = Number(g.camera.cx - 0.5);
  a["enavi_cy"] = Number(g.camera.cy - 0.5);
  a["enavi_depth_min"] = Number(g.camera.min_range);
  a["enavi_depth_max"] = Number(g.camera.max_range);
  return a;
}

std::vector<std::string> StackCommand(const api::RosStack& stack, const std::string& launch_xml,
                                      const std::map<std::string, std::string>& episode_args,
                                      const std::string& master_uri) {
  std::vector<std::string> cmd;
  if (!stack.launch.empty()) {
    cmd = {"roslaunch", "--screen", "--skip-log-check", stack.launch};
    for (const auto& [k, v] : stack.args) cmd.push_back(k + ":=" + v);
    const std::set<std::string> declared = DeclaredLaunchArgs(launch_xml);
    for (const auto& [k, v] : episode_args)
      if (declared.count(k) && !stack.args.count(k)) cmd.push_back(k + ":=" + v);
  } else {
    cmd = stack.run;
  }
  if (stack.workspace.empty()) return cmd;
  // A catkin setup script may set its own master (ros_environment's profile scripts): ours wins.
  std::vector<std::string> out = {
      "/bin/bash", "-c",
      "source \"$0\" >/dev/null && export ROS_MASTER_URI=" + master_uri + " ROS_HOSTNAME=127.0.0.1 && exec \"$@\"",
      stack.workspace};
  out.insert(out.end(), cmd.begin(), cmd.end());
  return out;
}

std::string LogTail(const std::string& path, std::size_t max_lines, std::size_t max_bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "";
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  const std::streamoff from = std::max<std::streamoff>(0, size - static_cast<std::streamoff>(max_bytes));
  in.seekg(from);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (from > 0) {
    const auto nl = text.find('\n');
    text = nl == std::string::npos ? text : text.substr(nl + 1);
  }
  std::deque<std::string> lines;
  std::istringstream s(text);
  for (std::string line; std::getline(s, line);) {
    lines.push_back(line);
    if (lines.size() > max_lines) lines.pop_front();
  }
  std::string out;
  for (const std::string& l : lines) out += l + "\n";
  return out;
}

}  // namespace enavi::ros
