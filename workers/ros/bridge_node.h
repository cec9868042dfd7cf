#pragma once
// The simulator's own ROS node, /enavi_sim (docs/ros.md, "Topics"): the hardware-in-the-loop
// host's side of a ROS episode. It publishes the episode's clock, the vehicle's odometry and TF,
// the depth camera's frames with their intrinsics and pose, and the goal, in sim time; it reads
// the stack's commands. Everything ROS is behind this class: no ROS header outside
// workers/ros/*.cc.
//
// roscpp keeps one master per process (ros::init reads the master's address once), so one
// process flies one ROS episode: `enavi fly` and the farm's episode children each are one.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "api/ros_stack.h"
#include "navstack/common/camera.h"
#include "navstack/common/state.h"
#include "workers/ros/setpoint.h"

namespace enavi::ros {

/// What the bridge tells the stack about the episode besides the streams.
struct EpisodeGeometry {
  Eigen::Vector3d start = Eigen::Vector3d::Zero();
  Eigen::Vector3d goal = Eigen::Vector3d::Zero();
  double start_yaw = 0;
  Eigen::AlignedBox3d bounds;
  navstack::CameraIntrinsics camera;
  Eigen::Isometry3d X_BC = Eigen::Isometry3d::Identity();  ///< the camera's optical frame in the body
  std::string board;
  int cores = 1;  ///< the board's cores: what nproc says on it (a process here sees the host's)
  std::uint64_t seed = 1;  ///< the episode's seed, for a stack that seeds its own randomness
};

/// What arrived on the command topic since the last look.
struct CommandInbox {
  std::optional<Command> newest;   ///< the newest well-formed command
  std::optional<std::string> error;  ///< the first bad one: wrong type, NaN, out of bounds (why)
  std::string error_kind;          ///< command_wrong_type or bad_command
  std::int64_t received = 0;       ///< all commands so far
};

class BridgeNode {
 public:
  /// Joins the master at `master_uri` (http://127.0.0.1:PORT) as /enavi_sim, sets /use_sim_time
  /// and the episode's parameters (/enavi/start, /enavi/goal, /enavi/bounds_min, /enavi/bounds_max,
  /// /enavi/camera/*, /enavi/board), advertises the streams and subscribes to the command topic.
  /// Throws std::runtime_error when the master does not answer, std::logic_error when this
  /// process already joined another master.
  BridgeNode(const api::RosStack& stack, const std::string& master_uri, const EpisodeGeometry& geometry,
             const CommandLimits& limits);
  ~BridgeNode();
  BridgeNode(const BridgeNode&) = delete;
  BridgeNode& operator=(const BridgeNode&) = delete;

  // Publishing, with sim-time stamps (called by one thread, the link's publisher).
  void PublishClock(double t);
  /// Odometry (world -> base_link; twist in base_link, as nav_msgs/Odometry specifies, or in the
  /// world frame with `odometry_twist: world`) and its /tf.
  void PublishOdometry(const navstack::VehicleState& state);
  /// The depth image, its CameraInfo and the camera's pose (and the cloud, if asked for).
  void PublishFrame(const navstack::DepthFrame& frame);
  /// The goal as a PoseStamped and as a one-pose Path (both latched).
  void PublishGoal(double t);

  /// Some node publishes on the command topic (the stack is wired up).
  bool CommandAdvertised() const;
  /// The master still answers.
  bool MasterAlive() const;
  /// What arrived on the command topic since the last call (thread-safe).
  CommandInbox TakeCommands();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace enavi::ros
