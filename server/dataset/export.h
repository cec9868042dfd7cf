#pragma once
// `enavi dataset export`: a collection job's transitions (E-Navi's frequency decisions, or the
// learned method's depth images and velocity commands) as NumPy .npz shards plus a JSON schema
// (docs/rl.md, "Datasets"). Episodes are never split across shards; every array of a shard has
// one row per transition.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/rollout_records.h"

namespace enavi::dataset {

inline constexpr std::size_t kFrequencyShardSteps = 100000;  // ~19 MB
inline constexpr std::size_t kNavShardSteps = 5000;          // ~31 MB at 64x48

struct ExportOptions {
  std::filesystem::path out;        ///< directory, created; shards and schema.json go here
  /// A shard closes after the episode that reaches this many steps; 0: the kind's default
  /// (kFrequencyShardSteps, or kNavShardSteps: images make a step ~3,000x larger).
  std::size_t shard_steps = 0;
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

/// The schema documents (arrays, dtypes, shapes, meanings): of E-Navi's frequency rollouts, for
/// observations of `obs_dim` and `num_actions` actions; of the learned method's (kind "nav"), for
/// width x height depth images. ExportDataset adds the shards and totals.
nlohmann::json DatasetSchema(int obs_dim, int num_actions);
nlohmann::json NavDatasetSchema(int width, int height, double max_depth_m);

}  // namespace enavi::dataset
