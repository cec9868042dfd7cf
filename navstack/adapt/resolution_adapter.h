#pragma once
// Resolution Adapter of the Strategy Controller (paper Sec. V.A): the map resolution for the next
// planning query, chosen greedily from a ladder of candidates, coarsest feasible first.
//
// Plain inputs and outputs: the caller reports planning outcomes, collision-check triggers, path
// quality and eci; nothing here touches a map.

#include <cstdint>
#include <deque>
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
  /// eci at or above this refines one step (paper Sec. VI: higher eci, finer map). Range [0, 1].
  double high_eci = 0.5;
  /// How long a refinement step counts (sim s): each one expires this long after the trigger that
  /// made it, and the map then goes one level coarser than the one in use. With no step live,
  /// the map also goes one level coarser after this long without a refinement or a coarsening
  /// (so a level that failed gets another try). The paper (Sec. V.A) refines on triggers and says
  /// nothing of coarsening. Steps that expire on their own make the level follow how many
  /// triggers came recently; a rule that coarsens only after a trigger-free period instead adds
  /// up every trigger of a stretch where they come about as often as that period (s2: collision
  /// predictions every 2.5-3 s), and the map drifts to the finest level in some flights and not
  /// in others. Default 3 s: the time to fly through the mapping range (5 m) at the planner's top
  /// speed (2 m/s), 2.5 s, after which the obstacles that raised the trigger are behind the
  /// vehicle, rounded up. Range (0, 1e6].
  double step_lifetime = 3.0;
  /// At most one refinement per this many sim seconds: several triggers in a row usually report
  /// the same obstacle coming into view. Range [0, 1e6].
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

/// Greedy coarsest-feasible resolution with event-driven refinement steps that expire.
///
/// State: a refinement floor (the coarsest level currently allowed) and, per level, the outcome of
/// the last planning attempt there. Select() takes the coarsest level >= floor whose cells
/// separate start and goal (Manhattan distance > 0) and whose last attempt did not fail (untried
/// levels are tried optimistically). A collision-check trigger, a path scoring below the threshold
/// or an eci at or above high_eci moves the floor one level finer than the level in use (at most
/// once per min_refine_interval), as a step that expires step_lifetime later. Each expiry, and
/// with no step live each step_lifetime without a refinement or coarsening, moves one level
/// coarser than the level in use and gives that level another try: one level at a time, so a map
/// refined past levels that failed near an obstacle does not jump back to the coarsest.
/// Expiry is evaluated at each call that carries a time.
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
  /// Applies the coarsening that is due at t, if any.
  void Advance(double t);

  ResolutionAdapterOptions options_;
  std::vector<Outcome> outcome_;
  std::deque<double> step_ends_;  ///< when each live refinement step expires, oldest first
  int floor_ = 0;
  int level_ = 0;
  bool has_decision_ = false;
  bool has_refined_ = false;
  double last_refine_t_ = 0.0;
  double last_change_t_ = 0.0;  ///< last refinement or coarsening (or the start)
};

}  // namespace enavi::navstack
