#pragma once
// The E-Navi paper's hardware-in-the-loop results (its Tab. "Average experimental results on
// HIL platform"; its Pi 5 row is the OrangePi 5): what `enavi eval --preset paper` prints ours
// beside. Numbers as printed in the paper, per board, method and scenario S1-S5.

#include <array>
#include <string>
#include <vector>

namespace enavi::server {

struct PaperRow {
  std::string board;   ///< our board name (pi4b, tx2, nx, opi5, x86)
  std::string method;  ///< "enavi" or "baseline"
  std::array<double, 5> cpu_pct;        ///< navigation task workload, % (S1-S5)
  std::array<double, 5> flight_time_s;  ///< S1-S5
  std::array<double, 5> path_m;         ///< S1-S5
};

/// The paper's ten rows (5 boards x E-Navi, baseline).
const std::vector<PaperRow>& PaperHilTable();
/// The row for (board, method), or nullptr.
const PaperRow* FindPaperRow(const std::string& board, const std::string& method);

/// The matrix of the paper's HIL experiment.
inline const std::vector<std::string>& PaperBoards() {
  static const std::vector<std::string> b = {"pi4b", "tx2", "nx", "opi5", "x86"};
  return b;
}
inline const std::vector<std::string>& PaperScenarios() {
  static const std::vector<std::string> s = {"s1", "s2", "s3", "s4", "s5"};
  return s;
}

}  // namespace enavi::server
