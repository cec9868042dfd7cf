#pragma once
// Stored rollouts as the HTTP API serves them (GET /api/jobs/{id}/rollouts): one record per done
// episode of a collection job, its rollout bytes as the worker sent them
// (navstack::rl::EncodeRollout) and what a dataset needs to know about the episode.
//
// Stream: "ENRS", u32 record count, then per record u32 + metadata JSON (every field below but
// `rollout`), u32 + rollout bytes. Little-endian.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace enavi::api {

struct StoredRollout {
  std::string episode_id;
  int index = 0;  ///< episode index in its job
  int attempt = 0;
  std::string worker;
  std::string board, scenario, world;
  std::uint64_t seed = 0;
  std::string policy_hash;  ///< SHA-256 hex of the policy the episode flew
  bool success = false, collided = false;
  double flight_time_s = 0, nav_cpu_util_pct = 0;
  std::string rollout;
};

std::string EncodeRolloutStream(const std::vector<StoredRollout>& records);
/// @throws std::invalid_argument naming `source` on a malformed stream.
std::vector<StoredRollout> DecodeRolloutStream(std::string_view bytes, const std::string& source);

}  // namespace enavi::api
