#include "server/compare/compare.h"

#include <gtest/gtest.h>

#include "api/episode.h"
#include "tests/support/synthetic_result.h"

namespace enavi::server {
namespace {

// Result objects as ResultQueries::Results returns them: the flat record plus episode_id.
nlohmann::json Job(const std::string& prefix, const std::vector<std::string>& boards, int seeds,
                   double v_max_on_tx2 = 0, const std::string& clock = "virtual") {
  nlohmann::json list = nlohmann::json::array();
  int i = 0;
  for (const auto& board : boards) {
    for (const char* method : {"baseline", "enavi"}) {
      for (int seed = 1; seed <= seeds; ++seed) {
        api::EpisodeSpec spec;
        spec.world = "s1";
        spec.board = board;
        spec.method = method;
        spec.seed = seed;
        spec.clock = clock;
        if (v_max_on_tx2 > 0 && board == "tx2") spec.overrides["planner.v_max"] = v_max_on_tx2;
        nlohmann::json r = api::ResultSummaryJson(testing::SyntheticResult(spec));
        r["episode_id"] = prefix + "-" + std::to_string(i++);
        list.push_back(std::move(r));
      }
    }
  }
  return list;
}

const MetricChange& Metric(const CompareReport& r, const std::string& board, const std::string& method,
                           const std::string& name) {
  for (const auto& c : r.cells) {
    if (c.board != board || c.method != method) continue;
    for (const auto& m : c.metrics) {
      if (m.name == name) return m;
    }
  }
  throw std::runtime_error("no metric " + name);
}

TEST(CompareTest, SameResultsAreNoChange) {
  const auto a = Job("a", {"tx2", "pi4b"}, 3);
  const CompareReport r = Compare(a, a, {});
  EXPECT_EQ(r.mode, "exact");
  EXPECT_TRUE(r.no_change());
  EXPECT_EQ(r.regressions, 0);
  EXPECT_EQ(r.cells.size(), 4u);
  EXPECT_NE(CompareTable(r).find("no change"), std::string::npos);
}

// A record's count map lists only the triggers that fired. A trigger in one pair only is no
// change of the other pairs; one that fires only in the candidate is a change from 0.
TEST(CompareTest, CountMapKeysThatDidNotOccurCountAsZero) {
  nlohmann::json a = Job("a", {"tx2"}, 3), b = Job("b", {"tx2"}, 3);
  for (auto* job : {&a, &b}) {
    for (auto& r : *job) {
      if (r["seed"] == 1) r["replans_by_trigger"]["difference"] = 2;
    }
  }
  const CompareReport same = Compare(a, b, {});
  EXPECT_TRUE(same.no_change()) << CompareTable(same);
  for (const auto& c : same.cells) EXPECT_TRUE(c.changed.empty()) << c.board << "/" << c.method;

  for (auto& r : b) {
    if (r["method"] == "enavi") r["replans_by_trigger"]["speed_limit"] = 4;
  }
  const CompareReport r = Compare(a, b, {});
  const MetricChange& m = Metric(r, "tx2", "enavi", "replans_by_trigger.speed_limit");
  EXPECT_EQ(m.verdict, "change");
  EXPECT_EQ(m.pairs, 3);
  EXPECT_DOUBLE_EQ(m.base_mean, 0.0);
  EXPECT_DOUBLE_EQ(m.candidate_mean, 4.0);
  for (const auto& c : r.cells) {
    EXPECT_EQ(c.changed.size(), c.method == "enavi" ? 3u : 0u) << c.method;
    for (const auto& e : c.changed) EXPECT_EQ(e.metrics, std::vector<std::string>{"replans_by_trigger.speed_limit"});
  }
}

TEST(CompareTest, ExactModeGivesExactDeltasAndNamesTheRegressedCell) {
  const auto a = Job("a", {"tx2", "pi4b"}, 3);
  const auto b = Job("b", {"tx2", "pi4b"}, 3, /*v_max_on_tx2=*/1.0);  // twice the flight time
  const CompareReport r = Compare(a, b, {});
  const MetricChange& ft = Metric(r, "tx2", "baseline", "flight_time_s");
  EXPECT_EQ(ft.verdict, "regression");
  EXPECT_DOUBLE_EQ(ft.delta, ft.base_mean);  // exactly doubled
  EXPECT_EQ(ft.changed_pairs, 3);
  EXPECT_EQ(Metric(r, "pi4b", "baseline", "flight_time_s").verdict, "same");
  EXPECT_EQ(r.regressions, 2);  // tx2 baseline and tx2 enavi
  ASSERT_EQ(r.cells[0].changed.size(), 3u);
  EXPECT_EQ(r.cells[0].changed[0].base_episode, "a-0");
  EXPECT_EQ(r.cells[0].changed[0].candidate_episode, "b-0");
  // Deterministic: the report is a function of the inputs.
  EXPECT_EQ(CompareJson(r).dump(), CompareJson(Compare(a, b, {})).dump());
}

TEST(CompareTest, ProvenanceThatDiffersIsNamedWithWhatItMeans) {
  auto stamp = [](nlohmann::json job, const std::string& tx2_cost_model) {
    for (auto& r : job) {
      r["notes"]["provenance.git_commit"] = "abc123";
      r["notes"]["provenance.cost_model_sha256"] = r["board"] == "tx2" ? tx2_cost_model : "pi4b-prices";
    }
    return job;
  };
  const auto a = stamp(Job("a", {"tx2", "pi4b"}, 2), "tx2-rev1");
  EXPECT_TRUE(Compare(a, a, {}).provenance.empty());

  auto b = stamp(Job("b", {"tx2", "pi4b"}, 2), "tx2-rev2");
  b[0]["notes"].erase("provenance.git_commit");  // a result stored before the note existed
  const CompareReport r = Compare(a, b, {});
  ASSERT_EQ(r.provenance.size(), 2u);
  const ProvenanceChange& cost = r.provenance[0];
  EXPECT_EQ(cost.name, "cost_model_sha256");
  EXPECT_EQ(cost.cells, 2) << "tx2 baseline and tx2 enavi, not pi4b";
  EXPECT_EQ(cost.base_values, (std::vector<std::string>{"pi4b-prices", "tx2-rev1"}));
  EXPECT_EQ(cost.candidate_values, (std::vector<std::string>{"pi4b-prices", "tx2-rev2"}));
  EXPECT_NE(cost.meaning.find("re-pricing"), std::string::npos) << cost.meaning;
  const ProvenanceChange& commit = r.provenance[1];
  EXPECT_EQ(commit.name, "git_commit");
  EXPECT_EQ(commit.cells, 1);
  EXPECT_EQ(commit.candidate_values, (std::vector<std::string>{"(none)", "abc123"}));
  EXPECT_TRUE(commit.meaning.empty());
  EXPECT_TRUE(r.no_change()) << "provenance alone is not a change of any metric";

  const std::string table = CompareTable(r);
  EXPECT_NE(table.find("cost_model_sha256 in 2 of 4 cells: pi4b-prices, tx2-rev1 -> pi4b-prices, tx2-rev2"),
            std::string::npos)
      << table;
  EXPECT_EQ(CompareJson(r)["provenance"][0]["cells"], 2);
}

TEST(CompareTest, RunsFromHostsWithOtherRayKernelsAreNamed) {
  auto on = [](nlohmann::json job, const std::string& kernels) {
    for (auto& r : job) r["notes"]["provenance.ray_kernels"] = kernels;
    return job;
  };
  const auto a = on(Job("a", {"tx2"}, 2), "avx2");
  const CompareReport r = Compare(a, on(Job("b", {"tx2"}, 2), "sse-avx"), {});
  ASSERT_EQ(r.provenance.size(), 1u);
  EXPECT_EQ(r.provenance[0].name, "ray_kernels");
  EXPECT_NE(r.provenance[0].meaning.find("no change of code"), std::string::npos) << r.provenance[0].meaning;
  EXPECT_TRUE(Compare(a, a, {}).provenance.empty());
}

TEST(CompareTest, BetterIsAnImprovementAndUnjudgedMetricsOnlyChange) {
  const auto a = Job("a", {"tx2"}, 2, 1.0);
  const auto b = Job("b", {"tx2"}, 2);
  const CompareReport r = Compare(a, b, {});
  EXPECT_EQ(r.regressions, 0);
  EXPECT_EQ(Metric(r, "tx2", "baseline", "flight_time_s").verdict, "improvement");
  EXPECT_EQ(Metric(r, "tx2", "baseline", "velocity_mean_mps").verdict, "change");
  EXPECT_EQ(Metric(r, "tx2", "baseline", "velocity_mean_mps").direction, Direction::kNone);
}

TEST(CompareTest, UnpairedResultsAreListedNotDropped) {
  const auto a = Job("a", {"tx2", "pi4b"}, 3);
  auto b = Job("b", {"tx2"}, 2);
  const CompareReport r = Compare(a, b, {});
  // pi4b: 6 results only in base; tx2: seed 3 of both methods only in base.
  EXPECT_EQ(r.unpaired.size(), 8u);
  EXPECT_FALSE(r.no_change());
  EXPECT_NE(CompareTable(r).find("base only: pi4b/s1/baseline seed 1 (a-"), std::string::npos);
}

// Noisy flights (emulated clock): a small consistent slowdown is significant, a larger but
// erratic one is not.
TEST(CompareTest, PairedModeCallsOnlySignificantChanges) {
  auto a = Job("a", {"tx2"}, 8, 0, "emulated");
  auto b = a;
  const double noise[8] = {0.3, -0.2, 0.1, -0.4, 0.2, 0.0, -0.1, 0.3};
  for (std::size_t i = 0; i < 8; ++i) {
    b[i]["flight_time_s"] = a[i]["flight_time_s"].get<double>() * 1.10 + noise[i] * 0.1;  // baseline
    const double erratic = (i % 2 ? 1.0 : -1.0) * 6.0 + 1.0;
    b[8 + i]["flight_time_s"] = a[8 + i]["flight_time_s"].get<double>() + erratic;  // enavi
  }
  const CompareReport r = Compare(a, b, {});
  EXPECT_EQ(r.mode, "paired");
  const MetricChange& slow = Metric(r, "tx2", "baseline", "flight_time_s");
  EXPECT_EQ(slow.verdict, "regression");
  EXPECT_GT(slow.ci_low, 0.0);
  const MetricChange& erratic = Metric(r, "tx2", "enavi", "flight_time_s");
  EXPECT_EQ(erratic.verdict, "insignificant");
  EXPECT_LT(erratic.ci_low, 0.0);
  EXPECT_GT(erratic.ci_high, 0.0);
  EXPECT_EQ(r.regressions, 1);
}

// Exact mode judges by the delta (any difference is real) and says which verdicts the seeds'
// draw alone could give: the same data as above on the virtual clock.
TEST(CompareTest, ExactModeNamesTheRegressionsWithinTheSeedsDraw) {
  auto a = Job("a", {"tx2"}, 8);
  auto b = a;
  const double noise[8] = {0.3, -0.2, 0.1, -0.4, 0.2, 0.0, -0.1, 0.3};
  for (std::size_t i = 0; i < 8; ++i) {
    b[i]["flight_time_s"] = a[i]["flight_time_s"].get<double>() * 1.10 + noise[i] * 0.1;
    b[8 + i]["flight_time_s"] = a[8 + i]["flight_time_s"].get<double>() + (i % 2 ? 1.0 : -1.0) * 6.0 + 1.0;
  }
  const CompareReport r = Compare(a, b, {});
  ASSERT_EQ(r.mode, "exact");
  const MetricChange& slow = Metric(r, "tx2", "baseline", "flight_time_s");
  EXPECT_EQ(slow.verdict, "regression");
  EXPECT_FALSE(slow.within_draw);
  EXPECT_GT(slow.ci_low, 0.0);
  const MetricChange& erratic = Metric(r, "tx2", "enavi", "flight_time_s");
  EXPECT_EQ(erratic.verdict, "regression");  // +1 s mean is beyond the 5 % threshold
  EXPECT_TRUE(erratic.within_draw);
  EXPECT_LT(erratic.ci_low, 0.0);
  EXPECT_GT(erratic.ci_high, 0.0);
  EXPECT_EQ(r.regressions, 2);
  EXPECT_EQ(r.regressions_within_draw, 1);
  const std::string text = CompareTable(r);
  EXPECT_NE(text.find("1 of the 2 are within the seeds' draw"), std::string::npos) << text;
  EXPECT_EQ(CompareJson(r)["regressions_within_draw"], 1);
}

TEST(CompareTest, ThresholdFileOverridesDefaultsAndAddsMetrics) {
  const MetricRules rules = ParseMetricRules(
      "metrics:\n  flight_time_s: {rel: 2.0}\n  velocity_mean_mps: {direction: higher, rel: 0.01}\n", "t.yaml");
  CompareOptions options;
  options.rules = rules;
  const CompareReport r = Compare(Job("a", {"tx2"}, 2), Job("b", {"tx2"}, 2, 1.0), options);
  EXPECT_EQ(Metric(r, "tx2", "baseline", "flight_time_s").verdict, "change");
  EXPECT_EQ(Metric(r, "tx2", "baseline", "velocity_mean_mps").verdict, "regression");
  EXPECT_TRUE(rules.at("flight_time_s").success_only);  // unchanged fields keep the default
}

TEST(CompareTest, BadThresholdFileNamesLineFieldAndReason) {
  try {
    ParseMetricRules("metrics:\n  flight_time_s:\n    direction: sideways\n", "t.yaml");
    FAIL() << "accepted a bad direction";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "t.yaml:3: metrics.flight_time_s.direction: 'sideways': expected lower, higher or none");
  }
  EXPECT_THROW(ParseMetricRules("metric: {}\n", "t.yaml"), std::invalid_argument);
  EXPECT_THROW(ParseMetricRules("metrics:\n  x: {abs: nope}\n", "t.yaml"), std::invalid_argument);
  CompareOptions fast;
  fast.mode = "fast";
  EXPECT_THROW(Compare(nlohmann::json::array(), nlohmann::json::array(), fast), std::invalid_argument);
}

TEST(CompareTest, JunitEscapesNamesAndCountsFailures) {
  nlohmann::json a = nlohmann::json::array({Job("a", {"tx2"}, 1)[0]});
  a[0]["method"] = "<m&\"x\">";
  auto b = a;
  b[0]["success"] = false;
  const std::string xml = CompareJunit(Compare(a, b, {}));
  EXPECT_NE(xml.find("classname=\"tx2.s1.&lt;m&amp;&quot;x&quot;&gt;\""), std::string::npos) << xml;
  EXPECT_EQ(xml.find("<m&"), std::string::npos);
  EXPECT_NE(xml.find("failures=\"1\""), std::string::npos);
}

// Issue 44's case: one seed per cell, the candidate with planner.v_max 1.0 on tx2 (twice the
// flight time), compared in paired mode. With one pair there is no interval: the report says the
// mode cannot judge, never "no regression", and the verdict is its own (exit 4 at the CLI).
TEST(CompareTest, PairedModeWithOnePairCannotJudgeAndSaysSo) {
  CompareOptions paired;
  paired.mode = "paired";
  const CompareReport r = Compare(Job("a", {"tx2"}, 1), Job("b", {"tx2"}, 1, /*v_max_on_tx2=*/1.0), paired);
  const MetricChange& ft = Metric(r, "tx2", "baseline", "flight_time_s");
  EXPECT_EQ(ft.verdict, "too_few_pairs");
  EXPECT_TRUE(ft.undecided);
  EXPECT_FALSE(ft.has_interval);
  EXPECT_EQ(r.regressions, 0);
  EXPECT_GT(r.undecided, 0);
  EXPECT_EQ(r.undecided_cells, 2);
  EXPECT_EQ(r.verdict(), "cannot_judge");
  EXPECT_TRUE(r.exact_applies);
  const std::string text = CompareTable(r);
  EXPECT_NE(text.find("CANNOT JUDGE: "), std::string::npos) << text;
  EXPECT_NE(text.find("or compare with --mode exact"), std::string::npos) << text;
  EXPECT_EQ(text.find("no regression"), std::string::npos) << text;
  EXPECT_EQ(CompareJson(r)["verdict"], "cannot_judge");
  EXPECT_EQ(CompareJson(r)["undecided"], r.undecided);
  // JUnit: an error per metric the gate cannot judge, so a CI server fails the build.
  const std::string xml = CompareJunit(r);
  EXPECT_NE(xml.find("type=\"cannot_judge\""), std::string::npos) << xml;
  EXPECT_NE(xml.find("errors=\"" + std::to_string(r.undecided) + "\""), std::string::npos) << xml;
  // Exact mode, the default where it applies, calls the same change a regression; with one pair it
  // says no interval exists rather than counting it as outside the draw.
  const CompareReport exact = Compare(Job("a", {"tx2"}, 1), Job("b", {"tx2"}, 1, 1.0), {});
  EXPECT_EQ(exact.mode, "exact");
  EXPECT_EQ(exact.verdict(), "regression");
  EXPECT_EQ(exact.regressions_within_draw, 0);
  EXPECT_EQ(exact.regressions_without_interval, exact.regressions);
  EXPECT_NE(CompareTable(exact).find("in cells of one seed pair: no interval"), std::string::npos);
}

// A change within its threshold is no regression whatever the interval: one pair suffices.
TEST(CompareTest, PairedModeWithOnePairJudgesAChangeWithinTheThreshold) {
  nlohmann::json a = Job("a", {"tx2"}, 1), b = a;
  b[0]["flight_time_s"] = a[0]["flight_time_s"].get<double>() * 1.01;  // +1 %, threshold 5 %
  CompareOptions paired;
  paired.mode = "paired";
  const CompareReport r = Compare(a, b, paired);
  EXPECT_EQ(Metric(r, "tx2", "baseline", "flight_time_s").verdict, "change");
  EXPECT_EQ(r.verdict(), "no_regression");
}

// How the jobs differ (specs per pair, labels, the server build) is listed before any metric, in
// every form of the report.
TEST(CompareTest, SpecLabelAndBuildDifferencesComeBeforeTheMetrics) {
  auto input = [](const std::string& name, double v_max_on_tx2, const std::string& label, const std::string& commit) {
    CompareInput in;
    in.name = name;
    in.results = Job(name, {"tx2", "pi4b"}, 2, v_max_on_tx2);
    for (const auto& r : in.results) {
      api::EpisodeSpec spec;
      spec.world = "s1";
      spec.board = r["board"];
      spec.method = r["method"];
      spec.seed = r["seed"];
      if (v_max_on_tx2 > 0 && spec.board == "tx2") spec.overrides["planner.v_max"] = v_max_on_tx2;
      in.specs[r["episode_id"]] = spec;
    }
    in.job_known = true;
    in.job_name = name;
    in.labels = {{"run", label}};
    in.provenance = {{"git_commit", commit}, {"enavi_version", "0.1.0"}, {"clock", "virtual"}};
    return in;
  };
  const CompareReport same = Compare(input("a", 0, "fast", "c1"), input("a", 0, "fast", "c1"), {});
  EXPECT_TRUE(same.spec_changes.empty());
  EXPECT_NE(CompareTable(same).find("the two jobs' specs, labels and server builds are the same"), std::string::npos);

  const CompareReport r = Compare(input("a", 0, "fast", "c1"), input("b", 1.0, "slow", "c2"), {});
  ASSERT_EQ(r.spec_changes.size(), 3u);
  EXPECT_EQ(r.spec_changes[0].name, "overrides.planner.v_max");
  EXPECT_EQ(r.spec_changes[0].kind, "spec");
  EXPECT_EQ(r.spec_changes[0].cells, 2) << "tx2 baseline and tx2 enavi, not pi4b";
  EXPECT_EQ(r.spec_changes[0].base_values, std::vector<std::string>{"(default)"});
  EXPECT_EQ(r.spec_changes[0].candidate_values, std::vector<std::string>{"1.0"});
  EXPECT_EQ(r.spec_changes[1].name, "label.run");
  EXPECT_EQ(r.spec_changes[1].kind, "label");
  EXPECT_EQ(r.spec_changes[2].name, "build.git_commit");
  EXPECT_EQ(r.spec_changes[2].candidate_values, std::vector<std::string>{"c2"});
  const std::string text = CompareTable(r);
  const std::size_t differ = text.find("how the jobs differ");
  ASSERT_NE(differ, std::string::npos) << text;
  EXPECT_NE(text.find("overrides.planner.v_max in 2 of 4 cells: (default) -> 1.0"), std::string::npos) << text;
  EXPECT_NE(text.find("label.run: fast -> slow"), std::string::npos) << text;
  EXPECT_LT(differ, text.find("tx2/s1/baseline")) << text;
  EXPECT_NE(text.find("('b', 8 results)"), std::string::npos) << text;
  const nlohmann::json j = CompareJson(r);
  EXPECT_EQ(j["spec_changes"][0]["name"], "overrides.planner.v_max");
  EXPECT_EQ(j["spec_changes"][0]["candidate_values"][0], "1.0");
  EXPECT_TRUE(j["specs_compared"]);
  const std::string xml = CompareJunit(r);
  EXPECT_LT(xml.find("<testsuite name=\"how the jobs differ\""), xml.find("<testsuite name=\"tx2/s1/baseline\""));
  EXPECT_NE(xml.find("<property name=\"overrides.planner.v_max\" value=\"(default) -&gt; 1.0 (in 2 of 4 cells)\"/>"),
            std::string::npos)
      << xml;
}

TEST(CompareTest, StudentQuantilesMatchTheTable) {
  EXPECT_DOUBLE_EQ(StudentT975(1), 12.706);
  EXPECT_DOUBLE_EQ(StudentT975(9), 2.262);
  EXPECT_DOUBLE_EQ(StudentT975(30), 2.042);
  EXPECT_DOUBLE_EQ(StudentT975(500), 1.980);
  EXPECT_THROW(StudentT975(0), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::server
