#pragma once
// The store's collection-job tables (docs/rl.md): policies kept by content hash, which job flies
// which policy, and the rollouts stored with their episodes' results (ingest.cc writes them).

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "api/rollout_records.h"
#include "server/store/jobs.h"

namespace enavi::server {

struct StoreConnection;

class CollectStore {
 public:
  explicit CollectStore(StoreConnection& connection) : c_(connection) {}

  /// Keeps a policy by content hash (idempotent). @pre hash == Sha256Hex(json).
  void PutPolicy(const std::string& hash, const std::string& json, std::int64_t now_ms);
  std::optional<std::string> Policy(const std::string& hash);
  std::optional<CollectionInfo> Collection(const std::string& job_id);
  /// Policies of running collection jobs, hash -> JSON (published to workers).
  std::map<std::string, std::string> ActivePolicies();
  /// The job's stored rollouts in episode order (one per done episode, exactly once).
  std::vector<api::StoredRollout> Rollouts(const std::string& job_id);

 private:
  StoreConnection& c_;
};

}  // namespace enavi::server
