#pragma once
// How a ROS episode's processes are started (docs/ros.md, "How it runs"): the command lines and
// environments of the private master, the bag recorder and the user's stack, and the launch
// arguments the episode hands a launch file. Plain data, no ROS: tested without a master.

#include <map>
#include <set>
#include <string>
#include <vector>

#include "api/ros_stack.h"
#include "workers/ros/bridge_node.h"

namespace enavi::ros {

/// The episode's ROS directories and files.
struct EpisodeFiles {
  std::string dir;         ///< everything below lives here
  std::string ros_log;     ///< ROS_LOG_DIR
  std::string ros_home;    ///< ROS_HOME
  std::string master_log, stack_log, bag_log, supervisor_log;
  std::string bag;         ///< the bag (empty: no recording)
};
/// The files of an episode in `dir`, bag file name `bag_name` (empty: none).
EpisodeFiles FilesIn(const std::string& dir, const std::string& bag_name);

/// The environment every process of the episode gets: the caller's own (`base`, "NAME=value")
/// without its ROS_* variables, then ROS_MASTER_URI, ROS_HOSTNAME=127.0.0.1, ROS_LOG_DIR,
/// ROS_HOME, ROS_PACKAGE_PATH (the stack's package_path first), unbuffered Python output and
/// /usr/bin first in PATH (Debian's ROS is Debian's python3's; a pyenv python3 first in PATH
/// lacks rospy).
std::vector<std::string> EpisodeEnvironment(const std::vector<std::string>& base, const api::RosStack& stack,
                                            const std::string& master_uri, const EpisodeFiles& files);

/// rosmaster --core on `port`.
std::vector<std::string> MasterCommand(int port);

/// rosbag record of every topic of the episode (the stack's roles, /clock, /tf, /tf_static) into `bag`.
std::vector<std::string> BagCommand(const api::RosStack& stack, const std::string& bag);

/// The launch arguments a launch file declares at its top level (<arg name="..."> outside
/// <include> and <node> elements, comments ignored); what roslaunch accepts on its command line.
std::set<std::string> DeclaredLaunchArgs(const std::string& launch_xml);

/// What the episode offers every launch file (passed only where it declares them): start, goal
/// and start yaw; the world's bounds; map_size for planners whose map is centred on the origin
/// (Ego-Planner's grid_map: 2 x the largest |bound| per axis); the depth camera's intrinsics; the
/// board's cores (a process on the host sees the host's).
std::map<std::string, std::string> EpisodeLaunchArgs(const EpisodeGeometry& g);

/// The stack's command: roslaunch --screen FILE name:=value... (the stack's args, then the
/// episode's that the file declares and the stack does not set), or its `run` command; through
/// bash when a workspace is sourced first. `launch_xml` is the launch file's text.
std::vector<std::string> StackCommand(const api::RosStack& stack, const std::string& launch_xml,
                                      const std::map<std::string, std::string>& episode_args,
                                      const std::string& master_uri);

/// The last `max_lines` lines (at most `max_bytes`) of a log file: what the result keeps of a
/// stack that failed.
std::string LogTail(const std::string& path, std::size_t max_lines = 30, std::size_t max_bytes = 4000);

}  // namespace enavi::ros
