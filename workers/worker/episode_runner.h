#pragma once
// Runs one episode in a child process: writes the spec, executes
//   <command...> --spec-file SPEC.json --result-file RESULT.json
// under memory/CPU limits and a wall-clock timeout, and reads the result back. Exit code 0 means
// RESULT.json holds a full api::EpisodeResult (even for a crashed flight); anything else is an
// episode error whose message carries the tail of the child's stderr.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "api/episode.h"

namespace enavi::worker {

struct EpisodeLimits {
  std::int64_t memory_bytes = std::int64_t{8} << 30;  ///< RLIMIT_AS; 0: none
  std::int64_t cpu_seconds = 4 * 3600;                ///< RLIMIT_CPU; 0: none
  std::chrono::seconds wall_timeout{3600};
};

struct EpisodeRun {
  std::vector<std::string> command;  ///< e.g. {"/usr/bin/enavi", "fly"}
  std::filesystem::path dir;         ///< working directory, created; spec, result and logs go here
  EpisodeLimits limits;
  std::vector<std::string> env;      ///< NAME=value for the child (episode id, attempt, ...)
  bool collect_rollout = false;      ///< also pass --rollout-file and read the rollout back
};

struct EpisodeOutcome {
  enum class Kind { kResult, kError, kAborted };
  Kind kind = Kind::kError;
  std::string error;       ///< kError: what went wrong
  double wall_time_s = 0;
  api::EpisodeResult result;  ///< kResult
  std::string rollout;        ///< kResult of a collect_rollout run: EncodeRollout or EncodeNavRollout
};

/// The production episode command: this executable's `fly` subcommand.
std::vector<std::string> DefaultEpisodeCommand();

/// Runs the episode; returns early with kAborted (child killed) once `abort` becomes true.
EpisodeOutcome RunEpisode(const api::EpisodeSpec& spec, const EpisodeRun& run,
                          const std::atomic<bool>& abort);

}  // namespace enavi::worker
