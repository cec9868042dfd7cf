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
// The store is in rooms, each a narrow header over the one connection this class opens:
//   jobs.h          job lifecycle: create, progress, list, cancel, episodes
//   leases.h        scheduling: lease, renew, expire, release
//   ingest.h        results in: one transaction per batch, with the per-cell running sums
//   queries.h       reads for the dashboard and `enavi compare`: results, summaries, trend
//   collect_store.h collection jobs: policies and rollouts
//   worker_store.h  the workers seen (provenance of their results)
//   schema.h        tables and migrations; series_codec.h the stored time series
// Time is passed in (now_ms, Unix ms) so tests control it; nothing here reads the clock.

#include <condition_variable>
#include <filesystem>
#include <memory>
#include <mutex>
#include <thread>

namespace enavi::server {

struct StoreOptions {
  int max_attempts = 3;       ///< leases an episode may take before it is `failed`
  int busy_timeout_ms = 10000;
  /// Opens an existing database for reading only (`enavi dashboard`, `enavi compare`): no
  /// schema change, no checkpoints; every write throws.
  bool read_only = false;
};

struct StoreConnection;
class JobStore;
class LeaseStore;
class ResultIngest;
class ResultQueries;
class CollectStore;
class WorkerStore;

class Store {
 public:
  /// Opens or creates the database; refuses a database with a newer schema version.
  explicit Store(const std::filesystem::path& path, StoreOptions options = {});
  ~Store();
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;

  JobStore& jobs() { return *jobs_; }
  LeaseStore& leases() { return *leases_; }
  ResultIngest& ingest() { return *ingest_; }
  ResultQueries& queries() { return *queries_; }
  CollectStore& collect() { return *collect_; }
  WorkerStore& workers() { return *workers_; }

  int max_attempts() const;

 private:
  void CheckpointLoop(std::filesystem::path path);

  std::unique_ptr<StoreConnection> connection_;
  std::unique_ptr<JobStore> jobs_;
  std::unique_ptr<LeaseStore> leases_;
  std::unique_ptr<ResultIngest> ingest_;
  std::unique_ptr<ResultQueries> queries_;
  std::unique_ptr<CollectStore> collect_;
  std::unique_ptr<WorkerStore> workers_;
  // WAL checkpoints run on their own connection and thread, off the ingestion path: copying
  // pages into the database file inside a commit halved result ingestion with large series.
  std::mutex checkpoint_mutex_;
  std::condition_variable checkpoint_cv_;
  bool stop_checkpoints_ = false;
  std::thread checkpointer_;
};

}  // namespace enavi::server
