// Our ROS node's message conversions (ros/node/conversions.h), without a master: the bridge's
// depth encodings, CameraInfo's pixel convention, odometry's twist frames, the PositionCommand.
// C++17, as the node's ROS side.
#include "ros/node/conversions.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <sensor_msgs/image_encodings.h>

namespace enavi::rosnode {
namespace {

template <typename T>
void Put(std::vector<std::uint8_t>* data, std::size_t offset, T v, bool big_endian = false) {
  std::uint8_t b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big_endian) std::reverse(b, b + sizeof(T));
  std::memcpy(data->data() + offset, b, sizeof(T));
}

sensor_msgs::Image Image(const std::string& encoding, int w, int h, int step) {
  sensor_msgs::Image m;
  m.encoding = encoding;
  m.width = w;
  m.height = h;
  m.step = step;
  m.data.assign(static_cast<std::size_t>(h * step), 0);
  return m;
}

TEST(RosNodeConversionsTest, MetresIn32FC1WithNaNInfiniteAndNonPositiveAsNoReturn) {
  sensor_msgs::Image m = Image(sensor_msgs::image_encodings::TYPE_32FC1, 3, 2, 3 * 4 + 4);  // padded rows
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const float row0[3] = {1.25f, nan, -2.0f}, row1[3] = {0.0f, inf, 9.5f};
  for (int u = 0; u < 3; ++u) {
    Put(&m.data, static_cast<std::size_t>(4 * u), row0[u]);
    Put(&m.data, static_cast<std::size_t>(m.step + 4 * u), row1[u]);
  }
  const navstack::DepthImage d = ToDepthImage(m);
  ASSERT_EQ(d.width, 3);
  ASSERT_EQ(d.height, 2);
  EXPECT_EQ(d.at(0, 0), 1.25f);
  EXPECT_EQ(d.at(2, 1), 9.5f);
  for (const auto& [u, v] : {std::pair{1, 0}, std::pair{2, 0}, std::pair{0, 1}, std::pair{1, 1}})
    EXPECT_FALSE(navstack::DepthImage::Valid(d.at(u, v))) << u << ", " << v;
}

TEST(RosNodeConversionsTest, MillimetresIn16UC1AsTheRealSenseDriverSendsThem) {
  sensor_msgs::Image m = Image(sensor_msgs::image_encodings::TYPE_16UC1, 2, 1, 4);
  // The bridge writes round(z x 1000): 3.4567 m arrives as 3457 mm.
  Put<std::uint16_t>(&m.data, 0, static_cast<std::uint16_t>(std::lround(3.4567 * 1000)));
  Put<std::uint16_t>(&m.data, 2, 0);
  const navstack::DepthImage d = ToDepthImage(m);
  EXPECT_NEAR(d.at(0, 0), 3.4567f, 0.0005f);
  EXPECT_FALSE(navstack::DepthImage::Valid(d.at(1, 0))) << "0 mm is no return";
}

TEST(RosNodeConversionsTest, TheOtherByteOrderIsSwapped) {
  sensor_msgs::Image m = Image(sensor_msgs::image_encodings::TYPE_32FC1, 1, 1, 4);
  m.is_bigendian = 1;
  Put(&m.data, 0, 2.5f, /*big_endian=*/true);
  EXPECT_EQ(ToDepthImage(m).at(0, 0), 2.5f);
  sensor_msgs::Image mm = Image(sensor_msgs::image_encodings::TYPE_16UC1, 1, 1, 2);
  mm.is_bigendian = 1;
  Put<std::uint16_t>(&mm.data, 0, 1500, /*big_endian=*/true);
  EXPECT_FLOAT_EQ(ToDepthImage(mm).at(0, 0), 1.5f);
}

TEST(RosNodeConversionsTest, AnotherEncodingOrAShortBufferIsRefusedSayingWhy) {
  sensor_msgs::Image rgb = Image(sensor_msgs::image_encodings::RGB8, 2, 2, 6);
  try {
    ToDepthImage(rgb);
    FAIL() << "rgb8 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'rgb8'"), std::string::npos) << e.what();
  }
  sensor_msgs::Image short_buffer = Image(sensor_msgs::image_encodings::TYPE_32FC1, 4, 4, 16);
  short_buffer.data.resize(40);
  EXPECT_THROW(ToDepthImage(short_buffer), std::invalid_argument);
  sensor_msgs::Image short_step = Image(sensor_msgs::image_encodings::TYPE_32FC1, 4, 1, 8);
  EXPECT_THROW(ToDepthImage(short_step), std::invalid_argument);
}

// The bridge publishes CameraInfo in ROS's convention, pixel centres at integer coordinates
// (cx - 0.5); the node's intrinsics are the stack's again, so the same pixel is the same ray.
TEST(RosNodeConversionsTest, CameraInfoGivesBackTheStacksIntrinsics) {
  const navstack::CameraIntrinsics k = navstack::CameraIntrinsics::DefaultStream();
  sensor_msgs::CameraInfo info;
  info.width = static_cast<std::uint32_t>(k.width);
  info.height = static_cast<std::uint32_t>(k.height);
  info.K = {k.fx, 0, k.cx - 0.5, 0, k.fy, k.cy - 0.5, 0, 0, 1};
  const navstack::CameraIntrinsics got = ToIntrinsics(info, 0.2, 10.0);
  EXPECT_EQ(got.width, k.width);
  EXPECT_EQ(got.height, k.height);
  EXPECT_EQ(got.fx, k.fx);
  EXPECT_EQ(got.fy, k.fy);
  EXPECT_DOUBLE_EQ(got.cx, k.cx);
  EXPECT_DOUBLE_EQ(got.cy, k.cy);
  EXPECT_TRUE(got.PixelRay(17, 101).isApprox(k.PixelRay(17, 101), 1e-12));
  EXPECT_EQ(got.max_range, 10.0);
  sensor_msgs::CameraInfo unset;
  EXPECT_THROW(ToIntrinsics(unset, 0.2, 10.0), std::invalid_argument);
}

// A vehicle yawed 90 degrees flying along world y at 2 m/s and turning at 0.5 rad/s: the same
// state from a body twist (nav_msgs) and from a world twist (the FAST-Lab stacks).
TEST(RosNodeConversionsTest, OdometryTwistInTheBodyOrTheWorldFrameIsTheSameState) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  nav_msgs::Odometry body;
  body.header.stamp = ::ros::Time(12.5);
  body.pose.pose.position.x = 1;
  body.pose.pose.position.y = 2;
  body.pose.pose.position.z = 3;
  body.pose.pose.orientation.w = q.w();
  body.pose.pose.orientation.z = q.z();
  body.twist.twist.linear.x = 2.0;  // forward = world +y
  body.twist.twist.angular.z = 0.5;
  nav_msgs::Odometry world = body;
  world.twist.twist.linear.x = 0;
  world.twist.twist.linear.y = 2.0;
  for (const auto& [msg, in_world] : {std::pair{body, false}, std::pair{world, true}}) {
    const navstack::VehicleState s = ToVehicleState(msg, in_world);
    EXPECT_DOUBLE_EQ(s.t, 12.5);
    EXPECT_TRUE(s.p_WB.isApprox(Eigen::Vector3d(1, 2, 3)));
    EXPECT_TRUE(s.v_WB.isApprox(Eigen::Vector3d(0, 2, 0), 1e-12)) << s.v_WB.transpose();
    EXPECT_TRUE(s.w_WB_B.isApprox(Eigen::Vector3d(0, 0, 0.5), 1e-12)) << s.w_WB_B.transpose();
    EXPECT_TRUE(s.q_WB.isApprox(q));
  }
}

TEST(RosNodeConversionsTest, APositionCommandCarriesTheReferenceAsTrajServerDoes) {
  navstack::TrajectorySample r;
  r.p = {1, 2, 3};
  r.v = {0.5, 0, 0};
  r.a = {0, 0.25, 0};
  r.yaw = 0.3;
  r.yaw_rate = -0.1;
  const quadrotor_msgs::PositionCommand c = ToPositionCommand(4.25, r, 7, true);
  EXPECT_DOUBLE_EQ(c.header.stamp.toSec(), 4.25);
  EXPECT_EQ(c.header.frame_id, "world");
  EXPECT_EQ(c.position.z, 3);
  EXPECT_EQ(c.velocity.x, 0.5);
  EXPECT_EQ(c.acceleration.y, 0.25);
  EXPECT_EQ(c.yaw, 0.3);
  EXPECT_EQ(c.yaw_dot, -0.1);
  EXPECT_EQ(c.trajectory_id, 7u);
  EXPECT_EQ(c.trajectory_flag, quadrotor_msgs::PositionCommand::TRAJECTORY_STATUS_READY);
  EXPECT_EQ(c.kx[0], 0.0) << "traj_server's gains are 0 too";
  EXPECT_EQ(ToPositionCommand(0, r, 0, false).trajectory_flag, quadrotor_msgs::PositionCommand::TRAJECTORY_STATUS_EMPTY);
}

}  // namespace
}  // namespace enavi::rosnode
