#pragma once
// The E-Navi paper's hardware-in-the-loop results (its Tab. "Average experimental results on
// HIL platform"; its Pi 5 row is the OrangePi 5): what `enavi eval --preset paper` prints ours
// beside. Numbers as printed in the paper, per board, method and scenario S1-S5.

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace enavi::server {

struct PaperRow {
  std::string board;   ///< our board id (a registered board profile)
  std::string method;  ///< "enavi" or "baseline"
  std::array<double, 5> cpu_pct;        ///< navigation task workload, % (S1-S5)
  std::array<double, 5> flight_time_s;  ///< S1-S5
  std::array<double, 5> path_m;         ///< S1-S5
};

/// The paper's ten rows (5 boards x E-Navi, baseline).
const std::vector<PaperRow>& PaperHilTable();
/// The row for (board, method), or nullptr.
const PaperRow* FindPaperRow(const std::string& board, const std::string& method);

/// The eci range the paper gives for one of its scenarios (its Tab. "Descriptions of the five
/// experimental scenarios").
struct PaperEciRange {
  double min = 0, max = 0;
};
/// The paper's eci ranges of S1-S5, in PaperScenarios()'s order.
const std::array<PaperEciRange, 5>& PaperEciRanges();
/// The paper's eci range of `scenario` (one of PaperScenarios()), or nullptr.
const PaperEciRange* FindPaperEciRange(const std::string& scenario);

/// The boards of the paper's HIL experiment: those of PaperHilTable(), in its order.
const std::vector<std::string>& PaperBoards();
/// Its scenarios S1-S5: the registered generators after the paper's (those with a paper path
/// length), in the registry's order, which PaperRow's arrays follow.
const std::vector<std::string>& PaperScenarios();

}  // namespace enavi::server
