#pragma once
// `enavi dataset export`: a collection job's transitions as NumPy .npz shards plus a JSON schema
// (docs/rl.md, "Datasets"). Episodes are never split across shards; every array of a shard has
// one row per transition.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/rollout_records.h"

namespace enavi::dataset {

struct ExportOptions {
  std::filesystem::path out;        ///< directory, created; shards and schema.json go here
  std::size_t shard_steps = 100000; ///< a shard closes after the episode that reaches this
  std::string job_id;
};

struct ExportSummary {
  int episodes = 0;
  std::size_t steps = 0;
  std::vector<std::string> shards;
};

/// Writes shard-00000.npz, ... and schema.json.
/// @throws std::invalid_argument for rollouts that do not decode, differ in shape, or repeat an
///   episode; std::runtime_error on I/O failure.
ExportSummary ExportDataset(const std::vector<api::StoredRollout>& records, const ExportOptions& options);

/// The schema document (arrays, dtypes, shapes, meanings) for observations of `obs_dim` and
/// `num_actions` actions; ExportDataset adds the shards and totals.
nlohmann::json DatasetSchema(int obs_dim, int num_actions);

}  // namespace enavi::dataset
