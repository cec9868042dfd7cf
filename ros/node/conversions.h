#pragma once
// Our ROS node's messages to and from the navigation stack's types (docs/ros.md, "Topics"): the
// bridge's depth image in either encoding, its CameraInfo, the camera's pose, odometry with the
// twist in either frame, the goal; and the PositionCommand it sends back. C++17: ROS 1's
// message headers do not compile as C++20.

#include <cstdint>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Odometry.h>
#include <quadrotor_msgs/PositionCommand.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include "navstack/common/camera.h"
#include "navstack/common/state.h"

namespace enavi::rosnode {

/// A depth image as the stack reads it (z-depth in metres, 0 = no return): 32FC1 metres (NaN,
/// infinite or non-positive = no return) or 16UC1 millimetres (0 = no return), REP 118; rows
/// may be padded (step), either byte order. @throws std::invalid_argument for another encoding
/// or a buffer that does not hold height x step bytes.
navstack::DepthImage ToDepthImage(const sensor_msgs::Image& msg);

/// A pinhole camera from CameraInfo's K (ROS puts pixel centres at integer coordinates, the
/// stack at +0.5) with the given range (CameraInfo carries none). @throws std::invalid_argument
/// for a zero size or focal length.
navstack::CameraIntrinsics ToIntrinsics(const sensor_msgs::CameraInfo& msg, double min_range, double max_range);

/// The vehicle's state: pose world -> body; the twist is in the body frame (nav_msgs/Odometry's
/// child frame) unless `twist_in_world` (what the FAST-Lab stacks publish and read).
navstack::VehicleState ToVehicleState(const nav_msgs::Odometry& msg, bool twist_in_world);

Eigen::Isometry3d ToIsometry(const geometry_msgs::Pose& pose);

/// traj_server's message (the FAST-Lab planners): the reference's position, velocity,
/// acceleration, yaw and yaw rate stamped `t`, in `world`, with the trajectory's id; flagged
/// READY while a trajectory is followed, EMPTY otherwise. The gains stay 0 (traj_server sends
/// 0 too; the farm's controller has its own).
quadrotor_msgs::PositionCommand ToPositionCommand(double t, const navstack::TrajectorySample& reference,
                                                  std::uint32_t trajectory_id, bool following);

}  // namespace enavi::rosnode
