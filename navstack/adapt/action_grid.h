#pragma once
// Discrete action space of the frequency adapter (paper Sec. V.C): triples (f_per, f_col, f_dif).

#include <optional>
#include <string>
#include <vector>

namespace enavi::navstack {

/// Execution frequencies of the three periodic navigation tasks, Hz (paper Sec. III.A).
/// f_col = 0 or f_dif = 0 means the task is not released at all.
struct TaskFrequencies {
  double f_per = 0.0;  ///< perception: depth -> points -> map update
  double f_col = 0.0;  ///< collision check of the current trajectory against the map
  double f_dif = 0.0;  ///< environment-difference detection on raw sensor data

  bool operator==(const TaskFrequencies&) const = default;
};

/// Levels of the default grid. Every non-zero level divides the 30 Hz sensor rate, so each task
/// runs on every k-th depth frame (no beat between task period and frame period), and the levels
/// are roughly geometric (x2-x2.5 steps) so the policy can move utilisation in proportional steps.
/// Floors: the map is updated at least every 0.4 m at 2 m/s (f_per >= 5 Hz) and the trajectory is
/// checked against it at least twice a second (f_col >= 2 Hz). C1 and C2 alone would allow
/// 1 Hz / 0 Hz, but in training, policies that slowed down that far flew round corners into
/// what the map had not caught up with; those rates save almost nothing on a coarse map anyway.
/// 0 Hz switches difference detection off.
inline const std::vector<double>& DefaultPerceptionLevels() {
  static const std::vector<double> levels = {5, 10, 15, 30};
  return levels;
}
inline const std::vector<double>& DefaultCollisionLevels() {
  static const std::vector<double> levels = {2, 5, 10, 15, 30};
  return levels;
}
inline const std::vector<double>& DefaultDifferenceLevels() {
  static const std::vector<double> levels = {0, 1, 2, 5, 10, 15, 30};
  return levels;
}

/// An ordered, finite list of frequency triples; the index of a triple is the policy's action.
/// Constant after construction (safe to share between threads).
class ActionGrid {
 public:
  /// The default grid: the Cartesian product of the default levels, minus the triples with
  /// f_col > f_per (C2's cascade part can never hold for them, whatever the board), ordered
  /// f_per-major, then f_col, then f_dif, all ascending: 14 (f_per, f_col) pairs x 7 = 98 actions.
  ActionGrid();

  /// Product of the given levels, dropping triples with f_col > f_per when `drop_cascade_violations`.
  /// @throws std::invalid_argument when a level list is empty, unsorted, has duplicates, a negative
  ///   or non-finite value, or a perception level <= 0.
  static ActionGrid FromLevels(const std::vector<double>& f_per, const std::vector<double>& f_col,
                               const std::vector<double>& f_dif, bool drop_cascade_violations = true);

  /// An explicit list of triples (as stored in a policy file).
  /// @throws std::invalid_argument when empty, when a triple repeats, or a frequency is negative,
  ///   non-finite, or f_per <= 0. `what` names the source in the message.
  static ActionGrid FromTriples(std::vector<TaskFrequencies> triples,
                                const std::string& what = "action grid");

  int size() const { return static_cast<int>(actions_.size()); }
  /// @throws std::out_of_range for an index outside [0, size()).
  const TaskFrequencies& At(int index) const;
  const std::vector<TaskFrequencies>& actions() const { return actions_; }

  /// Index of an exact triple, if it is on the grid.
  std::optional<int> Find(const TaskFrequencies& f) const;
  /// Index of the grid triple closest to `f` (Euclidean in Hz; ties -> lowest index).
  int Nearest(const TaskFrequencies& f) const;

  bool operator==(const ActionGrid& o) const { return actions_ == o.actions_; }

 private:
  explicit ActionGrid(std::vector<TaskFrequencies> actions) : actions_(std::move(actions)) {}
  std::vector<TaskFrequencies> actions_;
};

}  // namespace enavi::navstack
