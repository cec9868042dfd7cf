#pragma once
// Resolution Adapter of the Strategy Controller (paper Sec. V.A): the map resolution for the next
// planning query, chosen greedily from a ladder of candidates, coarsest feasible first.
//
// Plain inputs and outputs: the caller reports planning outcomes, collision-check triggers, path
// quality and eci; nothing here touches a map.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace enavi::navstack {

/// Inputs of the path score (paper Eqs. design-optimal_path, design-s).
struct PathScoreInputs {
  double path_length = 0.0;      ///< |L|, m: length of the planned path
  double straight_length = 0.0;  ///< |Lbar|, m: straight line start -> goal
  double occupied_cells = 0.0;   ///< rho_c: occupied cells of the map
  double total_cells = 0.0;      ///< rho*_c: all cells of the map
};

/// s = exp(-(|L| - |L*|) / |Lbar|) with L* = (1 + gamma rho_c / rho*_c) Lbar, in (0, 1].
/// The paper defines s for |L| >= |L*|; a path shorter than the reference scores 1. Degenerate
/// inputs (|Lbar| <= 0) score 1; rho*_c <= 0 counts as an empty map.
/// @throws std::domain_error when a length or count is NaN or negative, or gamma < 0.
double PathScore(const PathScoreInputs& in, double gamma);

/// Manhattan distance, in cells, between the cells holding a and b on a grid of the given
/// resolution anchored at `origin` (cell index floor((p - origin) / res) per axis).
std::int64_t ManhattanCellDistance(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   double resolution,
                                   const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/// Tunables (named, with ranges; a bad value throws std::invalid_argument naming the field).
struct ResolutionAdapterOptions {
  /// Candidate resolutions, m, strictly decreasing (coarsest first), all > 0.
  std::vector<double> ladder = {0.5, 0.4, 0.3, 0.2, 0.15, 0.1};
  /// gamma of L* (paper: scaling hyperparameter, > 0). Range [0, 100].
  double gamma = 1.0;
  /// Refine one step when a planned path scores below this. Range [0, 1].
  double score_threshold = 0.9;
  /// eci at or below this counts as "low" (open space). Range [0, 1].
  double low_eci = 0.3;
  /// eci at or above this refines one step (at most every min_refine_interval). Range [low_eci, 1].
  double high_eci = 0.5;
  /// eci must stay low this long (sim s) before going one step coarser. Range > 0.
  double coarsen_after = 3.0;
  /// Also go one step coarser when no refinement trigger (collision-check trigger, path score
  /// below the threshold, eci at or above high_eci) has come for this long (sim s), whatever
  /// the eci: the paper (Sec. V.A) refines on those events and says nothing of coarsening, and
  /// eci alone keeps a refinement for the rest of a flight wherever it hovers between low_eci
  /// and high_eci. Default 3 s: the time to fly through the mapping range (5 m) at the planner's
  /// top speed (2 m/s), 2.5 s, after which the obstacles that raised the last trigger are behind
  /// the vehicle, rounded up to the adapter's other hysteresis periods (coarsen_after,
  /// refine_hold). Range > 0.
  double quiet_period = 3.0;
  /// No coarsening within this time (sim s) after a refinement: the hysteresis that stops
  /// refine / coarsen oscillation. Range >= 0.
  double refine_hold = 3.0;
  /// At most one refinement per this many sim seconds. Range >= 0.
  double min_refine_interval = 2.0;
  /// Anchor of the map grid, for the Manhattan rule.
  Eigen::Vector3d grid_origin = Eigen::Vector3d::Zero();
};

/// Why the current level is what it is, for logs and time series.
enum class ResolutionReason {
  kGreedy,          ///< coarsest level that passes the Manhattan rule and has no recorded failure
  kSameCell,        ///< no level puts start and goal in different cells: finest level
  kAllFailed,       ///< every admissible level failed its last planning attempt: finest level
};

/// The resolution to plan at.
struct ResolutionDecision {
  double resolution = 0.0;  ///< m
  int level = 0;            ///< index into the ladder (0 = coarsest)
  bool changed = false;     ///< differs from the previous decision
  ResolutionReason reason = ResolutionReason::kGreedy;
};

/// Greedy coarsest-feasible resolution with event-driven refinement and two coarsening rules.
///
/// State: a refinement floor (the coarsest level currently allowed) and, per level, the outcome of
/// the last planning attempt there. Select() takes the coarsest level >= floor whose cells separate
/// start and goal (Manhattan distance > 0) and whose last attempt did not fail (untried levels are
/// tried optimistically). The floor moves one step finer after a collision-check trigger, a path
/// scoring below the threshold or an eci at or above high_eci (each is a trigger, even when
/// min_refine_interval holds the refinement back); it moves one step coarser (and that level gets
/// another try) when eci has stayed low for `coarsen_after` or no trigger has come for
/// `quiet_period`, no sooner than `refine_hold` after a refinement, and again only after another
/// full period of either kind. The coarsening rules are evaluated at each ObserveEci().
class ResolutionAdapter {
 public:
  /// @throws std::invalid_argument for an option outside its range (message names the field).
  explicit ResolutionAdapter(const ResolutionAdapterOptions& options = {});

  /// Resolution for the next planning query from p_start to p_goal (world frame, m).
  ResolutionDecision Select(const Eigen::Vector3d& p_start_W, const Eigen::Vector3d& p_goal_W);

  /// The planner's outcome at a ladder level: whether it found a collision-free path.
  /// @throws std::out_of_range for a level outside the ladder.
  void ReportPlanningOutcome(int level, bool found_path);

  /// The collision check found the current trajectory in collision with the map at sim time t:
  /// refine one step from the current level.
  void OnCollisionTrigger(double t);

  /// Scores a newly planned path (PathScore with options.gamma) and refines one step when it is
  /// below the threshold. Returns the score.
  double OnPathPlanned(double t, const PathScoreInputs& path);

  /// One eci sample (every sensor frame or every decision) at sim time t (non-decreasing).
  void ObserveEci(double t, double eci);

  int level() const { return level_; }
  double resolution() const { return options_.ladder[static_cast<std::size_t>(level_)]; }
  int floor_level() const { return floor_; }
  int num_levels() const { return static_cast<int>(options_.ladder.size()); }
  const ResolutionAdapterOptions& options() const { return options_; }

 private:
  enum class Outcome : std::uint8_t { kUnknown, kFound, kFailed };
  void Refine(double t);

  ResolutionAdapterOptions options_;
  std::vector<Outcome> outcome_;
  int floor_ = 0;
  int level_ = 0;
  bool has_decision_ = false;
  bool has_refined_ = false;
  double last_refine_t_ = 0.0;
  bool eci_low_ = false;
  double eci_low_since_ = 0.0;
  double quiet_since_ = 0.0;  ///< time of the last trigger or coarsening
};

}  // namespace enavi::navstack
