#pragma once
// Ego-Planner's ESDF-free B-spline optimisation ("rebound", Zhou et al., EGO-Planner, RA-L 2021;
// ZJU-FAST-Lab/ego-planner, bspline_opt/src/bspline_optimizer.cpp), on inflated occupancy.
//
// What Ego-Planner does (bspline_optimizer.cpp, planner_manager.cpp reboundReplan):
//  1. initControlPoints: walks the control polygon of the initial B-spline (a polynomial from the
//     start to the local target) through the inflated map and cuts it into segments that pass
//     through obstacles; for each, an A* search (dyn_a_star.cpp) between the free control points
//     before and after gives a guiding path around the obstacle. Every control point Q_j of the
//     segment gets a {p, v} pair: v points from Q_j to where the plane through Q_j normal to
//     Q_{j+1} - Q_{j-1} cuts the A* path, p is the obstacle surface on the way there. Control points
//     of the segment without a pair take their neighbour's.
//  2. rebound_optimize: L-BFGS (at most 200 iterations, g_epsilon 0.01, memory 16) on
//     lambda_smooth x jerk + lambda_collision x sum over pairs of a penalty of d = (Q_j - p) . v
//     below dist0 (cubic, quadratic beyond dist0) + lambda_feasibility x per-axis velocity /
//     acceleration excess. After 3 evaluations, once the curve is smooth, every evaluation checks
//     the control points again (check_collision_and_rebound); one in an obstacle not covered by
//     its pairs is a new obstacle: new A* and pairs, and the run stops and restarts ("rebound",
//     at most 20 times). A converged curve that still hits the map is re-segmented with twice the
//     collision weight (at most 3 restarts).
//  3. refineTrajAlgo: if the limits are exceeded, time is stretched and the curve refitted.
// What we do differently: our initial path is the straight line (or the climb into the flight
// bounds then the line) timed by BsplineFromPath; the map is inflated by the vehicle's radius on
// demand (InflatedOccupancy) instead of by 0.099 m in the map; the whole curve is checked, not its
// first 2/3 (we return one trajectory to the goal, Ego-Planner re-plans it every 1.5 m); the
// checks are exact distance probes near obstacles; time re-allocation is StretchTime (refit to
// the old shape) followed by another rebound optimisation instead of Ego-Planner's fitness term;
// the L-BFGS iteration bound is options.max_optimizer_iterations; the A*'s 0.2 s limit is the
// caller's work budget (board time).

#include "navstack/common/state.h"
#include "navstack/common/work.h"
#include "navstack/planning/bspline.h"
#include "navstack/planning/bspline_optimizer.h"
#include "navstack/planning/inflated_occupancy.h"
#include "navstack/planning/path_search.h"
#include "navstack/planning/planner_options.h"

namespace enavi::navstack {

enum class ReboundStatus {
  kOk,          ///< optimised; summary says whether it is clear and within the limits
  kNoGuide,     ///< an obstacle on the initial path has no way around it (A* found none)
  kOverBudget,  ///< an A* search was stopped by the work budget
};

/// The two inflations of the grid the rebound optimiser reads.
struct ReboundMaps {
  /// Inflated by the vehicle's radius: what "in collision" means for the segments, the rebound
  /// check, the A* and the final check.
  const InflatedOccupancy& collision;
  /// Inflated by Ego-Planner's map inflation (kEgoPlannerInflation): the anchors of the pairs, so
  /// that dist0 is measured from (nearly) the obstacle's surface as in Ego-Planner.
  const InflatedOccupancy& guide;
};

/// Ego-Planner's grid_map/obstacles_inflation (advanced_param.xml) [m].
constexpr double kEgoPlannerInflation = 0.099;

/// Rebound optimisation of `initial` (which starts at `start`'s p, v, a) on maps, A* searches
/// inside bounds, then time re-allocation as OptimizeTrajectory does. summary->min_clearance is the exact clearance of dense curve
/// samples outside rule's escape ball, capped at options.robot_radius (only the collision test
/// is measured); clearance_ok says no sample is closer than robot_radius.
/// Adds kOptimizerEval (control points + pairs per cost evaluation), kAstarExpansion,
/// kTrajectorySample and, through the maps, kCellProbe / kStateCheck to *work.
UniformBspline OptimizeTrajectoryRebound(const UniformBspline& initial, const TrajectorySample& start,
                                         const ReboundMaps& maps,
                                         const Eigen::AlignedBox3d& bounds, const ClearanceRule& rule,
                                         const PlannerOptions& options, const OverBudget& over_budget,
                                         WorkCounts* work, OptimizationSummary* summary,
                                         ReboundStatus* status);

}  // namespace enavi::navstack
