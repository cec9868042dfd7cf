#pragma once
// Ego-Planner-style optimisation of a uniform B-spline's control points (smoothness, clearance,
// dynamic feasibility) with L-BFGS, and time re-allocation when the limits are still exceeded.

#include <limits>
#include <string>

#include "navstack/common/state.h"
#include "navstack/common/work.h"
#include "navstack/planning/bspline.h"
#include "navstack/planning/distance_field.h"
#include "navstack/planning/path_search.h"
#include "navstack/planning/planner_options.h"

namespace enavi::navstack {

/// What the optimisation did and what it achieved.
struct OptimizationSummary {
  int lbfgs_runs = 0;
  int iterations = 0;          ///< L-BFGS iterations over all runs
  int evaluations = 0;         ///< cost evaluations over all runs
  int time_reallocations = 0;  ///< stretch-and-refit rounds
  int clearance_retries = 0;   ///< re-runs with a stronger clearance weight
  double final_cost = 0.0;
  double max_speed = 0.0;         ///< bound from the control points after the fixed start [m/s]
  double max_acceleration = 0.0;  ///< same for acceleration [m/s^2]
  double min_clearance = std::numeric_limits<double>::infinity();  ///< dense samples outside the escape ball [m]
  bool within_limits = false;  ///< max_speed <= v_max and max_acceleration <= a_max
  bool clearance_ok = false;   ///< min_clearance >= robot_radius
  // Rebound optimiser only (rebound_optimizer.h).
  int rebounds = 0;          ///< L-BFGS runs cut short because a new obstacle was met
  int astar_searches = 0;    ///< guiding A* searches run
  int astar_expansions = 0;  ///< nodes they expanded
  std::string message;
};

/// One L-BFGS run (at most options.max_optimizer_iterations iterations) over the free control
/// points: all but the first three (the start state) and the last three (rest at the end).
/// Cost = weight_smoothness * sum |Q_{i+3} - 3 Q_{i+2} + 3 Q_{i+1} - Q_i|^2 (jerk)
///      + clearance_weight * sum (d_safe - d(p))^2 over curve points p at every knot and half
///        knot with distance d(p) < d_safe = robot_radius + safe_distance_margin
///      + weight_feasibility * sum (|V_i|^2 / v^2 - 1)^2 and (|A_i|^2 / a^2 - 1)^2 over control
///        velocities / accelerations above 0.97 x the limits.
/// Adds (control points + clearance points) kOptimizerEval per cost evaluation to *work.
UniformBspline OptimizeControlPoints(const UniformBspline& spline, const DistanceField& field,
                                     const PlannerOptions& options, double clearance_weight,
                                     WorkCounts* work, OptimizationSummary* summary);

/// How far the control-point speed / acceleration bounds (V_0, V_1 and A_0 left out: the start
/// state fixes them) exceed v_max / a_max, as a time-scaling factor; 1 when within the limits.
double LimitExcessRatio(const UniformBspline& spline, const PlannerOptions& options);

/// The same curve, slowed down by factor (> 0): duration x factor, about the same knot span, start
/// (p, v, a) kept exactly, end at rest; the rest is refitted to the old curve's shape.
UniformBspline StretchTime(const UniformBspline& spline, const TrajectorySample& start,
                           double factor);

/// Smallest field distance along the curve, sampled at most every resolution / 2 of travel and at
/// least 4 times per knot span, ignoring points inside rule's escape ball. Adds one
/// kTrajectorySample per sample.
double MinClearance(const UniformBspline& spline, const DistanceField& field,
                    const ClearanceRule& rule, WorkCounts* work);

/// Optimise; while the control-point speed or acceleration bound exceeds v_max / a_max, stretch
/// time by the excess (at most 2x per round, 3x in total) and optimise again
/// (max_time_reallocations rounds in all); if the dense clearance is below robot_radius, optimise
/// again with 4x the clearance weight (max_clearance_retries times). Limits can stay exceeded when
/// the start state itself demands it (summary.within_limits false).
/// `start` is the state the initial spline starts from (its p, v, a are kept exactly).
UniformBspline OptimizeTrajectory(const UniformBspline& initial, const TrajectorySample& start,
                                  const DistanceField& field, const ClearanceRule& rule,
                                  const PlannerOptions& options, WorkCounts* work,
                                  OptimizationSummary* summary);

}  // namespace enavi::navstack
