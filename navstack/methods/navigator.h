#pragma once
// What every navigation method is to the episode: frames and odometry in, a reference out, events
// and counters for the results (the plug-in interface of navstack/methods/method.h), and the
// options every method is built from.

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/camera.h"
#include "navstack/common/state.h"
#include "navstack/planning/planner_options.h"
#include "navstack/planning/trajectory.h"

namespace enavi::navstack {
namespace rl {
class NavPolicyNet;
struct PolicyFile;
struct Rollout;
class DecisionPort;
}  // namespace rl

/// Task configuration: fixed for `fixed`, changed by E-Navi's strategy controller; for other
/// methods what their tasks run at (for the time series).
struct TaskRates {
  double f_per = 30.0;   ///< perception (map update), Hz
  double f_plan = 20.0;  ///< planning timer, Hz; 0: planning only on triggers
  double f_col = 0.0;    ///< collision check, Hz; 0 with collision_on_map_update: after every map update
  double f_dif = 0.0;    ///< difference detection, Hz; 0: off
  bool collision_on_map_update = true;
  double resolution = 0.1;  ///< map resolution, m
};

/// What every method is built from: the flight (camera, sensor rate, goal, bounds, seed), the
/// planner tunables every method accepts (planner.*: limits, robot radius), and the method's own
/// tunables. A method's internals (our stack's NavStackOptions, the baseline's grid map) are its
/// factory's business.
struct MethodOptions {
  /// The depth stream the method reads (and the simulator renders): 320x240 by default.
  CameraIntrinsics camera = CameraIntrinsics::DefaultStream();
  double f_sen = 30.0;  ///< sensor rate, Hz
  Eigen::Vector3d goal = Eigen::Vector3d::Zero();
  Eigen::AlignedBox3d flight_bounds;
  std::uint64_t seed = 1;
  /// Limits and robot radius; planner.v_max is also the nominal speed the episode's timeout reads.
  PlannerOptions planner;
  /// The perception.* overrides of a job (absent: the method's own choice).
  std::optional<int> perception_stride;
  std::optional<double> perception_max_range;
  /// The frequency-adapter policy (methods with MethodInfo::uses_policy), else null.
  std::shared_ptr<const rl::PolicyFile> policy;
  /// Record a training rollout (methods with MethodInfo::records_rollouts; read by rollout()).
  bool record_rollout = false;
  /// Decisions taken outside the method (the Python envs), or null.
  rl::DecisionPort* decisions = nullptr;
  /// The navigation policy (methods with MethodInfo::uses_nav_policy), else null.
  std::shared_ptr<const rl::NavPolicyNet> nav_policy;
  /// The method's own tunables by name (MethodInfo::tunables), defaults filled in and ranges
  /// checked by ConfigureMethod() and ApplyOverride().
  std::map<std::string, double> params;

  /// The value of method tunable `name`. @throws std::logic_error if the method never declared it.
  double Param(const std::string& name) const {
    const auto it = params.find(name);
    if (it == params.end()) throw std::logic_error("method parameter '" + name + "' was never declared");
    return it->second;
  }
};

struct NavEvent {
  double t = 0;
  std::string kind;
  std::string detail;
};

/// One navigation method running on a TaskExecutor (which it registers its jobs with and which
/// must outlive it).
class Navigator {
 public:
  virtual ~Navigator() = default;

  /// A new sensor frame (call at capture time, before advancing the executor).
  virtual void OnFrame(DepthFramePtr frame) = 0;
  /// Latest odometry.
  virtual void OnState(const VehicleState& state) = 0;
  /// What the flight controller tracks at time t.
  virtual TrajectorySample Reference(double t) const = 0;
  /// Events since the last call. Kinds every method uses for the results: "replan" (detail: the
  /// trigger), "plan_failed", "emergency_stop".
  virtual std::vector<NavEvent> TakeEvents() = 0;

  /// What the tasks run at now, and the map's resolution (time series).
  virtual TaskRates rates() const = 0;
  virtual double map_resolution() const = 0;
  /// The trajectory being followed, or null.
  virtual std::shared_ptr<const Trajectory> trajectory() const = 0;
  virtual std::int64_t plan_failures() const = 0;

  /// The episode ended (learning methods close their rollout).
  virtual void FinishEpisode(bool /*collided*/, bool /*reached_goal*/) {}
  /// The rollout recorded for training, or null.
  virtual const rl::Rollout* rollout() const { return nullptr; }
};

}  // namespace enavi::navstack
