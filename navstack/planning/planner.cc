#include "navstack/planning/planner.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "navstack/planning/bspline.h"
#include "navstack/planning/bspline_optimizer.h"
#include "navstack/planning/distance_field.h"

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

  // Distance field of the whole snapshot: the dominant cost at fine resolutions.
  const DistanceField field(*request.grid, &result.work);
  const Vec3 p0 = request.start.p;
  if (!field.Box().contains(p0)) {
    return finish(PlanStatus::kStartOutsideGrid, "start lies outside the grid box");
  }
  const Eigen::AlignedBox3d bounds = SearchBounds(field, request.flight_bounds_W, options);
  if (bounds.isEmpty()) {
    return finish(PlanStatus::kStartOutsideGrid,
                  "grid box and flight bounds do not overlap above min_altitude");
  }

  // Start: in inflated space -> escape ball; below the floor / outside the bounds -> the search
  // starts from the nearest point inside and the path begins with the straight way there.
  const ClearanceRule rule = MakeClearanceRule(field, p0, options);
  result.start_escape = rule.escape_radius > 0.0;
  const Vec3 s = p0.cwiseMax(bounds.min()).cwiseMin(bounds.max());
  if (s != p0 && !SegmentIsFree(field, rule, p0, s, options, &result.work)) {
    return finish(PlanStatus::kStartInCollision,
                  "the way from the start into the flight bounds is blocked");
  }

  // Goal, or local goals on the way to it, in order.
  const std::vector<Vec3> goals = GoalCandidates(field, bounds, rule, s, request.goal_W, options,
                                                 &result.goal_is_local, &result.work);
  if (goals.empty()) {
    return finish(PlanStatus::kGoalUnreachable,
                  "neither the goal nor any local goal on the way to it is free");
  }
  PathSearchResult search;
  for (const Vec3& goal : goals) {
    search = SearchPath(field, bounds, rule, s, goal, request.seed, options, &result.work);
    result.search_iterations += search.iterations;
    if (search.ok() || search.status == SearchStatus::kInvalidStart) break;
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
  const UniformBspline spline = OptimizeTrajectory(initial, request.start, field, rule, options,
                                                   &result.work, &summary);
  result.min_clearance = summary.min_clearance;
  result.max_speed = summary.max_speed;
  result.max_acceleration = summary.max_acceleration;
  std::ostringstream msg;
  msg << "search: " << search.message << "; optimiser: " << summary.message;
  if (!summary.within_limits) msg << "; WARNING: dynamic limits exceeded";
  if (!summary.clearance_ok) {
    return finish(PlanStatus::kTrajectoryInCollision, msg.str());
  }
  result.trajectory = std::make_shared<Trajectory>(spline, request.t_start, request.start.yaw, options);
  return finish(PlanStatus::kOk, msg.str());
}

}  // namespace enavi::navstack
