#pragma once
// The farm's durable state in SQLite (WAL, synchronous=FULL): jobs, their episodes and the
// results. Every state transition is one transaction, so a server killed at any instant restarts
// from a consistent database (docs/farm.md).
//
// Episode states:  pending --lease--> leased --result ok--> done
//                     ^                  |  \--error / lease lost, attempts < max--> pending
//                     |                  \----error / lease lost, attempts = max--> failed
//                     \--rejected (attempt not counted)
// A job's pending and leased episodes become `cancelled` when it is cancelled. A result for a
// done episode is acknowledged and ignored (idempotent by episode id); a late ok result for a
// failed episode still makes it done.
//
// Time is passed in (now_ms, Unix ms) so tests control it; nothing here reads the clock.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/episode.h"
#include "api/farm_messages.h"
#include "api/http_schema.h"
#include "api/rollout_records.h"

namespace enavi::server {

class Database;
class Statement;

inline constexpr int kStoreSchemaVersion = 1;

struct StoreOptions {
  int max_attempts = 3;       ///< leases an episode may take before it is `failed`
  int busy_timeout_ms = 10000;
  /// Opens an existing database for reading only (`enavi dashboard`, `enavi compare`): no
  /// schema change, no checkpoints; every write throws.
  bool read_only = false;
};

/// One leased attempt handed to a worker.
struct Lease {
  std::string episode_id;
  std::string job_id;
  std::string worker;  ///< the worker it is leased to
  int attempt = 0;
  std::int64_t deadline_ms = 0;
  api::EpisodeSpec spec;
};

/// A lease that ended without a result (expired or its worker gone).
struct ReleasedLease {
  std::string episode_id;
  std::string job_id;
  std::string worker;
  int attempt = 0;
  bool failed = false;  ///< out of attempts: the episode is now `failed`
  std::string reason;
};

/// What ingesting one result did.
struct IngestOutcome {
  api::AckStatus ack = api::AckStatus::kStored;
  std::string detail;
  std::string job_id;
  std::string event;  ///< job event kind to publish: episode_done, episode_failed, requeued, ""
};

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

/// Paging of list endpoints.
struct Page {
  std::int64_t offset = 0;
  std::int64_t limit = 100;
};

/// Filters a worker announces: empty lists accept anything.
struct WorkerCapabilities {
  std::vector<std::string> boards;
  std::vector<std::string> clocks;
};

class Store {
 public:
  /// Opens or creates the database; refuses a database with a newer schema version.
  explicit Store(const std::filesystem::path& path, StoreOptions options = {});
  ~Store();
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;

  // ---- jobs ----
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

  // ---- scheduling ----
  /// Leases up to `count` pending episodes (oldest job first) a worker can run.
  std::vector<Lease> LeaseEpisodes(const std::string& worker_id, int count,
                                   const WorkerCapabilities& caps, std::int64_t deadline_ms,
                                   std::int64_t now_ms);
  /// Extends the listed leases held by `worker_id`; returns how many were extended.
  int RenewLeases(const std::string& worker_id, const std::vector<api::EpisodeRef>& running,
                  std::int64_t deadline_ms);
  /// The same for many workers in one transaction (worker id -> attempts it runs).
  int RenewLeases(const std::map<std::string, std::vector<api::EpisodeRef>>& running_by_worker,
                  std::int64_t deadline_ms);
  /// Ends every lease whose deadline passed: back to pending, or failed when out of attempts.
  std::vector<ReleasedLease> ExpireLeases(std::int64_t now_ms);
  /// Every lease held now, in no particular order.
  std::vector<Lease> HeldLeases();
  /// Ends every lease held by a worker that is gone.
  std::vector<ReleasedLease> ReleaseWorker(const std::string& worker_id, const std::string& reason,
                                           std::int64_t now_ms);
  /// Leased episodes per worker.
  std::map<std::string, int> LeasedCounts();
  /// The lease an episode attempt holds right now, if it is leased to `worker_id` with `attempt`.
  bool HoldsLease(const std::string& episode_id, int attempt, const std::string& worker_id);

  // ---- results ----
  /// Ingests a batch of results in one transaction; one outcome per message, in order.
  std::vector<IngestOutcome> Ingest(const std::vector<api::ResultMessage>& results,
                                    std::int64_t now_ms);
  /// Result objects of a job in episode order: the flat record plus episode_id, worker,
  /// attempt, wall_time_s.
  nlohmann::json Results(const std::string& job_id);
  /// The full result (series and events included) of a done episode.
  std::optional<api::EpisodeResult> FullResult(const std::string& episode_id);

  // ---- collection jobs (server/store/collect_store.cc) ----
  /// Keeps a policy by content hash (idempotent). @pre hash == Sha256Hex(json).
  void PutPolicy(const std::string& hash, const std::string& json, std::int64_t now_ms);
  std::optional<std::string> Policy(const std::string& hash);
  std::optional<CollectionInfo> Collection(const std::string& job_id);
  /// Policies of running collection jobs, hash -> JSON (published to workers).
  std::map<std::string, std::string> ActivePolicies();
  /// The job's stored rollouts in episode order (one per done episode, exactly once).
  std::vector<api::StoredRollout> Rollouts(const std::string& job_id);

  // ---- dashboard aggregates (computed in SQLite) ----
  /// Per board x scenario x method cell of a job (a page of cells, in that order): episodes,
  /// and per metric n, mean, std, min, max over the cell's results; "success_only" repeats the
  /// statistics over successful episodes. {"cells": [...], "total" (cells), "offset", "limit"}.
  nlohmann::json JobSummary(const std::string& job_id, const Page& page);
  /// A page of result objects (as Results) in episode order: {"results", "total", ...}.
  nlohmann::json ResultsPage(const std::string& job_id, const Page& page);
  /// Failed episodes and unsuccessful flights with their reasons: {"failures", "total", ...}.
  nlohmann::json JobFailures(const std::string& job_id, const Page& page);
  /// Mean of `metric` per job, board and method over the jobs with label `key=value`, oldest
  /// first: {"points": [{"job_id", "name", "created_ms", "board", "method", "n", "mean", "df",
  /// "seed_std"}], "total" (jobs), ...}. seed_std is the spread over seeds within each scenario,
  /// pooled over the scenarios (df = sum of n - 1 per scenario; null when df is 0).
  nlohmann::json Trend(const std::string& key, const std::string& value,
                       const std::string& metric, const Page& page);

  // ---- workers ----
  /// Remembers a worker's host, version and calibration (provenance of its results).
  void RecordWorker(const api::WorkerStatus& status, std::int64_t now_ms);
  /// Every worker this database has seen: {"worker_id", "host", "version", ...}.
  nlohmann::json KnownWorkers();

  int max_attempts() const { return options_.max_attempts; }

 private:
  std::vector<ReleasedLease> ReleaseWhere(const std::string& where, const std::string& arg,
                                          std::int64_t value, const std::string& reason,
                                          std::int64_t now_ms);
  void FinishJobsIfComplete(const std::vector<std::string>& job_ids, std::int64_t now_ms);
  api::JobProgress ProgressLocked(const std::string& job_id, std::int64_t now_ms);

  void CheckpointLoop(std::filesystem::path path);
  void Migrate();
  std::string ResultsQuery(bool paged);
  nlohmann::json ResultObject(const Statement& q);
  bool HasColumn(const std::string& table, const std::string& column);

  StoreOptions options_;
  std::mutex mutex_;  // one connection, used by the scheduler and the HTTP threads
  std::unique_ptr<Database> db_;
  // WAL checkpoints run on their own connection and thread, off the ingestion path: copying
  // pages into the database file inside a commit halved result ingestion with large series.
  std::mutex checkpoint_mutex_;
  std::condition_variable checkpoint_cv_;
  bool stop_checkpoints_ = false;
  std::thread checkpointer_;
};

/// Packs a time series into the compact binary form stored in the results table.
std::vector<std::uint8_t> PackSeries(const api::TimeSeries& series);
/// @throws std::invalid_argument on a malformed blob.
api::TimeSeries UnpackSeries(const std::vector<std::uint8_t>& blob);

}  // namespace enavi::server
