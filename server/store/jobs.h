#pragma once
// The store's job lifecycle: a job and its episodes are created together (all pending), report
// their progress, and end done (every episode finished) or cancelled (store.h has the states).

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "api/episode.h"
#include "api/http_schema.h"
#include "server/store/leases.h"

namespace enavi::server {

class Database;
struct StoreConnection;

struct EpisodeInfo {
  std::string id;
  int index = 0;
  std::string state;
  int attempts = 0;
  std::string lease_owner;
  std::int64_t lease_deadline_ms = 0;
  std::string last_error;
  api::EpisodeSpec spec;
};

/// A collection job: its episodes fly the policy `policy_hash` and store their rollouts.
struct CollectionInfo {
  std::string policy_hash;  ///< SHA-256 hex of the policy's canonical bytes (policies table)
  bool sample = false;
};

/// What a job carries besides its episodes: the spec's labels and where it came from.
struct JobMeta {
  std::map<std::string, std::string> labels;
  std::map<std::string, std::string> provenance;
};

class JobStore {
 public:
  explicit JobStore(StoreConnection& connection) : c_(connection) {}

  /// Stores a job and its episodes (all pending); returns the new job id.
  std::string CreateJob(const std::string& name, const std::string& spec_yaml,
                        const std::vector<api::EpisodeSpec>& episodes, std::int64_t now_ms,
                        const JobMeta& meta = {},
                        const std::optional<CollectionInfo>& collect = std::nullopt);
  std::optional<api::JobProgress> Progress(const std::string& job_id, std::int64_t now_ms);
  std::vector<api::JobProgress> ListJobs(std::int64_t now_ms);
  /// Jobs carrying every label of `labels` (all jobs when empty), oldest first.
  std::vector<api::JobProgress> ListJobs(std::int64_t now_ms,
                                         const std::map<std::string, std::string>& labels);
  /// Cancels a running job. Returns the leases it revoked (their workers should stop), or
  /// nullopt when there is no such job.
  std::optional<std::vector<ReleasedLease>> CancelJob(const std::string& job_id,
                                                      std::int64_t now_ms);
  std::vector<EpisodeInfo> Episodes(const std::string& job_id);

 private:
  api::JobProgress ProgressLocked(const std::string& job_id, std::int64_t now_ms);

  StoreConnection& c_;
};

/// Marks done every listed running job that has no pending or leased episode left. Called
/// inside the transaction that finished its episodes (leases.cc, ingest.cc).
void FinishJobsIfComplete(Database& db, const std::vector<std::string>& job_ids, std::int64_t now_ms);

}  // namespace enavi::server
