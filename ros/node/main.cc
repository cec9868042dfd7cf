// enavi_ros_node: one of our navigation methods (fixed, enavi, baseline) as a ROS 1 node behind
// the bridge's topics (docs/ros.md, "Our own stacks as ROS nodes"). It reads the depth image
// (32FC1 or 16UC1), camera_info, the camera's pose, odometry and the goal; it commands
// quadrotor_msgs/PositionCommand at ~command_hz (100: the FAST-Lab planners' traj_server timer),
// sampled from the method's reference. The method's jobs run on its own scheduler in ROS time
// (node_core.h); the node knows nothing of the board or the dilation.
//
// Private parameters:
//   ~method (fixed)  ~seed (1)  ~policy (the shipped one, for enavi)  ~cores (0: this machine's)
//   ~odom_twist (body | world)  ~command_hz (100)
//   ~bounds_min, ~bounds_max ([x, y, z]; default /enavi/bounds_min, /enavi/bounds_max)
//   ~depth_min, ~depth_max (m; default /enavi/camera/min_range, max_range, else 0.2, 10)
//   any other: a tunable by its `enavi fly --set` name with / for . (~planner/v_max), checked
//   against its range.
// Topics are the bridge's default names (api/ros_stack.h); remap them as usual (/enavi/odom:=...).
// Bad parameters end the node with exit code 2 and a message naming the parameter.
//
// C++17: ROS 1's message headers (std::allocator<void>::rebind is gone in C++20).

#include <pthread.h>

#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Odometry.h>
#include <quadrotor_msgs/PositionCommand.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include "api/ros_stack.h"
#include "ros/node/conversions.h"
#include "ros/node/node_core.h"

namespace {

using enavi::rosnode::NodeCore;
using enavi::rosnode::NodeParams;

struct Options {
  NodeParams core;
  bool twist_in_world = false;
  double command_hz = 100;
};

std::string DefaultTopic(const std::string& role) {
  for (const enavi::api::RosTopicRole& r : enavi::api::RosTopicRoles())
    if (role == r.role) return r.default_name;
  throw std::logic_error("no topic role " + role);
}

// A number parameter: int, double or bool (true = 1).
bool Number(const XmlRpc::XmlRpcValue& v, double* out) {
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeInt: *out = static_cast<int>(const_cast<XmlRpc::XmlRpcValue&>(v)); return true;
    case XmlRpc::XmlRpcValue::TypeDouble: *out = static_cast<double>(const_cast<XmlRpc::XmlRpcValue&>(v)); return true;
    case XmlRpc::XmlRpcValue::TypeBoolean: *out = static_cast<bool>(const_cast<XmlRpc::XmlRpcValue&>(v)) ? 1 : 0; return true;
    default: return false;
  }
}

// ~name, else the bridge's `fallback` parameter (empty: none): true when either is set.
bool Param(const std::string& name, const std::string& fallback, XmlRpc::XmlRpcValue* v) {
  return ::ros::param::get("~" + name, *v) || (!fallback.empty() && ::ros::param::get(fallback, *v));
}

double NumberParam(const std::string& name, const std::string& fallback, double def) {
  XmlRpc::XmlRpcValue v;
  if (!Param(name, fallback, &v)) return def;
  double out = 0;
  if (!Number(v, &out) || !std::isfinite(out)) throw std::invalid_argument("~" + name + ": not a finite number");
  return out;
}

Eigen::Vector3d PointParam(const std::string& name, const std::string& fallback) {
  XmlRpc::XmlRpcValue v;
  if (!Param(name, fallback, &v))
    throw std::invalid_argument("~" + name + ": not set (and no " + fallback + " from the bridge): [x, y, z] in metres");
  Eigen::Vector3d p;
  if (v.getType() != XmlRpc::XmlRpcValue::TypeArray || v.size() != 3)
    throw std::invalid_argument("~" + name + ": not a list of three numbers");
  for (int i = 0; i < 3; ++i)
    if (!Number(v[i], &p[i]) || !std::isfinite(p[i])) throw std::invalid_argument("~" + name + ": not a list of three numbers");
  return p;
}

std::string StringParam(const std::string& name, const std::string& def) {
  XmlRpc::XmlRpcValue v;
  if (!::ros::param::get("~" + name, v)) return def;
  if (v.getType() != XmlRpc::XmlRpcValue::TypeString) throw std::invalid_argument("~" + name + ": not a string");
  return static_cast<std::string>(v);
}

Options ReadOptions() {
  Options o;
  NodeParams& p = o.core;
  p.method = StringParam("method", p.method);
  const double seed = NumberParam("seed", "", 1);
  if (seed < 0 || seed != std::floor(seed) || seed > 9.007199254740992e15)
    throw std::invalid_argument("~seed: " + std::to_string(seed) + " is not a non-negative integer");
  p.seed = static_cast<std::uint64_t>(seed);
  p.policy = StringParam("policy", "");
  const double cores = NumberParam("cores", "", 0);
  if (cores < 0 || cores > 1024 || cores != std::floor(cores))
    throw std::invalid_argument("~cores: " + std::to_string(cores) + " is not an integer in [0, 1024] (0: this machine's)");
  p.cores = static_cast<int>(cores);
  const std::string twist = StringParam("odom_twist", "body");
  if (twist != "body" && twist != "world")
    throw std::invalid_argument("~odom_twist: '" + twist + "' (body: nav_msgs' child frame, or world)");
  o.twist_in_world = twist == "world";
  o.command_hz = NumberParam("command_hz", "", 100);
  if (!(o.command_hz > 0 && o.command_hz <= 1000))
    throw std::invalid_argument("~command_hz: " + std::to_string(o.command_hz) + " is outside (0, 1000]");
  p.bounds = Eigen::AlignedBox3d(PointParam("bounds_min", "/enavi/bounds_min"), PointParam("bounds_max", "/enavi/bounds_max"));
  p.depth_min = NumberParam("depth_min", "/enavi/camera/min_range", p.depth_min);
  p.depth_max = NumberParam("depth_max", "/enavi/camera/max_range", p.depth_max);

  // Every other private parameter is a tunable: ~planner/v_max is planner.v_max.
  static const std::set<std::string> own = {"method", "seed", "policy", "cores", "odom_twist", "command_hz",
                                            "bounds_min", "bounds_max", "depth_min", "depth_max"};
  const std::string ns = ::ros::this_node::getName() + "/";
  std::vector<std::string> names;
  ::ros::param::getParamNames(names);
  for (const std::string& full : names) {
    if (full.compare(0, ns.size(), ns) != 0) continue;
    const std::string name = full.substr(ns.size());
    if (own.count(name)) continue;
    std::string tunable = name;
    for (char& c : tunable)
      if (c == '/') c = '.';
    XmlRpc::XmlRpcValue v;
    double value = 0;
    if (!::ros::param::get(full, v) || !Number(v, &value))
      throw std::invalid_argument("~" + name + " (" + tunable + "): not a number");
    p.overrides[tunable] = value;
  }
  return o;
}

// Names the calling thread once (ros.threads in the result shows the node's CPU by thread name):
// roscpp's spinner threads are the callbacks' threads.
void NameThisThread(const char* name) {
  thread_local const bool named = pthread_setname_np(pthread_self(), name) == 0;
  (void)named;
}

int Fail(const std::string& what, int code) {
  std::fprintf(stderr, "enavi_ros_node: %s\n", what.c_str());
  std::fflush(stderr);
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  ::ros::init(argc, argv, "enavi_node");
  ::ros::NodeHandle nh;
  Options options;
  std::unique_ptr<NodeCore> core;
  const auto clock = std::make_shared<enavi::navstack::SteppedClock>();
  try {
    options = ReadOptions();
    core = std::make_unique<NodeCore>(options.core, clock);
  } catch (const std::invalid_argument& e) {
    // A bad parameter names itself: ~planner/v_max (planner.v_max) or the core's field.
    return Fail(std::string("bad parameter: ") + e.what() + " (tunables are private parameters, ~planner/v_max for planner.v_max)", 2);
  }
  std::printf("enavi_ros_node: %s\n", core->Describe().c_str());
  std::fflush(stdout);

  const ::ros::TransportHints hints = ::ros::TransportHints().tcpNoDelay();
  // ROS time: our own copy of /clock on a thread of its own, so that a frame waiting for running
  // jobs never holds the clock up.
  ::ros::CallbackQueue clock_queue;
  ::ros::SubscribeOptions clock_options;
  clock_options.init<rosgraph_msgs::Clock>("/clock", 1, [&clock](const rosgraph_msgs::Clock::ConstPtr& m) {
    NameThisThread("ros-clock");
    clock->Set(m->clock.toSec());
  });
  clock_options.callback_queue = &clock_queue;
  clock_options.transport_hints = hints;
  const ::ros::Subscriber clock_sub = nh.subscribe(clock_options);
  ::ros::AsyncSpinner clock_spinner(1, &clock_queue);
  clock_spinner.start();

  // Inputs, the newest of each (queue 1: a late frame is not worth having, as in the emulated
  // clock's frame slot). Messages that do not convert end the node: the bridge is the only source.
  std::atomic<int> exit_code{0};
  auto guarded = [&exit_code](const char* what, auto f) {
    NameThisThread("ros-inputs");
    try {
      f();
    } catch (const std::exception& e) {
      Fail(std::string(what) + ": " + e.what(), 1);
      exit_code = 1;
      ::ros::shutdown();
    }
  };
  const bool twist_in_world = options.twist_in_world;
  const double depth_min = options.core.depth_min, depth_max = options.core.depth_max;
  NodeCore& c = *core;
  std::vector<::ros::Subscriber> subs;
  subs.push_back(nh.subscribe<geometry_msgs::PoseStamped>(
      DefaultTopic("goal"), 1,
      [&](const geometry_msgs::PoseStamped::ConstPtr& m) {
        guarded("goal", [&] { c.OnGoal({m->pose.position.x, m->pose.position.y, m->pose.position.z}); });
      },
      ::ros::VoidConstPtr(), hints));
  subs.push_back(nh.subscribe<sensor_msgs::CameraInfo>(
      DefaultTopic("camera_info"), 1,
      [&](const sensor_msgs::CameraInfo::ConstPtr& m) {
        guarded("camera_info", [&] { c.OnCameraInfo(enavi::rosnode::ToIntrinsics(*m, depth_min, depth_max)); });
      },
      ::ros::VoidConstPtr(), hints));
  subs.push_back(nh.subscribe<nav_msgs::Odometry>(
      DefaultTopic("odom"), 1,
      [&](const nav_msgs::Odometry::ConstPtr& m) {
        guarded("odom", [&] { c.OnOdometry(enavi::rosnode::ToVehicleState(*m, twist_in_world)); });
      },
      ::ros::VoidConstPtr(), hints));
  subs.push_back(nh.subscribe<sensor_msgs::Image>(
      DefaultTopic("depth"), 1,
      [&](const sensor_msgs::Image::ConstPtr& m) {
        guarded("depth", [&] { c.OnDepth(m->header.stamp.toSec(), enavi::rosnode::ToDepthImage(*m)); });
      },
      ::ros::VoidConstPtr(), hints));
  subs.push_back(nh.subscribe<geometry_msgs::PoseStamped>(
      DefaultTopic("camera_pose"), 1,
      [&](const geometry_msgs::PoseStamped::ConstPtr& m) {
        guarded("camera_pose", [&] { c.OnCameraPose(m->header.stamp.toSec(), enavi::rosnode::ToIsometry(m->pose)); });
      },
      ::ros::VoidConstPtr(), hints));
  // Advertised last: the bridge starts sim time when the command topic appears.
  ::ros::Publisher command = nh.advertise<quadrotor_msgs::PositionCommand>(DefaultTopic("command"), 10);
  ::ros::AsyncSpinner spinner(1);
  spinner.start();

  // traj_server's timer: the reference sampled at every tick of ROS time (a late tick is not
  // made up, as roscpp's timers do not).
  std::mutex m;
  std::condition_variable cv;
  bool stop = false;
  clock->Listen(m, cv);
  std::thread commander([&] {
    pthread_setname_np(pthread_self(), "nav-command");
    std::unique_lock l(m);
    double next = 0;
    while (!stop) {
      const double now = clock->Now();
      if (now < next) {
        clock->WaitUntil(cv, l, next);
        continue;
      }
      next = (std::floor(now * options.command_hz + 1e-6) + 1) / options.command_hz;
      l.unlock();
      if (const std::string err = c.error(); !err.empty()) {
        Fail("the method failed: " + err, 1);
        exit_code = 1;
        ::ros::shutdown();
      } else if (const auto s = c.Sample()) {
        command.publish(enavi::rosnode::ToPositionCommand(s->t, s->reference, s->trajectory_id, s->following));
      }
      l.lock();
    }
  });

  ::ros::waitForShutdown();
  {
    std::lock_guard l(m);
    stop = true;
  }
  cv.notify_all();
  commander.join();
  clock->Unlisten(cv);
  spinner.stop();
  clock_spinner.stop();
  core->Stop();
  std::printf("enavi_ros_node: %s\n", core->Summary().c_str());
  std::fflush(stdout);
  return exit_code;
}
