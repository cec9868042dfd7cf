#pragma once
// The store's reads for the dashboard and `enavi compare`: result objects (whole or paged), the
// full result of one episode, and aggregates computed in SQLite (per-cell statistics from the
// running sums, failures, a metric's trend over a label series).

#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "api/episode.h"

namespace enavi::server {

struct StoreConnection;

/// Paging of list endpoints.
struct Page {
  std::int64_t offset = 0;
  std::int64_t limit = 100;
};

class ResultQueries {
 public:
  explicit ResultQueries(StoreConnection& connection) : c_(connection) {}

  /// Result objects of a job in episode order: the flat record plus episode_id, worker,
  /// attempt, wall_time_s.
  nlohmann::json Results(const std::string& job_id);
  /// The full result (series and events included) of a done episode.
  std::optional<api::EpisodeResult> FullResult(const std::string& episode_id);
  /// A page of result objects (as Results) in episode order: {"results", "total", ...}.
  nlohmann::json ResultsPage(const std::string& job_id, const Page& page);
  /// Per board x scenario x method cell of a job (a page of cells, in that order): episodes,
  /// and per metric n, mean, std, min, max over the cell's results; "success_only" repeats the
  /// statistics over successful episodes. {"cells": [...], "total" (cells), "offset", "limit"}.
  nlohmann::json JobSummary(const std::string& job_id, const Page& page);
  /// Failed episodes and unsuccessful flights with their reasons: {"failures", "total", ...}.
  nlohmann::json JobFailures(const std::string& job_id, const Page& page);
  /// Mean of `metric` per job, board and method over the jobs with label `key=value`, oldest
  /// first: {"points": [{"job_id", "name", "created_ms", "board", "method", "n", "mean", "df",
  /// "seed_std"}], "total" (jobs), ...}. seed_std is the spread over seeds within each scenario,
  /// pooled over the scenarios (df = sum of n - 1 per scenario; null when df is 0).
  /// @throws std::invalid_argument naming the metric when no result of the series has it (with
  /// the names closest to it) or it has characters no metric name has.
  nlohmann::json Trend(const std::string& key, const std::string& value,
                       const std::string& metric, const Page& page);

 private:
  StoreConnection& c_;
};

}  // namespace enavi::server
