#include "navstack/planning/planner.h"

#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "navstack/planning/bspline.h"
#include "navstack/planning/bspline_optimizer.h"
#include "navstack/planning/distance_field.h"
#include "navstack/planning/inflated_occupancy.h"
#include "navstack/planning/rebound_optimizer.h"

namespace enavi::navstack {
namespace {

using Vec3 = Eigen::Vector3d;

void CheckRequest(const PlanRequest& request) {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("PlanRequest." + what);
  };
  if (!request.grid) fail("grid: is null");
  if (!std::isfinite(request.t_start)) fail("t_start: not finite");
  if (!request.start.p.allFinite() || !request.start.v.allFinite() || !request.start.a.allFinite() ||
      !std::isfinite(request.start.yaw)) {
    fail("start: p, v, a and yaw must be finite");
  }
  if (!request.goal_W.allFinite()) fail("goal_W: not finite");
  if (request.flight_bounds_W.isEmpty() || !request.flight_bounds_W.min().allFinite() ||
      !request.flight_bounds_W.max().allFinite()) {
    fail("flight_bounds_W: empty or not finite");
  }
}

double PathLength(const std::vector<Vec3>& path) {
  double length = 0.0;
  for (std::size_t i = 1; i < path.size(); ++i) length += (path[i] - path[i - 1]).norm();
  return length;
}

}  // namespace

const char* ToString(PlanStatus status) {
  switch (status) {
    case PlanStatus::kOk: return "ok";
    case PlanStatus::kNoPath: return "no_path";
    case PlanStatus::kStartInCollision: return "start_in_collision";
    case PlanStatus::kStartOutsideGrid: return "start_outside_grid";
    case PlanStatus::kGoalUnreachable: return "goal_unreachable";
    case PlanStatus::kTrajectoryInCollision: return "trajectory_in_collision";
    case PlanStatus::kSearchTimeout: return "search_timeout";
  }
  return "unknown";
}

PlanResult Plan(const PlanRequest& request, const PlannerOptions& options) {
  options.Validate();
  CheckRequest(request);
  PlanResult result;
  const auto finish = [&result](PlanStatus status, std::string message) {
    result.status = status;
    result.message = std::move(message);
    return result;
  };

  // kEsdf: distance field of the whole snapshot, the dominant cost at fine resolutions.
  // kRebound: the occupancy as bits, inflated by search clearance (search), by the vehicle's
  // radius (what "in collision" means) and by Ego-Planner's map inflation (anchors of the pairs).
  const bool rebound = options.optimizer == PlannerOptimizer::kRebound;
  std::unique_ptr<DistanceField> field;
  std::unique_ptr<OccupancyBits> bits;
  std::unique_ptr<InflatedOccupancy> search_map, collision_map, guide_map;
  if (rebound) {
    bits = std::make_unique<OccupancyBits>(*request.grid, &result.work);
    search_map = std::make_unique<InflatedOccupancy>(
        *bits, options.robot_radius + options.search_margin, &result.work);
    collision_map = std::make_unique<InflatedOccupancy>(*bits, options.robot_radius, &result.work);
    guide_map = std::make_unique<InflatedOccupancy>(*bits, kEgoPlannerInflation, &result.work);
  } else {
    field = std::make_unique<DistanceField>(*request.grid, &result.work);
  }
  const ClearanceMap& map = rebound ? static_cast<const ClearanceMap&>(*search_map) : *field;
  const Vec3 p0 = request.start.p;
  if (!map.Box().contains(p0)) {
    return finish(PlanStatus::kStartOutsideGrid, "start lies outside the grid box");
  }
  const Eigen::AlignedBox3d bounds = SearchBounds(map, request.flight_bounds_W, options);
  if (bounds.isEmpty()) {
    return finish(PlanStatus::kStartOutsideGrid,
                  "grid box and flight bounds do not overlap above min_altitude");
  }

  // Start: in inflated space -> escape ball; below the floor / outside the bounds -> the search
  // starts from the nearest point inside and the path begins with the straight way there.
  const ClearanceRule rule = MakeClearanceRule(map, p0, options);
  result.start_escape = rule.escape_radius > 0.0;
  const Vec3 s = p0.cwiseMax(bounds.min()).cwiseMin(bounds.max());
  if (s != p0 && !SegmentIsFree(map, rule, p0, s, options, &result.work)) {
    return finish(PlanStatus::kStartInCollision,
                  "the way from the start into the flight bounds is blocked");
  }

  // Goal, or local goals on the way to it, in order.
  const std::vector<Vec3> goals = GoalCandidates(map, bounds, rule, s, request.goal_W, options,
                                                 &result.goal_is_local, &result.work);
  if (goals.empty()) {
    return finish(PlanStatus::kGoalUnreachable,
                  "neither the goal nor any local goal on the way to it is free");
  }
  // Straight line or RRT-Connect + shortcut to the first goal candidate that has a path.
  PathSearchResult search;
  for (const Vec3& goal : goals) {
    search = SearchPath(map, bounds, rule, s, goal, request.seed, options, &result.work,
                        request.over_budget);
    result.search_iterations += search.iterations;
    if (search.ok() || search.status == SearchStatus::kInvalidStart ||
        search.status == SearchStatus::kOverBudget) {
      break;
    }
  }
  if (search.status == SearchStatus::kOverBudget) {
    return finish(PlanStatus::kSearchTimeout, search.message);
  }
  if (!search.ok()) {
    const bool start_problem = search.status == SearchStatus::kInvalidStart || result.start_escape;
    return finish(start_problem ? PlanStatus::kStartInCollision : PlanStatus::kNoPath,
                  search.message);
  }
  std::vector<Vec3> path = std::move(search.path);
  if (s != p0) path.insert(path.begin(), p0);
  result.search_path = path;
  result.path_length = PathLength(path);
  result.goal_used_W = path.back();

  // Smooth, clear and feasible trajectory from the exact start state.
  const UniformBspline initial = BsplineFromPath(request.start.v, request.start.a, path,
                                                 options.v_max, options.a_max,
                                                 options.control_point_spacing);
  OptimizationSummary summary;
  std::optional<UniformBspline> spline;
  if (rebound) {
    ReboundStatus status = ReboundStatus::kOk;
    spline = OptimizeTrajectoryRebound(initial, request.start, {*collision_map, *guide_map},
                                       bounds, rule, options, request.over_budget, &result.work,
                                       &summary, &status);
    result.search_iterations += summary.astar_expansions;
    if (status == ReboundStatus::kOverBudget) {
      return finish(PlanStatus::kSearchTimeout, summary.message);
    }
    if (status == ReboundStatus::kNoGuide) {
      return finish(PlanStatus::kNoPath, "search: " + search.message + "; " + summary.message);
    }
  } else {
    spline = OptimizeTrajectory(initial, request.start, *field, rule, options, &result.work,
                                &summary);
  }
  std::ostringstream msg;
  msg << "search: " << search.message << "; optimiser: " << summary.message;
  result.min_clearance = summary.min_clearance;
  result.max_speed = summary.max_speed;
  result.max_acceleration = summary.max_acceleration;
  if (!summary.within_limits) msg << "; WARNING: dynamic limits exceeded";
  if (!summary.clearance_ok) {
    return finish(PlanStatus::kTrajectoryInCollision, msg.str());
  }
  result.trajectory = std::make_shared<Trajectory>(*spline, request.t_start, request.start.yaw, options,
                                                       request.start.yaw_rate);
  return finish(PlanStatus::kOk, msg.str());
}

}  // namespace enavi::navstack
