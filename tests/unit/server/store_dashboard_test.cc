// The store's additions for the dashboard: labels, provenance, workers, aggregates computed in
// SQLite, read-only opening, and the migration of a database written before them.
#include <sqlite3.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <vector>

#include <gtest/gtest.h>

#include "server/store/jobs.h"
#include "server/store/queries.h"
#include "server/store/store.h"
#include "server/store/worker_store.h"
#include "tests/support/seed_store.h"

namespace enavi::server {
namespace {

namespace fs = std::filesystem;

constexpr const char* kJob = R"(name: nightly
labels: {suite: nightly, commit: 1a2b3c}
boards: [tx2, pi4b]
scenarios: [s1]
methods: [baseline, enavi]
seeds: 7
)";

class StoreDashboardTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("store_dashboard_test-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    store_ = std::make_unique<Store>(db());
  }
  void TearDown() override {
    store_.reset();
    fs::remove_all(dir_);
  }
  fs::path db() const { return dir_ / "farm.db"; }
  void Sql(const std::string& sql) {
    sqlite3* h = nullptr;
    ASSERT_EQ(sqlite3_open(db().c_str(), &h), SQLITE_OK);
    char* err = nullptr;
    const int rc = sqlite3_exec(h, sql.c_str(), nullptr, nullptr, &err);
    EXPECT_EQ(rc, SQLITE_OK) << (err ? err : "");
    sqlite3_free(err);
    sqlite3_close(h);
  }

  fs::path dir_;
  std::unique_ptr<Store> store_;
};

TEST_F(StoreDashboardTest, LabelsAndProvenanceAreStoredAndQueryable) {
  const std::string a = testing::SeedJob(*store_, kJob, 1000);
  const std::string b = testing::SeedJob(
      *store_, "name: other\nlabels: {suite: weekly}\nboards: [tx2]\nscenarios: [s1]\nmethods: [baseline]\nseeds: 1\n", 2000);
  const auto nightly = store_->jobs().ListJobs(3000, {{"suite", "nightly"}});
  ASSERT_EQ(nightly.size(), 1u);
  EXPECT_EQ(nightly[0].id, a);
  EXPECT_EQ(nightly[0].labels.at("commit"), "1a2b3c");
  EXPECT_EQ(nightly[0].provenance.at("clock"), "virtual");
  EXPECT_FALSE(nightly[0].provenance.at("git_commit").empty());
  EXPECT_EQ(store_->jobs().ListJobs(3000, {{"suite", "nightly"}, {"commit", "1a2b3c"}}).size(), 1u);
  EXPECT_TRUE(store_->jobs().ListJobs(3000, {{"suite", "nightly"}, {"commit", "ffff"}}).empty());
  EXPECT_EQ(store_->jobs().ListJobs(3000, {{"suite", "weekly"}}).at(0).id, b);
  EXPECT_EQ(store_->jobs().ListJobs(3000).size(), 2u);
}

TEST_F(StoreDashboardTest, SummaryStatisticsMatchTheResults) {
  const std::string job = testing::SeedJob(*store_, kJob, 1000);
  const nlohmann::json all = store_->queries().Results(job);
  const nlohmann::json summary = store_->queries().JobSummary(job, {});
  ASSERT_EQ(summary["total"], 4);
  ASSERT_EQ(summary["cells"].size(), 4u);
  // Recompute one cell by hand: pi4b baseline (cells are sorted by board, scenario, method).
  const nlohmann::json& cell = summary["cells"][0];
  EXPECT_EQ(cell["board"], "pi4b");
  EXPECT_EQ(cell["method"], "baseline");
  std::vector<double> ft, ok;
  for (const auto& r : all) {
    if (r["board"] != "pi4b" || r["method"] != "baseline") continue;
    ft.push_back(r["flight_time_s"]);
    if (r["success"]) ok.push_back(r["flight_time_s"]);
  }
  ASSERT_EQ(ft.size(), 7u);
  ASSERT_EQ(ok.size(), 6u);  // seed 7 collides
  double mean = 0, var = 0;
  for (double v : ft) mean += v / ft.size();
  for (double v : ft) var += (v - mean) * (v - mean) / (ft.size() - 1);
  const nlohmann::json& st = cell["metrics"]["flight_time_s"];
  EXPECT_EQ(st["n"], 7);
  EXPECT_NEAR(st["mean"].get<double>(), mean, 1e-9);
  EXPECT_NEAR(st["std"].get<double>(), std::sqrt(var), 1e-6);
  EXPECT_DOUBLE_EQ(st["min"].get<double>(), *std::min_element(ft.begin(), ft.end()));
  EXPECT_DOUBLE_EQ(st["max"].get<double>(), *std::max_element(ft.begin(), ft.end()));
  EXPECT_EQ(cell["success_only"]["flight_time_s"]["n"], 6);
  EXPECT_NEAR(cell["metrics"]["success"]["mean"].get<double>(), 6.0 / 7.0, 1e-12);
  // Paging: a page of cells.
  const nlohmann::json page = store_->queries().JobSummary(job, {2, 1});
  ASSERT_EQ(page["cells"].size(), 1u);
  EXPECT_EQ(page["cells"][0]["board"], "tx2");
  EXPECT_EQ(page["cells"][0]["method"], "baseline");
}

TEST_F(StoreDashboardTest, FailuresResultsPageAndTrend) {
  store_.reset();
  StoreOptions once;
  once.max_attempts = 1;
  store_ = std::make_unique<Store>(db(), once);
  const std::string job = testing::SeedJob(
      *store_, std::string(kJob) + "episode_overrides:\n  - match: {board: tx2, method: enavi, seed: 3}\n"
                                   "    overrides: {fake.exit_code: 9}\n", 1000);
  const nlohmann::json failures = store_->queries().JobFailures(job, {});
  // Four collisions (seed 7 of each cell) and the episode that failed.
  ASSERT_EQ(failures["total"], 5);
  bool found = false;
  for (const auto& f : failures["failures"]) {
    if (f["state"] == "failed") {
      found = true;
      EXPECT_NE(f["reason"].get<std::string>().find("exited with code 9"), std::string::npos);
    }
  }
  EXPECT_TRUE(found);
  EXPECT_EQ(store_->queries().JobSummary(job, {})["cells"][2]["failed_episodes"], 0);
  EXPECT_EQ(store_->queries().JobSummary(job, {})["cells"][3]["failed_episodes"], 1);
  const nlohmann::json page = store_->queries().ResultsPage(job, {10, 5});
  EXPECT_EQ(page["total"], 27);
  ASSERT_EQ(page["results"].size(), 5u);
  EXPECT_EQ(page["results"][0]["worker_host"], "seed-host");
  testing::SeedJob(*store_, kJob, 5000);
  const nlohmann::json trend = store_->queries().Trend("suite", "nightly", "nav_cpu_util_pct", {});
  EXPECT_EQ(trend["total"], 2);
  ASSERT_EQ(trend["points"].size(), 8u);  // 2 jobs x 2 boards x 2 methods
  EXPECT_EQ(trend["points"][0]["board"], "pi4b");
  EXPECT_EQ(trend["points"][0]["method"], "baseline");
  EXPECT_THROW(store_->queries().Trend("suite", "nightly", "x'); DROP TABLE jobs; --", {}), std::invalid_argument);
  // A metric no result of the series has is refused by name with the closest ones, not an empty
  // trend (which read as "no results"); a label no job carries is an empty series.
  try {
    store_->queries().Trend("suite", "nightly", "flight_time", {});
    FAIL() << "an unknown metric gave a trend";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "metric: 'flight_time': no result of the jobs labelled suite=nightly has it; did you mean flight_time_s?");
  }
  const nlohmann::json none = store_->queries().Trend("suite", "weekly", "flight_time", {});
  EXPECT_EQ(none["total"], 0);
  EXPECT_TRUE(none["points"].empty());
}

// A trend point's spread is the seeds' draw within each scenario, pooled; the difference between
// scenarios (flown by every job of the series) is not part of it.
TEST_F(StoreDashboardTest, TrendPoolsTheSpreadOverSeedsWithinEachScenario) {
  const std::string job = testing::SeedJob(
      *store_, "name: n\nlabels: {suite: nightly}\nboards: [tx2]\nscenarios: [s1, s3]\nmethods: [baseline]\nseeds: 4\n", 1000);
  std::map<std::string, std::vector<double>> by_scenario;
  double sum = 0;
  int n = 0;
  for (const auto& r : store_->queries().Results(job)) {
    const double v = r["flight_time_s"].get<double>();
    by_scenario[r["scenario"].get<std::string>()].push_back(v);
    sum += v;
    ++n;
  }
  ASSERT_EQ(n, 8);
  double ss = 0;
  for (const auto& [scenario, values] : by_scenario) {
    ASSERT_EQ(values.size(), 4u) << scenario;
    double m = 0;
    for (double v : values) m += v / 4;
    for (double v : values) ss += (v - m) * (v - m);
  }
  ASSERT_GT(ss, 0.0);  // the synthetic flights differ by seed
  // s3 flights 100 s longer: a scenario difference, which every job of a series flies alike.
  Sql("UPDATE results SET metrics_json = json_set(metrics_json, '$.flight_time_s', "
      "json_extract(metrics_json, '$.flight_time_s') + 100) WHERE scenario = 's3'");
  const nlohmann::json trend = store_->queries().Trend("suite", "nightly", "flight_time_s", {});
  ASSERT_EQ(trend["points"].size(), 1u);
  const nlohmann::json& p = trend["points"][0];
  EXPECT_EQ(p["n"], 8);
  EXPECT_EQ(p["df"], 6);  // (4 - 1) per scenario
  EXPECT_NEAR(p["mean"].get<double>(), (sum + 400) / 8, 1e-9);
  EXPECT_NEAR(p["seed_std"].get<double>(), std::sqrt(ss / 6), 1e-6);
  // One seed per scenario: no spread to estimate.
  testing::SeedJob(*store_, "name: one\nlabels: {suite: single}\nboards: [tx2]\nscenarios: [s1, s3]\nmethods: [baseline]\nseeds: 1\n", 2000);
  const nlohmann::json single = store_->queries().Trend("suite", "single", "flight_time_s", {});
  ASSERT_EQ(single["points"].size(), 1u);
  EXPECT_EQ(single["points"][0]["df"], 0);
  EXPECT_TRUE(single["points"][0]["seed_std"].is_null());
}

TEST_F(StoreDashboardTest, ReadOnlyStoreReadsAndNeverWrites) {
  const std::string job = testing::SeedJob(*store_, kJob, 1000);
  store_.reset();
  StoreOptions ro;
  ro.read_only = true;
  Store reader(db(), ro);
  EXPECT_EQ(reader.queries().Results(job).size(), 28u);
  EXPECT_EQ(reader.workers().KnownWorkers().size(), 1u);
  EXPECT_THROW(reader.jobs().CreateJob("x", "y", {api::EpisodeSpec{}}, 1), std::runtime_error);
  StoreOptions missing = ro;
  EXPECT_THROW({ Store s(dir_ / "nope.db", missing); }, std::runtime_error);
  EXPECT_FALSE(fs::exists(dir_ / "nope.db"));
}

// A database written before labels, provenance and metrics_json existed opens, gains them, and
// keeps every result (the metrics of old results are filled in).
TEST_F(StoreDashboardTest, OlderDatabaseIsMigratedInPlace) {
  const std::string job = testing::SeedJob(*store_, kJob, 1000);
  store_.reset();
  Sql("DROP TABLE job_labels; DROP TABLE workers; DROP TABLE cell_metrics; "
      "ALTER TABLE jobs DROP COLUMN provenance_json; ALTER TABLE results DROP COLUMN metrics_json;");
  {
    // Read-only, it is left as it is and the aggregates come from the results themselves.
    StoreOptions ro;
    ro.read_only = true;
    Store reader(db(), ro);
    EXPECT_EQ(reader.queries().JobSummary(job, {})["cells"][0]["metrics"]["flight_time_s"]["n"], 7);
    EXPECT_TRUE(reader.workers().KnownWorkers().empty());
  }
  store_ = std::make_unique<Store>(db());
  EXPECT_EQ(store_->queries().Results(job).size(), 28u);
  EXPECT_EQ(store_->queries().JobSummary(job, {})["cells"][0]["metrics"]["flight_time_s"]["n"], 7);
  EXPECT_TRUE(store_->jobs().Progress(job, 2000)->labels.empty());
  EXPECT_EQ(store_->jobs().ListJobs(2000, {{"suite", "nightly"}}).size(), 0u);
}

}  // namespace
}  // namespace enavi::server
