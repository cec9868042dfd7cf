#pragma once
// A* on the planner's grid around an obstacle: the guiding path of Ego-Planner's rebound
// optimiser (path_searching/src/dyn_a_star.cpp), over inflated occupancy instead of an ESDF.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/work.h"
#include "navstack/planning/inflated_occupancy.h"
#include "navstack/planning/path_search.h"

namespace enavi::navstack {

enum class AstarStatus { kOk, kNoPath, kOverBudget };

struct AstarResult {
  AstarStatus status = AstarStatus::kNoPath;
  std::vector<Eigen::Vector3d> path;  ///< cell centres, start .. goal; empty unless kOk
  int expansions = 0;
  bool ok() const { return status == AstarStatus::kOk; }
};

/// 26-connected A* over the cells of occupancy's grid whose centre lies in bounds and which are
/// not inflated-occupied; edge cost = centre distance, heuristic = 3-D diagonal distance x
/// (1 + 1e-4) (Ego-Planner's getDiagHeu and tie_breaker_). A start or goal cell that is occupied
/// is moved away from the other end one cell at a time until free, as Ego-Planner's
/// ConvertToIndexAndAdjustStartEndPoints does. Ego-Planner stops after 0.2 s of wall time; here
/// over_budget (if set) is asked before every expansion with *work, and the search ends with
/// kOverBudget when it says so; without a hook the search ends when the reachable cells are
/// exhausted. Ties in the open list break by insertion order: deterministic.
/// Adds kAstarExpansion per node expanded to *work (occupancy adds its own cell reads).
AstarResult GridAstar(const InflatedOccupancy& occupancy, const Eigen::AlignedBox3d& bounds,
                      const Eigen::Vector3d& start, const Eigen::Vector3d& goal, WorkCounts* work,
                      const OverBudget& over_budget = {});

}  // namespace enavi::navstack
