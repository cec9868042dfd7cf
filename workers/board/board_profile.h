#pragma once
// Onboard computers the farm emulates (workers/board/profiles/SOURCES.md) and their cost-model coefficients.
// Profiles are data (workers/board/profiles/*.yaml, embedded in the binary) with a cited source
// for every per-core speed figure; see profiles/SOURCES.md.

#include <map>
#include <string>
#include <vector>

#include "navstack/runtime/cost_model.h"

namespace enavi::board {

struct BoardProfile {
  std::string id;
  std::string name;
  std::string cpu;
  int cores = 1;
  double clock_ghz = 0;
  double paper_gflops = 0;
  /// Single-core speed relative to the reference core (the calibration host): a job that takes
  /// 1 ms on the reference core takes 1 / per_core_speed ms on this board.
  double per_core_speed = 1.0;
  std::string speed_benchmark;
  std::string notes;
  bool is_host = false;  ///< the machine itself, unthrottled
};

/// Nanoseconds per job and per work unit on the reference core, fitted by `enavi calibrate`, one
/// set per cost family (navstack::MethodInfo::cost_family): one price for a unit that is different
/// code in two code bases over-prices one and under-prices the other.
struct ReferenceCosts {
  using Coefficients = navstack::WorkCountCostModel::Coefficients;
  std::string reference_cpu;
  std::string calibration_id;
  std::map<std::string, Coefficients> families;
  /// The family's prices. Throws std::invalid_argument naming the family and the known ones.
  const Coefficients& For(const std::string& family) const;
};

/// Ids of all known boards, sorted: one per embedded profile, the farm's one list of boards (the
/// CLI's choices, job validation, a worker's capabilities read it).
std::vector<std::string> KnownBoards();
/// Loads an embedded profile. Throws std::invalid_argument naming the id and the known ones.
BoardProfile LoadBoard(const std::string& id);
/// Parses one profile document (`source` names it in error messages).
BoardProfile ParseBoardProfile(const std::string& yaml_text, const std::string& source);

/// The embedded reference costs (workers/board/profiles/reference_costs.yaml).
ReferenceCosts LoadReferenceCosts();
ReferenceCosts ParseReferenceCosts(const std::string& yaml_text, const std::string& source);

/// Every price of `c` times `factor`.
navstack::WorkCountCostModel::Coefficients Scaled(navstack::WorkCountCostModel::Coefficients c, double factor);

/// The board's cost-model coefficients for a cost family: reference ns per unit / per-core speed.
navstack::WorkCountCostModel::Coefficients BoardCoefficients(const BoardProfile& board, const ReferenceCosts& reference,
                                                             const std::string& family);

}  // namespace enavi::board
