#pragma once
// `enavi compare BASE CANDIDATE`: pairs the episodes of two jobs by (board, scenario, method,
// seed) and reports, per board x scenario x method cell, the change of every metric.
//
// On the virtual clock with the cost model a result is a function of its spec, so any difference
// is real: the report gives exact deltas and lists the episodes that changed ("exact" mode). On
// the emulated clock or with measured cost, flights are noisy: a paired t-test over the seeds
// gives a 95 % confidence interval of the mean difference, and a change is called only when
// the interval excludes zero ("paired" mode). Either way a regression is a change in the worse
// direction beyond the metric's threshold (metric_rules.h). A mode that cannot tell (paired mode
// with one seed pair: no interval) says so: the report's verdict is cannot_judge, never "no
// regression". Before any metric the report lists how the two jobs' specs, labels and server
// builds differ, so an override that explains a change is seen with it.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/compare/metric_rules.h"

namespace enavi::server {

/// One job as `enavi compare` reads it (compare_sources.h fills it from a database or a server).
struct CompareInput {
  std::string name;  ///< how the job was named: a job id, FILE.db:JOB
  nlohmann::json results = nlohmann::json::array();  ///< result objects (ResultQueries::Results)
  /// Each episode's spec as stored (api::EpisodeSpec's JSON), by episode id; empty: unknown.
  std::map<std::string, nlohmann::json> specs;
  /// The job's record: its name, labels and provenance (the server build and inputs at
  /// submission); job_known false: the results alone are known.
  bool job_known = false;
  std::string job_name;
  std::map<std::string, std::string> labels, provenance;
};

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
  bool has_interval = false;  ///< the CI exists: 2 or more pairs and a change
  /// Exact mode: a regression or improvement whose CI includes 0, i.e. real but within the
  /// seeds' draw (paired mode would call it insignificant).
  bool within_draw = false;
  double threshold = 0;       ///< |delta| beyond which the change counts
  int changed_pairs = 0;      ///< pairs whose values differ at all
  /// regression, improvement, change (no direction, or within threshold), same, insignificant,
  /// too_few_pairs (paired mode with < 2 pairs and a delta beyond the threshold: no interval to
  /// judge it by)
  std::string verdict;
  /// too_few_pairs in the worse direction: whether it regressed, the mode cannot tell.
  bool undecided = false;
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
  int undecided = 0;  ///< metrics undecided (MetricChange::undecided)
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

/// A setting that differs between the two jobs: in their episodes' specs (overrides, policy,
/// clock, cost, dilation, timeout, world parameters, ...; episodes paired as results are, so an
/// override of one method shows in that method's cells), their labels, or the server build that
/// took them.
struct SpecChange {
  std::string name;  ///< overrides.planner.v_max, policy, clock; label.KEY; build.git_commit
  std::string kind;  ///< spec, label or build
  int cells = 0;     ///< spec: cells with a pair whose values differ; label, build: 0 (the whole job)
  /// Distinct values, sorted; "(default)" where a spec leaves it out, "(none)" for a label.
  std::vector<std::string> base_values, candidate_values;
};

/// An episode result present in one job only.
struct Unpaired {
  std::string side;  ///< base or candidate
  std::string board, scenario, method, episode_id;
  std::uint64_t seed = 0;
};

struct CompareReport {
  std::string base, candidate;  ///< how the jobs were named (job id, FILE.db:JOB)
  std::string base_job_name, candidate_job_name;  ///< the jobs' own names, when known
  std::string mode;             ///< exact or paired
  bool exact_applies = false;   ///< both jobs on the virtual clock with the cost model
  int base_results = 0, candidate_results = 0;
  std::vector<CellChange> cells;
  std::vector<Unpaired> unpaired;
  /// How the jobs differ, spec settings first, then labels and build; by name within each.
  std::vector<SpecChange> spec_changes;
  bool specs_compared = false;  ///< both jobs' episode specs were known
  int spec_cells = 0;           ///< cells with episodes in both jobs (SpecChange::cells is of these)
  bool jobs_compared = false;   ///< both jobs' records (labels, build) were known
  std::vector<ProvenanceChange> provenance;  ///< by name
  int regressions = 0, improvements = 0, changed_metrics = 0;
  int regressions_within_draw = 0;  ///< exact mode: regressions whose 95 % CI includes 0
  int regressions_without_interval = 0;  ///< regressions of cells with one pair: no CI at all
  int undecided = 0, undecided_cells = 0;  ///< CellChange::undecided, summed; cells with any
  bool no_change() const { return changed_metrics == 0 && unpaired.empty(); }
  /// regression (exit 3), cannot_judge (exit 4: a metric could have regressed but the mode has
  /// no interval to tell), no_change or no_regression (exit 0).
  std::string verdict() const;
};

/// Compares two jobs' results (ResultQueries::Results / GET /api/jobs/{id}/results).
/// @throws std::invalid_argument for an unknown mode or a record without board/method/seed.
CompareReport Compare(const CompareInput& base, const CompareInput& candidate, const CompareOptions& options);
/// The same for two lists of result objects alone (no specs, no job records).
CompareReport Compare(const nlohmann::json& base, const nlohmann::json& candidate,
                      const CompareOptions& options, const std::string& base_name = "base",
                      const std::string& candidate_name = "candidate");

nlohmann::json CompareJson(const CompareReport& report);
/// Human-readable: changed metrics per cell, the changed episodes, unpaired results, a verdict.
std::string CompareTable(const CompareReport& report);
/// JUnit XML: first a testsuite "how the jobs differ" whose properties are the spec changes,
/// then a testsuite per cell, a testcase per judged metric (failure = regression, error = cannot
/// judge); unpaired results are skipped testcases.
std::string CompareJunit(const CompareReport& report);

/// The two-sided 95 % quantile of Student's t with `df` degrees of freedom.
double StudentT975(int df);

/// Adds "ci95" to every point of a trend (ResultQueries::Trend): the half-width of the 95 % interval of
/// its mean over the seeds' draw, t(df) x seed_std / sqrt(n); null where seed_std is.
void AddTrendIntervals(nlohmann::json* trend);

}  // namespace enavi::server
