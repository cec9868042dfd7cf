#pragma once
// Frequency constraints C1-C4 of the Strategy Controller (paper Sec. V.B) and our reaction
// constraint (reaction_constraint.h), the feasible set over the action grid, proportional period
// scaling and the persistent-overload (hover) monitor (paper Sec. V.D "Timing Guarantees").
//
// Units: frequencies in Hz, execution times in board seconds, utilisation in cores
// (1.0 = one core fully busy, the paper's 100 %), so U_total = N for N cores.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "navstack/adapt/action_grid.h"
#include "navstack/adapt/reaction_constraint.h"

namespace enavi::navstack {

/// Worst-case execution time of one job of each navigation task, board seconds (paper C_i), taken
/// from the executor's recent statistics.
struct TaskWcets {
  double per = 0.0;   ///< perception (map update at the current resolution)
  double plan = 0.0;  ///< planning (path search + trajectory optimisation)
  double col = 0.0;   ///< collision check
  double dif = 0.0;   ///< environment-difference detection
};

/// Everything C1-C4 depend on apart from the candidate.
struct ConstraintInputs {
  double f_sen = 30.0;  ///< sensor frame rate, Hz
  /// Duration of the current trajectory C_L, s; +infinity when there is none (hovering): C1's
  /// lower bound and C3's planning term then vanish.
  double trajectory_duration = 1.0;
  TaskWcets wcet;
  int num_cores = 1;             ///< N
  double u_cur = 0.0;            ///< U_cur: current total navigation utilisation, cores
  TaskFrequencies current;       ///< configuration now running (the reference of C4's dU)
  /// Nearest obstacle and speed for the reaction constraint; the default (d0 = +inf) holds always.
  ReactionInputs reaction;
};

/// Tunables of the checker.
struct ConstraintOptions {
  /// U_total = capacity_fraction x N. 1.0 is the paper's N x 100 %; < 1 keeps headroom
  /// (e.g. for global EDF, which is not guaranteed to schedule a fully loaded multi-core).
  /// Range (0, 1].
  double capacity_fraction = 1.0;
  /// Absolute slack when comparing, so a configuration exactly on a bound holds despite rounding.
  double tolerance = 1e-9;
};

/// Which of C1-C4 and the reaction constraint hold for one candidate, and what they compare.
struct ConstraintStatus {
  static constexpr int kNumConstraints = 4;
  /// holds[k] is constraint C(k+1); the policy state uses it as a 0/1 vector (the reaction
  /// constraint is not in it, so policies trained before it keep their observation).
  std::array<bool, kNumConstraints> holds{};
  ReactionStatus reaction;  ///< the reaction constraint
  double f_per_min = 0.0;  ///< C1 lower bound 1 / C_L, Hz
  double c3_load = 0.0;    ///< C3 left side: f_per C_per + C_plan / C_L + f_col C_col + f_dif C_dif, cores
  double u_after = 0.0;    ///< C4 left side: U_cur + sum_i (f_new,i - f_cur,i) C_i, cores
  double u_total = 0.0;    ///< U_total, cores

  bool AllHold() const { return holds[0] && holds[1] && holds[2] && holds[3] && reaction.holds; }
};

/// Checks C1-C4 for `candidate` (paper Eqs. framework-constraint1..4) and the reaction constraint.
/// Planning is triggered, not periodic, so its frequency is not an action and dU_plan = 0.
/// @throws std::domain_error when an input is NaN or negative, C_L <= 0, N < 1, or an option is
///   outside its range (these come from the runtime, not from a user: a broken contract).
ConstraintStatus CheckConstraints(const ConstraintInputs& inputs, const TaskFrequencies& candidate,
                                  const ConstraintOptions& options = {});

/// The feasible set over a grid: mask[i] = 1 when action i satisfies C1-C4 and the reaction
/// constraint.
struct FeasibleSet {
  std::vector<std::uint8_t> mask;  ///< one entry per grid action; never all zero
  int num_feasible = 0;            ///< actions satisfying all constraints (0 when the fallback was used)
  /// True when no action satisfies all constraints: the mask then holds exactly the fallback
  /// action, so a masked policy must pick it. The caller should record this as an event.
  bool fallback_used = false;
  int fallback_action = -1;        ///< index of the fallback action, or -1
  /// The action of the mask with the lowest C3 load (ties -> lowest index): what a rule that
  /// spends the least CPU the constraints allow would run. The fallback action when it was used.
  int least_load_action = -1;
  /// No action satisfies the reaction constraint: the fallback is the quickest to react, and the
  /// vehicle must slow down (SafeSpeed) to make up the rest.
  bool reaction_infeasible = false;
};

/// Evaluates C1-C4 and the reaction constraint for every grid action. Fallback when none is
/// feasible, safety before CPU: the action with the lowest C3 load (least CPU) among those
/// satisfying C1, C2 (structural bounds: never fly blind, never check a map faster than it is
/// built) and the reaction constraint; if no action can react in time, the one with the shortest
/// reaction time among those satisfying C1 and C2; otherwise the lowest C3 load among all
/// actions. Ties -> lowest C3 load, then lowest index.
FeasibleSet ComputeFeasibleSet(const ActionGrid& grid, const ConstraintInputs& inputs,
                               const ConstraintOptions& options = {});

/// Result of proportional period scaling.
struct ScaledFrequencies {
  TaskFrequencies f;        ///< frequencies to run (continuous: periods need not be on the grid)
  double scale = 1.0;       ///< factor applied to f_col and f_dif (and f_per unless floored)
  bool scaled = false;      ///< U_cur exceeded U_total and frequencies were reduced
  bool f_per_floored = false;  ///< f_per was held at C1's lower bound 1 / C_L
  /// Predicted utilisation after scaling (U_cur minus the modelled reduction), cores. Above
  /// U_total when scaling cannot remove the overload (e.g. planning alone exceeds it); the
  /// overload monitor then sees it persist.
  double u_predicted = 0.0;
};

/// Paper Sec. V.D: when U_cur > U_total, lengthen all task periods proportionally. With the
/// scalable part U_s = f_per C_per + f_col C_col + f_dif C_dif of the running configuration, the
/// factor is k = 1 - (U_cur - U_total) / U_s (= U_total / U_cur when all load is scalable),
/// clamped to [0, 1]. f_per is not scaled below C1's lower bound 1 / C_L (if it was above it);
/// the utilisation that costs is taken from f_col and f_dif, which keeps C2 (f_col <= f_per).
/// Returns `current` unchanged (scaled = false) when U_cur <= U_total.
ScaledFrequencies ScaleToCapacity(const ConstraintInputs& inputs,
                                  const ConstraintOptions& options = {});

/// Tunables of the overload monitor.
struct OverloadMonitorOptions {
  /// A check is overloaded when U_cur > overload_fraction x U_total. Range (0, 2].
  double overload_fraction = 1.0;
  /// Fail-safe when overload has lasted at least this long (sim seconds; <= 0 disables). Range >= 0.
  double max_overload_duration = 1.0;
  /// Fail-safe after this many consecutive overloaded checks (0 disables). Range >= 0.
  int max_consecutive_overloaded = 0;
  /// Leave the fail-safe when U_cur <= recovery_fraction x U_total ... Range (0, overload_fraction].
  double recovery_fraction = 0.9;
  /// ... continuously for at least this long, sim seconds. Range >= 0.
  double recovery_duration = 0.5;
};

/// Watches U_cur over time and declares the hover fail-safe when overload persists (paper
/// Sec. V.D). Deterministic: driven by the sim time the caller passes, never the wall clock.
class OverloadMonitor {
 public:
  enum class Mode { kNominal, kOverloaded, kFailSafe };

  /// What one observation changed. `entered_failsafe` and `recovered` are edges (true once), for
  /// the caller to record as events.
  struct Update {
    Mode mode = Mode::kNominal;
    bool overloaded = false;        ///< this check exceeded the overload threshold
    bool entered_failsafe = false;
    bool recovered = false;
    double overload_duration = 0.0; ///< s since the current overload streak began (0 if none)
    int consecutive_overloaded = 0;
  };

  /// @throws std::invalid_argument when an option is outside its range (message names it).
  explicit OverloadMonitor(const OverloadMonitorOptions& options = {});

  /// One check at sim time t (non-decreasing) with the measured utilisation, cores.
  /// @throws std::domain_error when t decreases or a value is NaN / u_total <= 0.
  Update Observe(double t, double u_cur, double u_total);

  Mode mode() const { return mode_; }
  bool in_failsafe() const { return mode_ == Mode::kFailSafe; }
  void Reset();

 private:
  OverloadMonitorOptions options_;
  Mode mode_ = Mode::kNominal;
  double last_t_ = -1.0;
  bool has_last_ = false;
  double overload_since_ = 0.0;
  int consecutive_ = 0;
  bool recovering_ = false;
  double recovery_since_ = 0.0;
};

/// Name of a mode for logs and events ("nominal", "overloaded", "failsafe").
const char* ToString(OverloadMonitor::Mode mode);

}  // namespace enavi::navstack
