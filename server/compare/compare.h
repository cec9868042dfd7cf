#pragma once
// `enavi compare BASE CANDIDATE`: pairs the episodes of two jobs by (board, scenario, method,
// seed) and reports, per board x scenario x method cell, the change of every metric.
//
// On the virtual clock with the cost model a result is a function of its spec, so any difference
// is real: the report gives exact deltas and lists the episodes that changed ("exact" mode). On
// the emulated clock or with measured cost, flights are noisy: a paired t-test over the seeds
// gives a 95 % confidence interval of the mean difference, and a change is called only when
// the interval excludes zero ("paired" mode). Either way a regression is a change in the worse
// direction beyond the metric's threshold (metric_rules.h).

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/compare/metric_rules.h"

namespace enavi::server {

struct CompareOptions {
  MetricRules rules = DefaultMetricRules();
  std::string mode = "auto";  ///< auto (exact when both jobs are virtual clock + model), exact, paired
};

/// One metric of one cell.
struct MetricChange {
  std::string name;
  Direction direction = Direction::kNone;
  int pairs = 0;              ///< pairs the statistics use (success_only: both succeeded)
  double base_mean = 0, candidate_mean = 0, delta = 0;
  double ci_low = 0, ci_high = 0;  ///< 95 % CI of the mean difference over the pairs (the delta with < 2 pairs)
  /// Exact mode: a regression or improvement whose CI includes 0, i.e. real but within the
  /// seeds' draw (paired mode would call it insignificant).
  bool within_draw = false;
  double threshold = 0;       ///< |delta| beyond which the change counts
  int changed_pairs = 0;      ///< pairs whose values differ at all
  /// regression, improvement, change (no direction, or within threshold), same, insignificant,
  /// too_few_pairs (paired mode with < 2 pairs)
  std::string verdict;
};

/// An episode pair whose metrics differ (exact mode).
struct ChangedEpisode {
  std::uint64_t seed = 0;
  std::string base_episode, candidate_episode;
  std::vector<std::string> metrics;  ///< names that differ
};

struct CellChange {
  std::string board, scenario, method;
  int pairs = 0;
  std::vector<std::string> base_episodes, candidate_episodes;  ///< by seed, same order
  std::vector<std::uint64_t> seeds;
  std::vector<MetricChange> metrics;  ///< every metric present in the cell, by name
  std::vector<ChangedEpisode> changed;
  int regressions = 0, improvements = 0;
};

/// A provenance note (a result's notes "provenance.*", workers/sim/episode_provenance.h) whose
/// value differs between paired episodes: what, besides the code under test, changed between the
/// jobs. A different cost model (its prices or its pricing rule) re-prices CPU and timing on the
/// virtual clock, so those deltas are not the code's alone.
struct ProvenanceChange {
  std::string name;                  ///< without the "provenance." prefix, e.g. cost_model_sha256
  int cells = 0;                     ///< cells with at least one pair whose values differ
  std::vector<std::string> base_values, candidate_values;  ///< distinct values, sorted; "(none)": absent
  std::string meaning;               ///< what the difference does to the comparison; empty: nothing known
};

/// An episode result present in one job only.
struct Unpaired {
  std::string side;  ///< base or candidate
  std::string board, scenario, method, episode_id;
  std::uint64_t seed = 0;
};

struct CompareReport {
  std::string base, candidate;  ///< how the jobs were named (job id, FILE.db:JOB)
  std::string mode;             ///< exact or paired
  int base_results = 0, candidate_results = 0;
  std::vector<CellChange> cells;
  std::vector<Unpaired> unpaired;
  std::vector<ProvenanceChange> provenance;  ///< by name
  int regressions = 0, improvements = 0, changed_metrics = 0;
  int regressions_within_draw = 0;  ///< exact mode: regressions whose 95 % CI includes 0
  bool no_change() const { return changed_metrics == 0 && unpaired.empty(); }
};

/// Compares two lists of result objects (ResultQueries::Results / GET /api/jobs/{id}/results).
/// @throws std::invalid_argument for an unknown mode or a record without board/method/seed.
CompareReport Compare(const nlohmann::json& base, const nlohmann::json& candidate,
                      const CompareOptions& options, const std::string& base_name = "base",
                      const std::string& candidate_name = "candidate");

nlohmann::json CompareJson(const CompareReport& report);
/// Human-readable: changed metrics per cell, the changed episodes, unpaired results, a verdict.
std::string CompareTable(const CompareReport& report);
/// JUnit XML: a testsuite per cell, a testcase per judged metric (failure = regression);
/// unpaired results are skipped testcases.
std::string CompareJunit(const CompareReport& report);

/// The two-sided 95 % quantile of Student's t with `df` degrees of freedom.
double StudentT975(int df);

/// Adds "ci95" to every point of a trend (ResultQueries::Trend): the half-width of the 95 % interval of
/// its mean over the seeds' draw, t(df) x seed_std / sqrt(n); null where seed_std is.
void AddTrendIntervals(nlohmann::json* trend);

}  // namespace enavi::server
