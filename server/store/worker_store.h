#pragma once
// The workers a farm database has seen: host, version and calibration, the provenance of the
// results they sent (the dashboard's worker list of a finished database).

#include <cstdint>

#include <nlohmann/json.hpp>

#include "api/farm_messages.h"

namespace enavi::server {

struct StoreConnection;

class WorkerStore {
 public:
  explicit WorkerStore(StoreConnection& connection) : c_(connection) {}

  /// Remembers a worker's host, version and calibration (provenance of its results).
  void RecordWorker(const api::WorkerStatus& status, std::int64_t now_ms);
  /// Every worker this database has seen: {"worker_id", "host", "version", ...}.
  nlohmann::json KnownWorkers();

 private:
  StoreConnection& c_;
};

}  // namespace enavi::server
