#pragma once
// The episode child: the contract between a farm worker (or the trainer's collection job) and the
// process that flies one episode. The worker writes the spec as a JSON file, runs
// `enavi episode --spec-file S --result-file R [--rollout-file T]` under its limits, and reads
// the result (and the rollout) back; each file is written atomically, so a killed child leaves
// none or a whole one.

#include <string>

#include "api/episode.h"
#include "workers/sim/episode.h"

namespace enavi::sim {

/// Reads an episode spec file: one JSON object of EpisodeSpec fields, every field known (a
/// misspelt field would otherwise fly the default spec instead of the one meant).
/// @throws std::invalid_argument naming the file and the field: unreadable, not JSON, not an
///         object, an unknown field, a field of the wrong type, a timeout out of range.
api::EpisodeSpec ReadSpecFile(const std::string& file);

struct ChildFiles {
  std::string spec_file;     ///< in
  std::string result_file;   ///< out: the full EpisodeResult as JSON
  /// out, optional: the training rollout: E-Navi's frequency decisions (JSON, rollout.h), or the
  /// learned method's navigation decisions (binary, nav_rollout.h)
  std::string rollout_file;
};

/// Flies the spec in files.spec_file with `options` (a rollout is recorded when
/// files.rollout_file is set: method learned then flies its file's actions through a NavStepper,
/// decision by decision) and writes the result and the rollout files.
/// @throws std::invalid_argument for a bad spec (ReadSpecFile) or world; what RunEpisode throws.
api::EpisodeResult RunEpisodeChild(const ChildFiles& files, EpisodeOptions options = {});

}  // namespace enavi::sim
