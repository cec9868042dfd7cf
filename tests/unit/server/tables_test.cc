#include "server/eval/tables.h"

#include <algorithm>

#include <gtest/gtest.h>

#include "server/eval/paper_reference.h"
#include "server/eval/progress_pacer.h"
#include "workers/board/board_profile.h"
#include "worlds/generators.h"

namespace enavi::server {
namespace {

// The paper's matrix is read from its table and the registries, so it names registered boards
// and generators, and every board has both of the paper's rows.
TEST(PaperReferenceTest, TheMatrixIsRegisteredBoardsAndTheGeneratorsAfterThePapersScenarios) {
  const std::vector<std::string> known = board::KnownBoards();
  ASSERT_EQ(PaperBoards().size(), 5u) << "the paper flew five boards";
  for (const std::string& b : PaperBoards()) {
    EXPECT_NE(std::find(known.begin(), known.end(), b), known.end()) << b << " is not a registered board";
    EXPECT_NE(FindPaperRow(b, "enavi"), nullptr) << b;
    EXPECT_NE(FindPaperRow(b, "baseline"), nullptr) << b;
    EXPECT_GT(board::LoadBoard(b).paper_gflops, 0) << b << ": a board of the paper has its GFLOPS figure";
  }
  EXPECT_EQ(PaperHilTable().size(), 2 * PaperBoards().size());
  ASSERT_EQ(PaperScenarios().size(), 5u);
  for (const std::string& s : PaperScenarios()) {
    const worlds::GeneratorInfo* g = worlds::FindGenerator(s);
    ASSERT_NE(g, nullptr) << s;
    EXPECT_GT(g->paper_path_length, 0) << s;
  }
  EXPECT_EQ(PaperScenarios().front(), "s1") << "PaperRow's arrays run S1-S5";
  EXPECT_EQ(PaperScenarios().back(), "s5");
}

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

TEST(PaperComparisonTest, PrintsOursBesideThePapersCellsAndTheReductions) {
  // x86 over S1-S5: baseline 50 % / 40 s / 45 m everywhere, E-Navi 25 % / 30 s / 44 m.
  nlohmann::json results = nlohmann::json::array();
  for (const char* s : {"s1", "s2", "s3", "s4", "s5"}) {
    results.push_back(Result("x86", "baseline", s, 1, 50, 40, 45, true));
    results.push_back(Result("x86", "enavi", s, 1, 25, 30, 44, true));
  }
  const std::string out = PaperComparison(results);
  // Paper x86 S1: baseline 42.5 % / 74.8 s / 49.8 m; E-Navi 38.2 % / 45.8 s / 44.3 m.
  EXPECT_NE(out.find("x86    baseline  50.0   42.5    7.5"), std::string::npos) << out;
  EXPECT_NE(out.find("x86    enavi     25.0   38.2  -13.2"), std::string::npos) << out;
  EXPECT_NE(out.find("x86    baseline  40.0   74.8  -34.8"), std::string::npos) << out;
  EXPECT_NE(out.find("x86    enavi     44.0   44.3  -0.3"), std::string::npos) << out;
  // Ours: cpu (50-25)/50 = 50.0 %, time (40-30)/40 = 25.0 %. Paper x86: cpu mean 49.4 -> 42.16
  // = 14.7 %, flight 69.16 -> 40.5 = 41.4 %.
  // One seed per scenario: no spread to give an interval from.
  EXPECT_NE(out.find("x86                 50.0%              -  14.7%                       25.0%              -  41.4%"),
            std::string::npos)
      << out;
  EXPECT_EQ(out.find("tx2"), std::string::npos) << "boards without results are left out";
}

// The interval is the seeds' draw: baseline cpu 48 / 52 and E-Navi 24 / 26 in every scenario,
// flight 39 / 41 and 29 / 31. CPU: Var(B) = 5 x (8 / 2) / 25 = 0.8, Var(E) = 0.2, r = 0.5,
// sd = sqrt(0.2 / 50^2 + 25^2 x 0.8 / 50^4) = 0.012649, t(5) = 2.5706: 46.7 to 53.3 %. Flight:
// Var(B) = Var(E) = 0.2, r = 0.25, sd = sqrt(0.2 / 40^2 + 30^2 x 0.2 / 40^4) = 0.013975: 21.4 to
// 28.6 %.
TEST(PaperComparisonTest, TheReductionsIntervalIsTheSeedsSpreadWithinEachScenario) {
  nlohmann::json results = nlohmann::json::array();
  for (const char* s : {"s1", "s2", "s3", "s4", "s5"}) {
    results.push_back(Result("x86", "baseline", s, 1, 48, 39, 45, true));
    results.push_back(Result("x86", "baseline", s, 2, 52, 41, 45, true));
    results.push_back(Result("x86", "enavi", s, 1, 24, 29, 44, true));
    results.push_back(Result("x86", "enavi", s, 2, 26, 31, 44, true));
  }
  const std::string out = PaperComparison(results);
  EXPECT_NE(out.find("x86                 50.0%  46.7 to 53.3%  14.7%                       25.0%  21.4 to 28.6%  41.4%"),
            std::string::npos)
      << out;
  // A scenario offset the same in every run is not part of the draw: s1 10 points dearer for both
  // methods moves the reduction, not the width of its interval.
  for (auto& r : results) {
    if (r["scenario"] == "s1") r["nav_cpu_util_pct"] = r["nav_cpu_util_pct"].get<double>() + 10;
  }
  const std::string shifted = PaperComparison(results);
  // B = 52, E = 27: r = 48.1 %; sd = sqrt(0.2 / 52^2 + 27^2 x 0.8 / 52^4) = 0.012399, half 3.2.
  EXPECT_NE(shifted.find("x86                 48.1%  44.9 to 51.3%"), std::string::npos) << shifted;
}

TEST(PaperComparisonTest, AReductionNeedsEveryScenario) {
  nlohmann::json results = nlohmann::json::array();
  results.push_back(Result("tx2", "baseline", "s1", 1, 50, 40, 45, true));
  results.push_back(Result("tx2", "enavi", "s1", 1, 25, 30, 44, true));
  const std::string out = PaperComparison(results);
  EXPECT_NE(out.find("tx2    enavi     25.0   50.8  -25.8     -   59.2     -"), std::string::npos) << out;
  EXPECT_EQ(out.find("E-Navi vs baseline"), std::string::npos) << out;
  EXPECT_EQ(PaperComparison(nlohmann::json::array()), "no results on the paper's boards and scenarios\n");
}

TEST(TrendTableTest, OneRowPerJobAndMethodWithTheIntervalWhereThereIsOne) {
  const nlohmann::json trend = {{"points", nlohmann::json::array({
      {{"job_id", "ja"}, {"name", "n1"}, {"board", "tx2"}, {"method", "baseline"}, {"mean", 24.5}, {"ci95", 1.25}},
      {{"job_id", "ja"}, {"name", "n1"}, {"board", "pi4b"}, {"method", "baseline"}, {"mean", 23.0}, {"ci95", nullptr}},
      {{"job_id", "jb"}, {"name", "n2"}, {"board", "tx2"}, {"method", "enavi"}, {"mean", 0.5}, {"ci95", 0.125}},
  })}};
  const std::string all = TrendTable(trend, "");
  EXPECT_NE(all.find("1  ja   n1    baseline  23.00   24.50 ± 1.25"), std::string::npos) << all;
  EXPECT_NE(all.find("2  jb   n2    enavi         -  0.500 ± 0.125"), std::string::npos) << all;
  const std::string enavi = TrendTable(trend, "enavi");
  EXPECT_EQ(enavi.find("baseline"), std::string::npos) << enavi;
  EXPECT_EQ(TrendTable(trend, "fixed"), "no results with this label and metric\n");
}

nlohmann::json WithEci(nlohmann::json r, double lo, double hi, int frames) {
  r["eci"] = {{"min", 0.0}, {"mean", 0.5}, {"max", 1.0}, {"flight_min", lo}, {"flight_max", hi},
              {"flight_frames", frames}};
  return r;
}

TEST(EciRangeTableTest, AveragesEachFlightsRangeAndPrintsThePapersBesideIt) {
  nlohmann::json results = nlohmann::json::array();
  results.push_back(WithEci(Result("x86", "baseline", "s1", 1, 50, 40, 45, true), 0.10, 0.80, 900));
  results.push_back(WithEci(Result("tx2", "baseline", "s1", 2, 50, 40, 45, true), 0.20, 0.90, 800));
  // Never took off: no range; the all-frames min of 0 must not reach the table.
  results.push_back(WithEci(Result("x86", "baseline", "s1", 3, 50, 40, 45, false), 0.0, 0.0, 0));
  // Stored before the flight fields existed.
  nlohmann::json old = Result("x86", "baseline", "s4", 1, 50, 40, 45, true);
  old["eci"] = {{"min", 0.0}, {"mean", 0.5}, {"max", 1.0}};
  results.push_back(old);
  results.push_back(WithEci(Result("x86", "enavi", "forest", 1, 50, 40, 45, true), 0.30, 0.40, 700));
  const std::string out = EciRangeTable(results);
  // s1: min (0.10 + 0.20) / 2 = 0.15, max (0.80 + 0.90) / 2 = 0.85; paper 0.06-0.87.
  EXPECT_NE(out.find("s1        baseline        2         1  0.15  0.85        0.10         0.90       0.06       0.87"
                     "      0.09     -0.02"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("s4        baseline        0         1     -     -           -            -       0.26       0.86"
                     "         -         -"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("forest    enavi           1         0  0.30  0.40        0.30         0.40          -          -"
                     "         -         -"),
            std::string::npos)
      << out;
  EXPECT_EQ(EciRangeTable(nlohmann::json::array()), "no results\n");
}

TEST(EciRangeTableTest, LeavesThePaperColumnsOutWithoutAPaperScenario) {
  nlohmann::json results = nlohmann::json::array();
  results.push_back(WithEci(Result("x86", "baseline", "canyon", 1, 50, 40, 45, true), 0.25, 0.75, 900));
  const std::string out = EciRangeTable(results);
  EXPECT_EQ(out.find("paper"), std::string::npos) << out;
  EXPECT_NE(out.find("canyon    baseline        1         0  0.25  0.75        0.25         0.75"), std::string::npos) << out;
}

TEST(PaperReferenceTest, EciRangesFollowTheScenarioOrder) {
  ASSERT_NE(FindPaperEciRange("s3"), nullptr);
  EXPECT_DOUBLE_EQ(FindPaperEciRange("s3")->min, 0.19);
  EXPECT_DOUBLE_EQ(FindPaperEciRange("s5")->max, 0.79);
  EXPECT_EQ(FindPaperEciRange("canyon"), nullptr);
}

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

// In a log, progress is a line at the start, each time another tenth is done, and every period
// when nothing moves; polls in between print nothing.
TEST(ProgressPacerTest, ALineEveryTenthOrEveryPeriod) {
  using std::chrono::seconds;
  const auto t0 = std::chrono::steady_clock::time_point{} + seconds(100);
  ProgressPacer pacer(seconds(10));
  EXPECT_TRUE(pacer.Due(0, 40, t0)) << "the first line";
  EXPECT_FALSE(pacer.Due(3, 40, t0 + seconds(1))) << "7.5 %: not yet a tenth";
  EXPECT_TRUE(pacer.Due(4, 40, t0 + seconds(2))) << "10 %";
  EXPECT_FALSE(pacer.Due(5, 40, t0 + seconds(3)));
  EXPECT_TRUE(pacer.Due(5, 40, t0 + seconds(12))) << "10 s since the last line";
  EXPECT_FALSE(pacer.Due(5, 40, t0 + seconds(13)));
  EXPECT_TRUE(pacer.Due(40, 40, t0 + seconds(14))) << "from 10 % to 100 % at once: one line";
  EXPECT_FALSE(pacer.Due(40, 40, t0 + seconds(15)));
  ProgressPacer unknown_total(seconds(10));
  EXPECT_TRUE(unknown_total.Due(0, 0, t0));
  EXPECT_FALSE(unknown_total.Due(0, 0, t0 + seconds(9)));
  EXPECT_TRUE(unknown_total.Due(0, 0, t0 + seconds(10)));
}

}  // namespace
}  // namespace enavi::server
