#pragma once
// Tunable parameters of the local planner (search, B-spline optimisation, time allocation, yaw).
// One flat struct so a job spec can sweep any field by name; Validate() refuses out-of-range values.

#include <string_view>

namespace enavi::navstack {

/// The optimiser (and with it the pipeline) Plan() runs. Numeric so it can be a tunable.
enum class PlannerOptimizer : int {
  kEsdf = 0,     ///< "esdf": distance transform of the snapshot, RRT-Connect, ESDF clearance cost
  kRebound = 1,  ///< "rebound": Ego-Planner's ESDF-free optimisation with A*-guided {p, v} pairs
};

/// "esdf" / "rebound".
const char* ToString(PlannerOptimizer optimizer);
/// Parses "esdf" or "rebound" into *out; false (and *out untouched) for any other name.
bool ParsePlannerOptimizer(std::string_view name, PlannerOptimizer* out);

/// Parameters of Plan() and its parts. Defaults fit a 0.3 m quadrotor with a 10 m depth camera
/// flying at up to 2 m/s and 3 m/s^2 (paper Sec. VI). Ranges are enforced by Validate().
struct PlannerOptions {
  // Vehicle and dynamic limits.
  double robot_radius = 0.3;  ///< [m], (0, 5]
  double v_max = 2.0;         ///< [m/s], (0, 20]
  double a_max = 3.0;         ///< [m/s^2], (0, 50]

  // Planning volume (PlanningVolume()): a box of forward reach `camera_range` towards the goal,
  // `volume_back_margin` behind the start, `volume_height` tall. At 0.1 m the defaults give
  // 12 x 12 x 6 m = 864 k cells, which keeps the distance transform cheap.
  double camera_range = 10.0;       ///< [m], [1, 50]
  double volume_back_margin = 2.0;  ///< [m], [0, 20]
  double volume_height = 6.0;       ///< [m], [1, 50]
  double min_altitude = 0.5;        ///< [m] lowest z the search may use (a start below climbs first), [-1e4, 1e4]

  // Path search (OMPL RRT-Connect + deterministic shortcut).
  double search_margin = 0.1;          ///< [m] search needs clearance >= robot_radius + this, [0, 5]
  double motion_check_fraction = 0.5;  ///< motion checks every fraction x resolution, (0, 2]
  double search_range = 2.0;           ///< [m] RRT-Connect extension length, (0, 100]
  int max_search_iterations = 5000;    ///< samples drawn per search attempt, [1, 1e7]
  int max_goal_candidates = 3;         ///< local goals tried when the goal is not usable, [1, 20]
  double local_goal_search_radius = 2.0;  ///< [m] around the box exit point, [0, 20]
  double shortcut_spacing = 0.5;       ///< [m] path is densified at this spacing before the 2nd shortcut pass, (0, 10]

  // B-spline (uniform cubic): knot span dt = control_point_spacing / v_max.
  double control_point_spacing = 0.4;  ///< [m], (0, 5]

  // Optimiser (Ego-Planner-style cost on control points, L-BFGS).
  double safe_distance_margin = 0.2;   ///< [m] clearance target = robot_radius + this, [0, 5]
  double weight_smoothness = 1.0;      ///< jerk of control points, [0, 1e6]
  double weight_clearance = 20.0;      ///< (target - distance)^2 below the target, [0, 1e6]
  double weight_feasibility = 10.0;    ///< velocity / acceleration beyond the limits, [0, 1e6]
  int max_optimizer_iterations = 100;  ///< L-BFGS iterations per run, [1, 100000]
  int max_time_reallocations = 4;      ///< stretch-and-refit rounds when limits are exceeded, [0, 100]
  int max_clearance_retries = 2;       ///< re-optimisations with 4x clearance weight if the result is too close, [0, 10]

  // Which optimiser: kEsdf (0) or kRebound (1) (rebound_optimizer.h).
  PlannerOptimizer optimizer = PlannerOptimizer::kEsdf;

  // Rebound optimiser. Defaults from Ego-Planner's plan_manage/launch/advanced_param.xml
  // (optimization/lambda_smooth, lambda_collision, lambda_feasibility, dist0) and
  // bspline_optimizer.cpp (rebound_optimize: at most 20 rebounds, 3 restarts).
  double rebound_lambda_smooth = 1.0;       ///< jerk of control points, [0, 1e6]
  double rebound_lambda_collision = 0.5;    ///< {p, v} pair penalty below dist0, [0, 1e6]
  double rebound_lambda_feasibility = 0.1;  ///< per-axis velocity / acceleration excess, [0, 1e6]
  double rebound_dist0 = 0.5;               ///< [m] clearance target along v past the anchor, (0, 5]
  int max_rebounds = 20;                    ///< L-BFGS runs cut short by a new obstacle, [0, 1000]
  int max_rebound_restarts = 3;             ///< re-runs with 2x collision weight if the result collides, [0, 100]

  // Yaw: along the horizontal velocity; held below the speed threshold; rate and acceleration
  // limited.
  double yaw_speed_threshold = 0.3;  ///< [m/s], [0, 20]
  double yaw_rate_max = 2.0;         ///< [rad/s], (0, 100]
  /// [rad/s^2], (0, 1000]. What the vehicle can follow: an X500-class quadrotor's yaw torque at
  /// hover is at most k_m m g (each rotor pair between 0 and twice its hover thrust), 0.016 m x
  /// 1.5 kg x 9.81 m/s^2 = 0.235 N m, or 5.9 rad/s^2 with J_z = 0.040 kg m^2 (VehicleParams);
  /// half of it leaves the attitude controller the other half for feedback. Ego-Planner's
  /// trajectory server has no such limit (traj_server.cpp: YAW_DOT_DOT_MAX_PER_SEC is commented
  /// out) and reverses a 2 rad/s turn from one step to the next; the vehicle then fell 110 deg
  /// behind, and its camera looked away from where it flew.
  double yaw_accel_max = 3.0;
  double yaw_lookahead = 1.0;        ///< [s] heading towards the trajectory point this far ahead, [0, 10]

  /// Throws std::invalid_argument naming the field, its value and the allowed range.
  void Validate() const;
};

}  // namespace enavi::navstack
