#pragma once
// The store's way in for results: a batch from the workers is checked (the episode's own, finite,
// a collection episode's rollout of the job's policy) and stored in one transaction with the
// result's row, its series, its rollout and its cell's running sums (docs/dashboard.md).

#include <cstdint>
#include <string>
#include <vector>

#include "api/farm_messages.h"

namespace enavi::server {

struct StoreConnection;

/// What ingesting one result did.
struct IngestOutcome {
  api::AckStatus ack = api::AckStatus::kStored;
  std::string detail;
  std::string job_id;
  std::string event;  ///< job event kind to publish: episode_done, episode_failed, requeued, ""
};

class ResultIngest {
 public:
  explicit ResultIngest(StoreConnection& connection) : c_(connection) {}

  /// Ingests a batch of results in one transaction; one outcome per message, in order.
  std::vector<IngestOutcome> Ingest(const std::vector<api::ResultMessage>& results,
                                    std::int64_t now_ms);

 private:
  StoreConnection& c_;
};

}  // namespace enavi::server
