#pragma once
// The store's scheduling: pending episodes are leased to workers (oldest job first), leases are
// renewed by heartbeats, and a lease that ends without a result (expired, its worker gone)
// sends its episode back to pending, or to failed once it is out of attempts.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "api/episode.h"
#include "api/farm_messages.h"

namespace enavi::server {

struct StoreConnection;

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

/// Filters a worker announces: empty lists accept anything.
struct WorkerCapabilities {
  std::vector<std::string> boards;
  std::vector<std::string> clocks;
  std::vector<std::string> features;  ///< an episode that needs one goes only to a worker listing it
};

class LeaseStore {
 public:
  explicit LeaseStore(StoreConnection& connection) : c_(connection) {}

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

 private:
  std::vector<ReleasedLease> ReleaseWhere(const std::string& where, const std::string& arg,
                                          std::int64_t value, const std::string& reason,
                                          std::int64_t now_ms);

  StoreConnection& c_;
};

}  // namespace enavi::server
