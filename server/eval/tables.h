#pragma once
// Text renderings of farm results: the per-episode table and CSV of `enavi results`, the
// paper-style summary of `enavi eval`, and progress lines.

#include <string>

#include <nlohmann/json.hpp>

#include "api/http_schema.h"

namespace enavi::server {

/// One row per result object (as returned by ResultQueries::Results / GET .../results).
std::string ResultsTable(const nlohmann::json& results);
/// Every scalar field, nested objects flattened with dots (task_cpu_util_pct.perception).
std::string ResultsCsv(const nlohmann::json& results);

/// Paper-style summary: rows board x method; per scenario nav CPU %, flight time and path
/// length; success rate, collisions, velocity std and emergency stops per episode; then the
/// E-Navi vs baseline reduction per board and, with `fixed` in the results, the split of the
/// gap into runtime (baseline vs fixed) and configuration (fixed vs enavi).
/// Flight time and path length average successful episodes (a crash's flight time is not a
/// flight time); CPU % and velocity std average all episodes.
std::string PaperTable(const nlohmann::json& results);

/// `enavi eval --preset paper`: for every board x method the paper reports (E-Navi, baseline),
/// our per-scenario means of nav CPU %, flight time and path length beside the paper's HIL
/// table and their difference (ours - paper), then the average reductions per board (mean
/// over the scenarios of each method, E-Navi vs baseline) beside the paper's. Cells with no
/// result (or, for flight and path, no success) print "-".
std::string PaperComparison(const nlohmann::json& results);

/// `enavi eval`'s "eci range per scenario" (docs/results.md, "eci range along a flight"): per
/// scenario and method, over the flights that took off (result eci.flight_frames > 0), the mean
/// of each flight's least and greatest eci in flight (eci.flight_min, eci.flight_max), the
/// lowest and highest of them, and for the paper's scenarios its range and ours minus it.
/// Results without the flight fields (stored before they existed) are counted as "no range".
std::string EciRangeTable(const nlohmann::json& results);

/// Flights in worlds that move (issue 45: movers): per scenario and method, over every board and
/// seed, the flights, success rate, collisions with the static world and with movers
/// (result collided_with), mean flight time of the successful flights, mean tracking error
/// (setpoint_lag_p95_m: p95 of |reference - vehicle position|), mean nav CPU % and mean replans
/// asked for by E-Navi's change detection per flight (replans_by_trigger.difference).
std::string RobustnessTable(const nlohmann::json& results);
/// Whether the results hold a flight that RobustnessTable is for (a world with movers).
bool HasMovingWorlds(const nlohmann::json& results);

/// `enavi trend`: one row per job and method (oldest job first), a column per board with the
/// metric's mean and its 95 % interval ("24.86 ± 3.16"; no interval with one seed), from a trend
/// with intervals (ResultQueries::Trend, AddTrendIntervals). `method` empty: every method.
std::string TrendTable(const nlohmann::json& trend, const std::string& method);

/// "[########------] 12/40 done  1 failed  3.2 ep/s  ETA 9s" (bar when `bar`, else plain).
std::string ProgressLine(const api::JobProgress& p, bool bar);

}  // namespace enavi::server
