#include "ros/node/conversions.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <sensor_msgs/image_encodings.h>

namespace enavi::rosnode {
namespace {

// The byte order of this machine, as sensor_msgs/Image.is_bigendian says it.
bool HostIsBigEndian() {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 0;
}

// The pixel of type T at `p`, in this machine's byte order.
template <typename T>
T Pixel(const std::uint8_t* p, bool swap) {
  std::uint8_t b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (swap) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

}  // namespace

navstack::DepthImage ToDepthImage(const sensor_msgs::Image& msg) {
  namespace enc = sensor_msgs::image_encodings;
  const bool metres = msg.encoding == enc::TYPE_32FC1;
  const bool millimetres = msg.encoding == enc::TYPE_16UC1 || msg.encoding == enc::MONO16;
  if (!metres && !millimetres)
    throw std::invalid_argument("depth image: encoding '" + msg.encoding + "' (the node reads 32FC1 metres or 16UC1 millimetres)");
  const std::size_t bytes = metres ? 4 : 2;
  const std::size_t w = msg.width, h = msg.height;
  if (msg.step < w * bytes || msg.data.size() < h * msg.step)
    throw std::invalid_argument("depth image: " + std::to_string(msg.data.size()) + " bytes do not hold " +
                                std::to_string(h) + " rows of step " + std::to_string(msg.step) + " (" +
                                std::to_string(w) + " pixels of " + std::to_string(bytes) + " bytes)");
  const bool swap = (msg.is_bigendian != 0) != HostIsBigEndian();
  navstack::DepthImage out(static_cast<int>(w), static_cast<int>(h));
  for (std::size_t v = 0; v < h; ++v) {
    const std::uint8_t* row = msg.data.data() + v * msg.step;
    float* dst = out.data.data() + v * w;
    for (std::size_t u = 0; u < w; ++u) {
      float z = 0;
      if (metres) {
        z = Pixel<float>(row + 4 * u, swap);
        if (!std::isfinite(z) || z <= 0.0f) z = navstack::DepthImage::kNoReturn;
      } else {
        z = 1e-3f * static_cast<float>(Pixel<std::uint16_t>(row + 2 * u, swap));  // 0 stays no return
      }
      dst[u] = z;
    }
  }
  return out;
}

navstack::CameraIntrinsics ToIntrinsics(const sensor_msgs::CameraInfo& msg, double min_range, double max_range) {
  navstack::CameraIntrinsics k;
  k.width = static_cast<int>(msg.width);
  k.height = static_cast<int>(msg.height);
  k.fx = msg.K[0];
  k.fy = msg.K[4];
  k.cx = msg.K[2] + 0.5;
  k.cy = msg.K[5] + 0.5;
  k.min_range = min_range;
  k.max_range = max_range;
  if (k.width <= 0 || k.height <= 0 || !(k.fx > 0) || !(k.fy > 0))
    throw std::invalid_argument("camera_info: size " + std::to_string(k.width) + "x" + std::to_string(k.height) +
                                ", fx " + std::to_string(k.fx) + ", fy " + std::to_string(k.fy) +
                                " is not a pinhole camera (K unset?)");
  return k;
}

Eigen::Isometry3d ToIsometry(const geometry_msgs::Pose& pose) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::Quaterniond(pose.orientation.w, pose.orientation.x, pose.orientation.y, pose.orientation.z)
                   .normalized()
                   .toRotationMatrix();
  X.translation() = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
  return X;
}

navstack::VehicleState ToVehicleState(const nav_msgs::Odometry& msg, bool twist_in_world) {
  navstack::VehicleState s;
  s.t = msg.header.stamp.toSec();
  const auto& p = msg.pose.pose;
  s.p_WB = {p.position.x, p.position.y, p.position.z};
  s.q_WB = Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z).normalized();
  const auto& lin = msg.twist.twist.linear;
  const auto& ang = msg.twist.twist.angular;
  const Eigen::Vector3d v(lin.x, lin.y, lin.z), w(ang.x, ang.y, ang.z);
  s.v_WB = twist_in_world ? v : Eigen::Vector3d(s.q_WB * v);
  s.w_WB_B = twist_in_world ? Eigen::Vector3d(s.q_WB.conjugate() * w) : w;
  return s;
}

quadrotor_msgs::PositionCommand ToPositionCommand(double t, const navstack::TrajectorySample& r,
                                                  std::uint32_t trajectory_id, bool following) {
  quadrotor_msgs::PositionCommand c;
  c.header.stamp = ::ros::Time(std::max(0.0, t));
  c.header.frame_id = "world";
  c.position.x = r.p.x();
  c.position.y = r.p.y();
  c.position.z = r.p.z();
  c.velocity.x = r.v.x();
  c.velocity.y = r.v.y();
  c.velocity.z = r.v.z();
  c.acceleration.x = r.a.x();
  c.acceleration.y = r.a.y();
  c.acceleration.z = r.a.z();
  c.yaw = r.yaw;
  c.yaw_dot = r.yaw_rate;
  c.trajectory_id = trajectory_id;
  c.trajectory_flag = following ? quadrotor_msgs::PositionCommand::TRAJECTORY_STATUS_READY
                                : quadrotor_msgs::PositionCommand::TRAJECTORY_STATUS_EMPTY;
  return c;
}

}  // namespace enavi::rosnode
