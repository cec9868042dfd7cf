#pragma once
// The farm server's core: tracks workers (heartbeats and DDS liveliness), leases pending episodes
// to workers with free slots, renews leases the workers report as running, re-queues lost ones,
// ingests results idempotently and acknowledges them. It talks to workers only through the bus.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "api/farm_bus.h"
#include "api/job_spec.h"
#include "server/store/jobs.h"
#include "server/store/leases.h"
#include "server/store/store.h"

namespace enavi::server {

struct FarmServerOptions {
  api::BusOptions bus;
  /// Lease length. A worker's heartbeat (every second) extends the leases it lists as running,
  /// so this only has to cover a few lost heartbeats, not an episode.
  std::chrono::milliseconds lease{15000};
  /// A worker not heard from for this long is gone: its leases are re-queued.
  std::chrono::milliseconds worker_timeout{6000};
  /// Period of lease expiry and assignment when nothing arrives.
  std::chrono::milliseconds tick{200};
  /// Results ingested per SQLite transaction at most.
  std::size_t ingest_batch = 512;
  /// A result (time series, events, error text: ResultPayloadBytes) or rollout above these is
  /// refused: logged with worker and episode, not stored, and counted as a failed attempt.
  std::size_t max_result_bytes = std::size_t{16} << 20;
  std::size_t max_rollout_bytes = api::kMaxRolloutBytes;
};

/// The bytes a result carries beyond its fixed summary: its series samples, events and error.
std::size_t ResultPayloadBytes(const api::ResultMessage& m);

/// What the server knows about one worker.
struct WorkerView {
  api::WorkerStatus status;
  bool alive = true;
  double last_seen_s = 0;  ///< seconds since its last heartbeat
  int leased = 0;          ///< episodes leased to it now
};

struct FarmServerStats {
  std::uint64_t results_received = 0;
  std::uint64_t results_stored = 0;
  std::uint64_t duplicates = 0;
  std::uint64_t assignments = 0;
  std::uint64_t leases_lost = 0;
  std::uint64_t oversized = 0;  ///< results or rollouts refused by a size limit
};

class FarmServer {
 public:
  FarmServer(Store* store, FarmServerOptions options);
  ~FarmServer();
  FarmServer(const FarmServer&) = delete;
  FarmServer& operator=(const FarmServer&) = delete;

  /// Expires leases that ran out while the server was down, then runs the loop in a thread.
  void Start();
  void Stop();

  /// Stores a job and starts scheduling it; returns the job id.
  /// A collection job's policy must be in the store (CollectStore::PutPolicy) first.
  std::string Submit(const std::string& name, const std::string& spec_yaml,
                     const std::vector<api::EpisodeSpec>& episodes, const JobMeta& meta = {},
                     const std::optional<CollectionInfo>& collect = std::nullopt);
  /// Expands a validated job spec and stores it with its labels and provenance (this server's
  /// build, the policy's sha256) and, for a collection job, its policy; returns the job id.
  std::string Submit(const api::JobSpec& job, const std::string& spec_yaml);
  /// Cancels a job and tells workers to stop its episodes. False: no such job.
  bool Cancel(const std::string& job_id);

  std::vector<WorkerView> Workers() const;
  FarmServerStats stats() const;
  /// Sets `p.waiting` when some of its pending episodes need a feature (ROS) that no connected
  /// worker offers: they wait for one, and the user should know why.
  void ExplainWaiting(api::JobProgress* p) const;
  Store& store() { return *store_; }

 private:
  void Loop();
  void Step();
  void HandleStatuses(const std::vector<api::WorkerStatus>& statuses, std::int64_t now_ms);
  void HandleGone(const std::string& worker_id, const std::string& reason, std::int64_t now_ms);
  void HandleResults(const std::vector<api::ResultMessage>& results, std::int64_t now_ms);
  void HandleReleased(const std::vector<ReleasedLease>& released, std::int64_t now_ms);
  void Assign(std::int64_t now_ms);
  struct PendingEvent {
    std::string job_id, kind, episode_id, message;
  };
  void PublishEvents(const std::vector<PendingEvent>& events, std::int64_t now_ms);
  void RetireAssignment(const std::string& worker_id, const std::string& episode_id, int attempt);
  std::string CollectionHash(const std::string& job_id);
  void PublishPolicy(const std::string& hash);
  void RetirePolicyOf(const std::string& job_id);

  struct Worker {
    api::WorkerStatus status;
    std::chrono::steady_clock::time_point last_seen;
    std::chrono::steady_clock::time_point last_renewal;  // leases written to the store
    std::vector<api::EpisodeRef> renewed;                // what that renewal listed
    bool alive = true;
  };

  Store* store_;
  FarmServerOptions options_;
  std::unique_ptr<api::ServerBus> bus_;
  mutable std::mutex mutex_;  // workers_ and stats_ (read by HTTP threads)
  std::map<std::string, Worker> workers_;
  FarmServerStats stats_;
  std::set<std::string> finished_announced_;
  std::map<std::string, std::string> collect_hash_;  // job -> policy hash ("" : not collecting)
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::chrono::steady_clock::time_point last_periodic_;
};

/// Server wall clock, Unix ms (persisted lease deadlines and timestamps).
std::int64_t NowMs();

}  // namespace enavi::server
