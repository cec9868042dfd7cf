#include "server/eval/tables.h"

#include <gtest/gtest.h>

namespace enavi::server {
namespace {

nlohmann::json Result(const std::string& board, const std::string& method, const std::string& s,
                      int seed, double cpu, double time, double path, bool ok) {
  return {{"board", board}, {"method", method},       {"scenario", s},
          {"seed", seed},   {"nav_cpu_util_pct", cpu}, {"flight_time_s", time},
          {"path_length_m", path}, {"success", ok},   {"velocity_std_mps", 0.5},
          {"episode_id", "j-" + std::to_string(seed)}, {"end_reason", ok ? "goal_reached" : "collision"},
          {"task_cpu_util_pct", {{"perception", cpu / 2}}}};
}

TEST(PaperTableTest, AveragesPerCellAndReportsTheReductionPerBoard) {
  nlohmann::json results = nlohmann::json::array();
  results.push_back(Result("tx2", "baseline", "s1", 1, 100, 40, 44, true));
  results.push_back(Result("tx2", "baseline", "s1", 2, 80, 30, 46, true));
  results.push_back(Result("tx2", "enavi", "s1", 1, 60, 30, 45, true));
  // A crash: counts for CPU and success, not for flight time or path.
  results.push_back(Result("tx2", "enavi", "s1", 2, 48, 5, 3, false));
  const std::string table = PaperTable(results);
  // baseline: cpu (100+80)/2 = 90.0, time 35.0, path 45.0, success 100%.
  EXPECT_NE(table.find("tx2    baseline   90.0    35.0    45.0     100%"), std::string::npos) << table;
  // enavi: cpu (60+48)/2 = 54.0, time 30.0 (successful only), path 45.0, success 50%.
  EXPECT_NE(table.find("tx2    enavi      54.0    30.0    45.0      50%"), std::string::npos) << table;
  // Reductions: cpu (90-54)/90 = 40.0%, flight time (35-30)/35 = 14.3%.
  EXPECT_NE(table.find("tx2              40.0%                  14.3%"), std::string::npos) << table;
}

TEST(PaperTableTest, NoResultsSaysSo) { EXPECT_EQ(PaperTable(nlohmann::json::array()), "no results\n"); }

TEST(ResultsCsvTest, FlattensNestedFieldsAndQuotes) {
  nlohmann::json results = nlohmann::json::array();
  results.push_back(Result("tx2", "enavi", "s1", 1, 60, 30, 45, true));
  results[0]["end_reason"] = "error: a, b";
  const std::string csv = ResultsCsv(results);
  EXPECT_NE(csv.find("task_cpu_util_pct.perception"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\"error: a, b\""), std::string::npos) << csv;
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 2);
}

TEST(ProgressLineTest, ShowsCountsRateAndEta) {
  api::JobProgress p;
  p.id = "j1";
  p.state = "running";
  p.total = 10;
  p.done = 4;
  p.failed = 1;
  p.started_ms = 1000;
  p.now_ms = 6000;  // 5 finished in 5 s: 1 ep/s, 5 to go
  EXPECT_DOUBLE_EQ(p.rate_per_s(), 1.0);
  EXPECT_DOUBLE_EQ(p.eta_s(), 5.0);
  EXPECT_EQ(ProgressLine(p, false), "j1 4/10 done  1 failed  1.0 ep/s  ETA 5s");
  EXPECT_EQ(ProgressLine(p, true).rfind("[###############---------------] j1", 0), 0u);
  p.started_ms = 0;
  EXPECT_EQ(p.eta_s(), -1.0) << "unknown before the first lease";
}

}  // namespace
}  // namespace enavi::server
