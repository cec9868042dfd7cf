// A ROS stack made to test the bridge (docs/ros.md, "Testing the bridge"): one roscpp node whose
// --mode says what it does, well or badly. It reads the bridge's odometry and goal and, in the
// flying modes, commands a straight line from where the vehicle is to the goal at --speed m/s.
//
//   position | pose | trajectory    fly to the goal with PositionCommand / PoseStamped /
//                                   MultiDOFJointTrajectory setpoints at 100 Hz
//   exit:CODE@T                     fly, then exit with CODE after T s of ROS time
//   segv@T                          fly, then crash (SIGSEGV) after T s
//   silent                          advertise the command topic, never command
//   nan@T                           fly, then command a NaN position after T s
//   far@T                           fly, then command a point 1 km outside the world after T s
//   wrong_type                      publish std_msgs/String on the command topic
//   hang                            fly; ignore SIGINT and SIGTERM
//   fork                            fly; leave a grandchild in a session of its own that ignores
//                                   SIGINT, SIGTERM and SIGHUP
//   busy:N                          hover; N threads spin on the CPU (the thread-cap measurement)
//
// Usage: enavi_test_stack --mode MODE [--speed 1.0] [--command TOPIC] plus ROS remappings.

#include <pthread.h>
#include <signal.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>
#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Odometry.h>
#include <quadrotor_msgs/PositionCommand.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <trajectory_msgs/MultiDOFJointTrajectory.h>

namespace {

struct Args {
  std::string mode = "position";
  std::string command = "/enavi/cmd";
  double speed = 1.0;
  double after = 0;  // the T of exit:CODE@T, segv@T, nan@T, far@T
  int code = 0;      // exit:CODE
  int threads = 0;   // busy:N
};

Args Parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i + 1 < argc; ++i) {
    const std::string k = argv[i];
    if (k == "--mode") a.mode = argv[++i];
    else if (k == "--speed") a.speed = std::atof(argv[++i]);
    else if (k == "--command") a.command = argv[++i];
  }
  const auto at = a.mode.find('@');
  if (at != std::string::npos) {
    a.after = std::atof(a.mode.c_str() + at + 1);
    a.mode = a.mode.substr(0, at);
  }
  if (a.mode.rfind("exit:", 0) == 0) {
    a.code = std::atoi(a.mode.c_str() + 5);
    a.mode = "exit";
  }
  if (a.mode.rfind("busy:", 0) == 0) {
    a.threads = std::atoi(a.mode.c_str() + 5);
    a.mode = "busy";
  }
  return a;
}

std::atomic<bool> g_spin{true};

void Spin(int i) {
  pthread_setname_np(pthread_self(), ("busy-" + std::to_string(i)).c_str());
  volatile double x = 1;
  while (g_spin.load(std::memory_order_relaxed)) x = std::sqrt(x + 1.0);
}

}  // namespace

int main(int argc, char** argv) {
  ::ros::init(argc, argv, "enavi_test_stack");
  const Args args = Parse(argc, argv);
  ::ros::NodeHandle nh;

  if (args.mode == "hang") {
    signal(SIGINT, SIG_IGN);
    signal(SIGTERM, SIG_IGN);
  }
  if (args.mode == "fork") {
    // A grandchild that leaves the process group and ignores every polite signal.
    if (fork() == 0) {
      setsid();
      if (fork() == 0) {
        for (int sig : {SIGINT, SIGTERM, SIGHUP}) signal(sig, SIG_IGN);
        prctl(PR_SET_NAME, "enavi-orphan");
        for (;;) pause();
      }
      _exit(0);
    }
  }
  std::vector<std::thread> spinners;
  for (int i = 0; i < args.threads; ++i) spinners.emplace_back(Spin, i);

  ::ros::Publisher wrong, pos_cmd, pose_cmd, traj_cmd;
  if (args.mode == "wrong_type") wrong = nh.advertise<std_msgs::String>(args.command, 10);
  else if (args.mode == "pose") pose_cmd = nh.advertise<geometry_msgs::PoseStamped>(args.command, 10);
  else if (args.mode == "trajectory") traj_cmd = nh.advertise<trajectory_msgs::MultiDOFJointTrajectory>(args.command, 10);
  else pos_cmd = nh.advertise<quadrotor_msgs::PositionCommand>(args.command, 10);

  bool have_odom = false, have_goal = false;
  Eigen::Vector3d p(0, 0, 0), start(0, 0, 0), goal(0, 0, 0);
  double t_start = -1;
  auto odom = nh.subscribe<nav_msgs::Odometry>("/enavi/odom", 10, [&](const nav_msgs::Odometry::ConstPtr& m) {
    p = {m->pose.pose.position.x, m->pose.pose.position.y, m->pose.pose.position.z};
    if (!have_odom) start = p;
    have_odom = true;
  });
  auto goal_sub = nh.subscribe<geometry_msgs::PoseStamped>(
      "/move_base_simple/goal", 1, [&](const geometry_msgs::PoseStamped::ConstPtr& m) {
        goal = {m->pose.position.x, m->pose.position.y, m->pose.position.z};
        have_goal = true;
      });

  ::ros::Rate rate(100.0);
  while (::ros::ok()) {
    ::ros::spinOnce();
    rate.sleep();
    const double now = ::ros::Time::now().toSec();
    if (now <= 0 || !have_odom || !have_goal) continue;
    if (t_start < 0) t_start = now;
    const double since = now - t_start;
    if (args.mode == "silent" || args.mode == "busy") {
      if (args.mode == "busy") {  // hover where it is
        quadrotor_msgs::PositionCommand c;
        c.header.stamp = ::ros::Time::now();
        c.position.x = start.x();
        c.position.y = start.y();
        c.position.z = start.z();
        pos_cmd.publish(c);
      }
      continue;
    }
    if (args.mode == "wrong_type") {
      std_msgs::String s;
      s.data = "not a command";
      wrong.publish(s);
      continue;
    }
    if (args.mode == "exit" && since >= args.after) {
      std::cerr << "enavi_test_stack: exiting with code " << args.code << std::endl;
      return args.code;
    }
    if (args.mode == "segv" && since >= args.after) {
      std::cerr << "enavi_test_stack: crashing" << std::endl;
      raise(SIGSEGV);
    }
    // A straight line from the start to the goal at the given speed.
    const Eigen::Vector3d d = goal - start;
    const double length = d.norm();
    const double s = std::min(length, args.speed * since);
    const Eigen::Vector3d dir = length > 0 ? Eigen::Vector3d(d / length) : Eigen::Vector3d::UnitX();
    Eigen::Vector3d ref = start + s * dir;
    const Eigen::Vector3d vel = s < length ? Eigen::Vector3d(args.speed * dir) : Eigen::Vector3d::Zero();
    const double yaw = std::atan2(dir.y(), dir.x());
    if (args.mode == "nan" && since >= args.after) ref.x() = std::numeric_limits<double>::quiet_NaN();
    if (args.mode == "far" && since >= args.after) ref.z() += 1000.0;
    if (args.mode == "pose") {
      geometry_msgs::PoseStamped c;
      c.header.stamp = ::ros::Time::now();
      c.header.frame_id = "world";
      c.pose.position.x = ref.x();
      c.pose.position.y = ref.y();
      c.pose.position.z = ref.z();
      c.pose.orientation.w = std::cos(yaw / 2);
      c.pose.orientation.z = std::sin(yaw / 2);
      pose_cmd.publish(c);
    } else if (args.mode == "trajectory") {
      // The next second of the line, ten points.
      trajectory_msgs::MultiDOFJointTrajectory c;
      c.header.stamp = ::ros::Time::now();
      for (int i = 0; i < 10; ++i) {
        const double si = std::min(length, s + args.speed * 0.1 * i);
        const Eigen::Vector3d pi = start + si * dir;
        trajectory_msgs::MultiDOFJointTrajectoryPoint pt;
        geometry_msgs::Transform tf;
        tf.translation.x = pi.x();
        tf.translation.y = pi.y();
        tf.translation.z = pi.z();
        tf.rotation.w = std::cos(yaw / 2);
        tf.rotation.z = std::sin(yaw / 2);
        pt.transforms.push_back(tf);
        geometry_msgs::Twist v;
        v.linear.x = si < length ? vel.x() : 0;
        v.linear.y = si < length ? vel.y() : 0;
        v.linear.z = si < length ? vel.z() : 0;
        pt.velocities.push_back(v);
        pt.accelerations.push_back(geometry_msgs::Twist());
        pt.time_from_start = ::ros::Duration(0.1 * i);
        c.points.push_back(pt);
      }
      traj_cmd.publish(c);
    } else {
      quadrotor_msgs::PositionCommand c;
      c.header.stamp = ::ros::Time::now();
      c.header.frame_id = "world";
      c.position.x = ref.x();
      c.position.y = ref.y();
      c.position.z = ref.z();
      c.velocity.x = vel.x();
      c.velocity.y = vel.y();
      c.velocity.z = vel.z();
      c.yaw = yaw;
      c.trajectory_flag = quadrotor_msgs::PositionCommand::TRAJECTORY_STATUS_READY;
      pos_cmd.publish(c);
    }
  }
  g_spin = false;
  for (auto& t : spinners) t.join();
  return 0;
}
