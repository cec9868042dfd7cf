#include "workers/ros/bridge_node.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <stdexcept>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <quadrotor_msgs/PositionCommand.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2_msgs/TFMessage.h>
#include <topic_tools/shape_shifter.h>
#include <trajectory_msgs/MultiDOFJointTrajectory.h>

namespace enavi::ros {
namespace {

// Frame names (REP 105; the camera's is its optical frame, REP 103: z forward, x right, y down).
constexpr const char* kWorldFrame = "world";
constexpr const char* kBodyFrame = "base_link";
constexpr const char* kCameraFrame = "camera";

// roscpp reads the master's address once per process.
std::mutex g_init_mutex;
std::string g_master_uri;

::ros::Time Stamp(double t) { return ::ros::Time(std::max(0.0, t)); }

void Fill(geometry_msgs::Point& out, const Eigen::Vector3d& v) {
  out.x = v.x();
  out.y = v.y();
  out.z = v.z();
}
void Fill(geometry_msgs::Vector3& out, const Eigen::Vector3d& v) {
  out.x = v.x();
  out.y = v.y();
  out.z = v.z();
}
void Fill(geometry_msgs::Quaternion& out, const Eigen::Quaterniond& q) {
  out.w = q.w();
  out.x = q.x();
  out.y = q.y();
  out.z = q.z();
}
Eigen::Vector3d ToEigen(const geometry_msgs::Point& p) { return {p.x, p.y, p.z}; }
Eigen::Vector3d ToEigen(const geometry_msgs::Vector3& v) { return {v.x, v.y, v.z}; }
Eigen::Quaterniond ToEigen(const geometry_msgs::Quaternion& q) { return {q.w, q.x, q.y, q.z}; }

geometry_msgs::TransformStamped Transform(const std::string& parent, const std::string& child, const ::ros::Time& t,
                                          const Eigen::Isometry3d& X) {
  geometry_msgs::TransformStamped tf;
  tf.header.stamp = t;
  tf.header.frame_id = parent;
  tf.child_frame_id = child;
  tf.transform.translation.x = X.translation().x();
  tf.transform.translation.y = X.translation().y();
  tf.transform.translation.z = X.translation().z();
  Fill(tf.transform.rotation, Eigen::Quaterniond(X.rotation()));
  return tf;
}

// The three command types, decoded into plain setpoints at sim time.
Command Decode(const quadrotor_msgs::PositionCommand& m) {
  Setpoint s;
  s.t = m.header.stamp.toSec();
  s.p = ToEigen(m.position);
  s.v = ToEigen(m.velocity);
  s.a = ToEigen(m.acceleration);
  s.yaw = m.yaw;
  s.yaw_rate = m.yaw_dot;
  return {"quadrotor_msgs/PositionCommand", {s}};
}

Command Decode(const geometry_msgs::PoseStamped& m) {
  Setpoint s;
  s.t = m.header.stamp.toSec();
  s.p = ToEigen(m.pose.position);
  s.yaw = YawOf(ToEigen(m.pose.orientation).normalized());
  return {"geometry_msgs/PoseStamped", {s}};
}

Command Decode(const trajectory_msgs::MultiDOFJointTrajectory& m) {
  Command c{"trajectory_msgs/MultiDOFJointTrajectory", {}};
  const double t0 = m.header.stamp.toSec();
  for (const auto& point : m.points) {
    if (point.transforms.empty()) {
      Setpoint bad;
      bad.p = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
      c.points.push_back(bad);  // CheckCommand names it
      continue;
    }
    Setpoint s;
    s.t = t0 + point.time_from_start.toSec();
    s.p = ToEigen(point.transforms[0].translation);
    s.yaw = YawOf(ToEigen(point.transforms[0].rotation).normalized());
    if (!point.velocities.empty()) {
      s.v = ToEigen(point.velocities[0].linear);
      s.yaw_rate = point.velocities[0].angular.z;
    }
    if (!point.accelerations.empty()) s.a = ToEigen(point.accelerations[0].linear);
    c.points.push_back(s);
  }
  return c;
}

}  // namespace

struct BridgeNode::Impl {
  api::RosStack stack;
  EpisodeGeometry geometry;
  CommandLimits limits;
  std::unique_ptr<::ros::NodeHandle> nh;
  ::ros::CallbackQueue command_queue;
  std::unique_ptr<::ros::AsyncSpinner> spinner;
  ::ros::Publisher clock, odom, tf, tf_static, depth, info, pose, cloud, goal, goal_path;
  ::ros::Subscriber command;
  sensor_msgs::CameraInfo info_msg;
  std::mutex inbox_mutex;
  CommandInbox inbox;

  void OnCommand(const topic_tools::ShapeShifter::ConstPtr& msg) {
    const std::string type = msg->getDataType();
    std::optional<Command> decoded;
    std::string wrong;
    try {
      if (type == "quadrotor_msgs/PositionCommand" &&
          msg->getMD5Sum() == ::ros::message_traits::MD5Sum<quadrotor_msgs::PositionCommand>::value()) {
        decoded = Decode(*msg->instantiate<quadrotor_msgs::PositionCommand>());
      } else if (type == "geometry_msgs/PoseStamped") {
        decoded = Decode(*msg->instantiate<geometry_msgs::PoseStamped>());
      } else if (type == "trajectory_msgs/MultiDOFJointTrajectory") {
        decoded = Decode(*msg->instantiate<trajectory_msgs::MultiDOFJointTrajectory>());
      } else if (type == "quadrotor_msgs/PositionCommand") {
        wrong = "quadrotor_msgs/PositionCommand with MD5 " + msg->getMD5Sum() + " (the bridge's definition is " +
                ::ros::message_traits::MD5Sum<quadrotor_msgs::PositionCommand>::value() + ")";
      } else {
        wrong = type;
      }
    } catch (const std::exception& e) {
      wrong = type + " that does not decode (" + e.what() + ")";
    }
    std::lock_guard l(inbox_mutex);
    ++inbox.received;
    if (inbox.error) return;  // the first fault ends the episode; the rest changes nothing
    if (!decoded) {
      inbox.error = "the stack published " + wrong + " on " + stack.Topic("command") +
                    " (the bridge takes quadrotor_msgs/PositionCommand, geometry_msgs/PoseStamped or "
                    "trajectory_msgs/MultiDOFJointTrajectory)";
      inbox.error_kind = "command_wrong_type";
      return;
    }
    if (const auto why = CheckCommand(*decoded, limits)) {
      inbox.error = decoded->type + " on " + stack.Topic("command") + ": " + *why;
      inbox.error_kind = "bad_command";
      return;
    }
    inbox.newest = std::move(decoded);
  }
};

BridgeNode::BridgeNode(const api::RosStack& stack, const std::string& master_uri, const EpisodeGeometry& geometry,
                       const CommandLimits& limits)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.stack = stack;
  m.geometry = geometry;
  m.limits = limits;
  {
    std::lock_guard l(g_init_mutex);
    if (!g_master_uri.empty() && g_master_uri != master_uri)
      throw std::logic_error("ros: this process already joined the master at " + g_master_uri +
                             "; roscpp takes one master per process (one ROS episode per process)");
    if (g_master_uri.empty()) {
      ::ros::M_string remap{{"__master", master_uri}, {"__hostname", "127.0.0.1"}};
      ::ros::init(remap, "enavi_sim", ::ros::init_options::NoSigintHandler | ::ros::init_options::NoRosout);
      g_master_uri = master_uri;
    }
  }
  if (!::ros::master::check()) throw std::runtime_error("ros: the master at " + master_uri + " does not answer");
  // Our own node keeps wall time (it makes the clock); the stack's nodes read /use_sim_time.
  m.nh = std::make_unique<::ros::NodeHandle>();
  ::ros::param::set("/use_sim_time", true);
  const auto vec = [](const Eigen::Vector3d& v) { return std::vector<double>{v.x(), v.y(), v.z()}; };
  ::ros::param::set("/enavi/start", vec(geometry.start));
  ::ros::param::set("/enavi/start_yaw", geometry.start_yaw);
  ::ros::param::set("/enavi/goal", vec(geometry.goal));
  ::ros::param::set("/enavi/bounds_min", vec(geometry.bounds.min()));
  ::ros::param::set("/enavi/bounds_max", vec(geometry.bounds.max()));
  ::ros::param::set("/enavi/board", geometry.board);
  ::ros::param::set("/enavi/board_cores", geometry.cores);
  // XML-RPC integers are 32-bit: a larger seed goes as its decimal string.
  if (geometry.seed <= static_cast<std::uint64_t>(std::numeric_limits<int>::max()))
    ::ros::param::set("/enavi/seed", static_cast<int>(geometry.seed));
  else
    ::ros::param::set("/enavi/seed", std::to_string(geometry.seed));

  // CameraInfo: ROS puts pixel centres at integer coordinates, our intrinsics at +0.5
  // (CameraIntrinsics::PixelRay), so the principal point moves by half a pixel.
  const navstack::CameraIntrinsics& c = geometry.camera;
  sensor_msgs::CameraInfo& info = m.info_msg;
  info.header.frame_id = kCameraFrame;
  info.width = static_cast<std::uint32_t>(c.width);
  info.height = static_cast<std::uint32_t>(c.height);
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  const double cx = c.cx - 0.5, cy = c.cy - 0.5;
  info.K = {c.fx, 0, cx, 0, c.fy, cy, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {c.fx, 0, cx, 0, 0, c.fy, cy, 0, 0, 0, 1, 0};
  ::ros::param::set("/enavi/camera/width", c.width);
  ::ros::param::set("/enavi/camera/height", c.height);
  ::ros::param::set("/enavi/camera/fx", c.fx);
  ::ros::param::set("/enavi/camera/fy", c.fy);
  ::ros::param::set("/enavi/camera/cx", cx);
  ::ros::param::set("/enavi/camera/cy", cy);
  ::ros::param::set("/enavi/camera/min_range", c.min_range);
  ::ros::param::set("/enavi/camera/max_range", c.max_range);

  ::ros::NodeHandle& nh = *m.nh;
  m.clock = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  m.odom = nh.advertise<nav_msgs::Odometry>(stack.Topic("odom"), 10);
  m.tf = nh.advertise<tf2_msgs::TFMessage>("/tf", 100);
  m.tf_static = nh.advertise<tf2_msgs::TFMessage>("/tf_static", 1, /*latch=*/true);
  m.depth = nh.advertise<sensor_msgs::Image>(stack.Topic("depth"), 2);
  m.info = nh.advertise<sensor_msgs::CameraInfo>(stack.Topic("camera_info"), 2);
  m.pose = nh.advertise<geometry_msgs::PoseStamped>(stack.Topic("camera_pose"), 10);
  if (stack.point_cloud) m.cloud = nh.advertise<sensor_msgs::PointCloud2>(stack.Topic("cloud"), 2);
  m.goal = nh.advertise<geometry_msgs::PoseStamped>(stack.Topic("goal"), 1, /*latch=*/true);
  m.goal_path = nh.advertise<nav_msgs::Path>(stack.Topic("goal_path"), 1, /*latch=*/true);
  tf2_msgs::TFMessage statics;
  statics.transforms.push_back(Transform(kBodyFrame, kCameraFrame, Stamp(0), geometry.X_BC));
  m.tf_static.publish(statics);

  // Commands on their own queue and thread: the simulator's loop only takes what arrived.
  ::ros::SubscribeOptions options;
  options.init<topic_tools::ShapeShifter>(stack.Topic("command"), 10,
                                          [&m](const topic_tools::ShapeShifter::ConstPtr& msg) { m.OnCommand(msg); });
  options.callback_queue = &m.command_queue;
  options.transport_hints = ::ros::TransportHints().tcpNoDelay();
  m.command = nh.subscribe(options);
  m.spinner = std::make_unique<::ros::AsyncSpinner>(1, &m.command_queue);
  m.spinner->start();
}

BridgeNode::~BridgeNode() {
  Impl& m = *impl_;
  if (m.spinner) m.spinner->stop();
  m.command.shutdown();
  m.nh.reset();
  // The process leaves the graph; roscpp cannot join another master afterwards (see header).
  ::ros::shutdown();
}

void BridgeNode::PublishClock(double t) {
  rosgraph_msgs::Clock msg;
  msg.clock = Stamp(t);
  impl_->clock.publish(msg);
}

void BridgeNode::PublishOdometry(const navstack::VehicleState& s) {
  Impl& m = *impl_;
  const ::ros::Time stamp = Stamp(s.t);
  nav_msgs::Odometry odom;
  odom.header.stamp = stamp;
  odom.header.frame_id = kWorldFrame;
  odom.child_frame_id = kBodyFrame;
  Fill(odom.pose.pose.position, s.p_WB);
  Fill(odom.pose.pose.orientation, s.q_WB);
  const bool world = m.stack.odometry_twist == "world";
  Fill(odom.twist.twist.linear, world ? s.v_WB : Eigen::Vector3d(s.q_WB.conjugate() * s.v_WB));
  Fill(odom.twist.twist.angular, world ? Eigen::Vector3d(s.q_WB * s.w_WB_B) : s.w_WB_B);
  m.odom.publish(odom);
  Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
  X_WB.linear() = s.q_WB.toRotationMatrix();
  X_WB.translation() = s.p_WB;
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(Transform(kWorldFrame, kBodyFrame, stamp, X_WB));
  m.tf.publish(tf);
}

void BridgeNode::PublishFrame(const navstack::DepthFrame& f) {
  Impl& m = *impl_;
  const ::ros::Time stamp = Stamp(f.t);
  const navstack::DepthImage& d = f.image;
  // REP 118: 32FC1 metres with NaN where there is no return; 16UC1 millimetres with 0.
  sensor_msgs::Image img;
  img.header.stamp = stamp;
  img.header.frame_id = kCameraFrame;
  img.height = static_cast<std::uint32_t>(d.height);
  img.width = static_cast<std::uint32_t>(d.width);
  img.is_bigendian = 0;
  const std::size_t n = d.data.size();
  if (m.stack.depth_encoding == "16UC1") {
    img.encoding = sensor_msgs::image_encodings::TYPE_16UC1;
    img.step = img.width * 2;
    img.data.resize(n * 2);
    auto* out = reinterpret_cast<std::uint16_t*>(img.data.data());
    for (std::size_t i = 0; i < n; ++i) {
      const float z = d.data[i];
      out[i] = navstack::DepthImage::Valid(z) ? static_cast<std::uint16_t>(std::min(65535.0f, std::round(z * 1000.0f))) : 0;
    }
  } else {
    img.encoding = sensor_msgs::image_encodings::TYPE_32FC1;
    img.step = img.width * 4;
    img.data.resize(n * 4);
    auto* out = reinterpret_cast<float*>(img.data.data());
    for (std::size_t i = 0; i < n; ++i)
      out[i] = navstack::DepthImage::Valid(d.data[i]) ? d.data[i] : std::numeric_limits<float>::quiet_NaN();
  }
  m.depth.publish(img);
  sensor_msgs::CameraInfo info = m.info_msg;
  info.header.stamp = stamp;
  m.info.publish(info);
  geometry_msgs::PoseStamped pose;
  pose.header.stamp = stamp;
  pose.header.frame_id = kWorldFrame;
  Fill(pose.pose.position, f.X_WC.translation());
  Fill(pose.pose.orientation, Eigen::Quaterniond(f.X_WC.rotation()));
  m.pose.publish(pose);
  if (m.stack.point_cloud) {
    // The frame's returns in the world frame, unorganised (x, y, z float32).
    sensor_msgs::PointCloud2 cloud;
    cloud.header.stamp = stamp;
    cloud.header.frame_id = kWorldFrame;
    sensor_msgs::PointCloud2Modifier mod(cloud);
    mod.setPointCloud2FieldsByString(1, "xyz");
    std::size_t valid = 0;
    for (float z : d.data) valid += navstack::DepthImage::Valid(z) ? 1 : 0;
    mod.resize(valid);
    sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
    const navstack::CameraIntrinsics& c = m.geometry.camera;
    for (int v = 0; v < d.height; ++v) {
      for (int u = 0; u < d.width; ++u) {
        const float depth = d.at(u, v);
        if (!navstack::DepthImage::Valid(depth)) continue;
        const Eigen::Vector3d p_W = f.X_WC * (c.PixelRay(u, v) * depth);
        *x = static_cast<float>(p_W.x());
        *y = static_cast<float>(p_W.y());
        *z = static_cast<float>(p_W.z());
        ++x;
        ++y;
        ++z;
      }
    }
    m.cloud.publish(cloud);
  }
}

void BridgeNode::PublishGoal(double t) {
  Impl& m = *impl_;
  geometry_msgs::PoseStamped goal;
  goal.header.stamp = Stamp(t);
  goal.header.frame_id = kWorldFrame;
  Fill(goal.pose.position, m.geometry.goal);
  const Eigen::Vector3d d = m.geometry.goal - m.geometry.start;
  Fill(goal.pose.orientation, Eigen::Quaterniond(Eigen::AngleAxisd(std::atan2(d.y(), d.x()), Eigen::Vector3d::UnitZ())));
  m.goal.publish(goal);
  nav_msgs::Path path;
  path.header = goal.header;
  path.poses.push_back(goal);
  m.goal_path.publish(path);
}

bool BridgeNode::CommandAdvertised() const { return impl_->command.getNumPublishers() > 0; }

bool BridgeNode::MasterAlive() const { return ::ros::master::check(); }

CommandInbox BridgeNode::TakeCommands() {
  Impl& m = *impl_;
  std::lock_guard l(m.inbox_mutex);
  CommandInbox out = m.inbox;
  m.inbox.newest.reset();
  return out;
}

}  // namespace enavi::ros
