#pragma once
// Our navigation methods as a ROS node (docs/ros.md, "Our own stacks as ROS nodes"): the part of
// enavi_ros_node that knows no ROS. It runs a registered method (fixed, enavi, baseline) on its
// own scheduler, a RealtimeExecutor with the method's threads and policy, as the emulated
// clock's navstack process does, but in ROS time: a SteppedClock the node sets from /clock. It
// is told nothing of the board or the dilation; what a job costs is the ROS time it took
// (JobTiming::kElapsed), as a node on a real board measures it.
//
// The ROS side (main.cc, C++17: ROS 1's message headers) feeds it the converted messages and
// publishes what Sample() returns at the command rate. This header is plain C++17 too.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/camera.h"
#include "navstack/common/state.h"
#include "navstack/runtime/time_source.h"

namespace enavi::rosnode {

/// What the node is told (its private parameters; main.cc reads them).
struct NodeParams {
  std::string method = "fixed";
  std::uint64_t seed = 1;
  std::string policy;  ///< the frequency-adapter policy file of methods that use one; empty: the shipped one
  /// Tunables by their `enavi fly --set` names (navstack::StackTunablesFor), checked against their ranges.
  std::map<std::string, double> overrides;
  /// The cores the method may use (threads 0 of a method means all): 0 = this machine's.
  int cores = 0;
  Eigen::AlignedBox3d bounds;  ///< the flight bounds, required
  double depth_min = 0.2, depth_max = 10.0;  ///< the camera's range, m (CameraInfo has none)
};

/// One command for the controller: the method's reference at `t` (ROS time), and the id of the
/// trajectory it comes from (0: none yet), as traj_server's PositionCommand carries them.
struct CommandSample {
  double t = 0;
  navstack::TrajectorySample reference;
  std::uint32_t trajectory_id = 0;
  bool following = false;  ///< the reference is a trajectory's (not a hold: before the first plan, a stop)
};

class NodeCore {
 public:
  /// Checks the method, its overrides and policy (std::invalid_argument naming the parameter
  /// and why) and prepares the scheduler on `clock`; the method itself is built once the goal,
  /// the first odometry and the camera's intrinsics have arrived.
  NodeCore(const NodeParams& params, std::shared_ptr<navstack::SteppedClock> clock);
  ~NodeCore();  ///< Stop()s
  NodeCore(const NodeCore&) = delete;
  NodeCore& operator=(const NodeCore&) = delete;

  // Inputs (any thread; converted by the ROS side).
  void OnGoal(const Eigen::Vector3d& goal);
  void OnCameraInfo(const navstack::CameraIntrinsics& intrinsics);
  void OnOdometry(const navstack::VehicleState& state);
  /// The depth image and the camera pose of one frame arrive apart; a frame is handed to the
  /// method once both with the same stamp are there (with the vehicle's velocity then).
  void OnDepth(double stamp, navstack::DepthImage image);
  void OnCameraPose(double stamp, const Eigen::Isometry3d& X_WC);

  /// The method's reference now, or nullopt until it runs.
  std::optional<CommandSample> Sample();
  /// What the first failed job or commit said; empty while none did.
  std::string error() const;
  bool running() const;
  /// Threads and scheduler the method runs on, for the log.
  std::string Describe() const;
  /// Per task: released, late, skipped, mean and max job time (ROS time), the host CPU of its
  /// jobs; one line per task the method ran.
  std::string Summary() const;
  /// Stops the method's jobs (idempotent).
  void Stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace enavi::rosnode
