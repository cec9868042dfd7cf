#pragma once
// What a ROS stack commands, as the farm's controller tracks it (docs/ros.md, "Commands"): the
// three command messages the bridge accepts, decoded into plain setpoints by the bridge's node,
// checked here, and sampled at the controller's instants. No ROS types: this is the part of the
// bridge that is tested without a master.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/state.h"

namespace enavi::ros {

/// One commanded state at sim time t. Fields the message does not carry are zero (a
/// PoseStamped setpoint has no velocity or acceleration; the controller then holds the pose).
struct Setpoint {
  double t = 0;  ///< s, sim time: the message's stamp plus the point's time_from_start
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  double yaw = 0;
  double yaw_rate = 0;
};

/// A command as it arrived: one setpoint (quadrotor_msgs/PositionCommand, geometry_msgs/
/// PoseStamped) or the points of a trajectory_msgs/MultiDOFJointTrajectory, in time order.
struct Command {
  std::string type;  ///< the ROS message type it came as
  std::vector<Setpoint> points;
};

/// Limits a command must respect; beyond them the stack is misbehaving and the episode ends
/// (end reason bad_command). Far beyond any quadrotor of the X500's class (vehicle.h: a 2 m/s
/// cruise, ~10 m/s^2 of thrust margin), so that only a broken stack meets them.
struct CommandLimits {
  Eigen::AlignedBox3d bounds;   ///< the world's flight bounds; positions may exceed them by margin_m
  double margin_m = 2.0;
  double v_max = 30.0;          ///< m/s
  double a_max = 100.0;         ///< m/s^2
  double yaw_rate_max = 50.0;   ///< rad/s
};

/// Why `command` cannot be flown (a NaN or infinite field, a position outside the bounds, a
/// velocity, acceleration or yaw rate beyond the limits, points out of time order), naming the
/// point and field; nullopt when it can.
std::optional<std::string> CheckCommand(const Command& command, const CommandLimits& limits);

/// The reference at sim time t from the newest command: a single setpoint as it is (the
/// FAST-Lab controllers track the latest PositionCommand the same way); a trajectory
/// interpolated linearly between its points (position, velocity, acceleration, yaw on the
/// shorter arc), held at its ends.
navstack::TrajectorySample SampleCommand(const Command& command, double t);

/// The yaw of a rotation (z-up world, the heading of the body x axis).
double YawOf(const Eigen::Quaterniond& q);

}  // namespace enavi::ros
