#pragma once
// Geometric path search in 3-D over a clearance map (distance field or inflated occupancy): OMPL RRT-Connect with an iteration budget
// and a per-call seed (bit-identical results), then a deterministic shortcut. Also the choice of
// the planning volume and of a local goal when the final goal is not usable. No OMPL type
// appears in this header.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/work.h"
#include "navstack/planning/clearance_map.h"
#include "navstack/planning/distance_field.h"
#include "navstack/planning/planner_options.h"

namespace enavi::navstack {

/// Clearance a point needs to be valid: `required` everywhere, except inside the escape ball
/// around a start that lies in inflated space (late map updates), where `escape_required`
/// (lower) applies so that the vehicle can leave it.
struct ClearanceRule {
  double required = 0.0;
  Eigen::Vector3d escape_center = Eigen::Vector3d::Zero();
  double escape_radius = 0.0;  ///< 0: no escape ball
  double escape_required = 0.0;

  double RequiredAt(const Eigen::Vector3d& p_W) const {
    return (p_W - escape_center).squaredNorm() < escape_radius * escape_radius ? escape_required
                                                                                : required;
  }
  bool InEscapeBall(const Eigen::Vector3d& p_W) const {
    return (p_W - escape_center).squaredNorm() < escape_radius * escape_radius;
  }
};

/// Rule for a search from p_start with clearance robot_radius + search_margin; if p_start has less
/// than that, an escape ball of radius (required - clearance) + 2 resolutions lets the path leave
/// while not getting closer than (start clearance - resolution / 2).
ClearanceRule MakeClearanceRule(const ClearanceMap& map, const Eigen::Vector3d& p_start,
                                const PlannerOptions& options);

/// The box the caller should extract from the map for a plan from `start` towards `goal`: reaching
/// options.camera_range ahead along the horizontal goal direction (less if the goal is nearer),
/// volume_back_margin behind, (camera_range + volume_back_margin) wide and volume_height tall,
/// centred in z between start and goal; shifted (not shrunk) to lie inside flight_bounds where it
/// fits, clipped where it does not. With the defaults it holds <= 864 k cells at 0.1 m.
Eigen::AlignedBox3d PlanningVolume(const Eigen::Vector3d& start, const Eigen::Vector3d& goal,
                                   const Eigen::AlignedBox3d& flight_bounds,
                                   const PlannerOptions& options);

/// States a search may visit: the map's box intersected with flight_bounds, floor raised to
/// options.min_altitude, shrunk by 1e-6 m so clamped points stay inside. May be empty.
Eigen::AlignedBox3d SearchBounds(const ClearanceMap& map,
                                 const Eigen::AlignedBox3d& flight_bounds,
                                 const PlannerOptions& options);

/// True if every point from a to b, checked every options.motion_check_fraction x resolution
/// (b included, a excluded), meets rule. Adds one kStateCheck per point checked.
bool SegmentIsFree(const ClearanceMap& map, const ClearanceRule& rule,
                   const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                   const PlannerOptions& options, WorkCounts* work);

enum class SearchStatus { kOk, kNoPath, kInvalidStart, kInvalidGoal, kOverBudget };

/// Budget hook of a search: called with everything the plan has done so far (its WorkCounts,
/// including the running search) once per search iteration; true stops the search. The caller
/// prices the counts in board time, so a time limit holds on any clock.
using OverBudget = std::function<bool(const WorkCounts&)>;

struct PathSearchResult {
  SearchStatus status = SearchStatus::kNoPath;
  std::string message;
  std::vector<Eigen::Vector3d> path;  ///< start .. goal, shortcut; empty unless kOk
  int iterations = 0;                 ///< samples drawn by RRT-Connect (0 if the straight line was free)
  bool ok() const { return status == SearchStatus::kOk; }
};

/// Path from start to goal inside bounds whose segments satisfy rule. The straight line is tried
/// first; otherwise RRT-Connect (OMPL, linear nearest-neighbour search, own seeded sampler) runs
/// until connected or options.max_search_iterations samples, then the path is shortcut.
/// Same inputs and seed -> bit-identical path, whatever ran before in the process.
/// Adds kPlannerIteration per sample and kStateCheck per state checked to *work. If over_budget
/// is set, it is asked before every sample with *work plus the running counts; true ends the
/// search with kOverBudget.
/// @pre start and goal inside bounds (kInvalidStart / kInvalidGoal otherwise, also when they
/// violate rule).
PathSearchResult SearchPath(const ClearanceMap& map, const Eigen::AlignedBox3d& bounds,
                            const ClearanceRule& rule, const Eigen::Vector3d& start,
                            const Eigen::Vector3d& goal, std::uint32_t seed,
                            const PlannerOptions& options, WorkCounts* work,
                            const OverBudget& over_budget = {});

/// Deterministic shortcut: greedy "furthest vertex reachable by a free segment" from each kept
/// vertex, then the same again on the path densified at options.shortcut_spacing.
std::vector<Eigen::Vector3d> ShortcutPath(const std::vector<Eigen::Vector3d>& path,
                                          const ClearanceMap& map, const ClearanceRule& rule,
                                          const PlannerOptions& options, WorkCounts* work);

/// Goals to try, in order. If goal lies inside bounds and satisfies rule: {goal} and
/// *is_local = false. Otherwise (*is_local = true) up to options.max_goal_candidates valid points
/// on the way to it: the point where the segment start->goal leaves bounds (or the goal itself
/// when inside), the valid cell nearest to that point within local_goal_search_radius, and the
/// last valid point walking back from it towards the start. Empty if none is valid.
/// Adds kStateCheck per cell or point evaluated.
std::vector<Eigen::Vector3d> GoalCandidates(const ClearanceMap& map,
                                            const Eigen::AlignedBox3d& bounds,
                                            const ClearanceRule& rule,
                                            const Eigen::Vector3d& start,
                                            const Eigen::Vector3d& goal,
                                            const PlannerOptions& options, bool* is_local,
                                            WorkCounts* work);

/// Levels of OMPL's console messages.
enum class OmplLogLevel { kDebug = 0, kInfo = 1, kWarn = 2, kError = 3 };
using OmplLogSink = std::function<void(OmplLogLevel level, const std::string& message)>;

/// Routes OMPL's messages at or above min_level to sink (an empty sink drops them all). Until this
/// is called, the first search sets OMPL to print only warnings and errors (to stderr).
/// Process-wide, like OMPL's own console.
void RouteOmplLog(OmplLogSink sink, OmplLogLevel min_level = OmplLogLevel::kWarn);

}  // namespace enavi::navstack
