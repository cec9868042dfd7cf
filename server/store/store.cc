#include "server/store/store.h"

#include <chrono>
#include <stdexcept>

#include "server/store/collect_store.h"
#include "server/store/connection.h"
#include "server/store/ingest.h"
#include "server/store/jobs.h"
#include "server/store/leases.h"
#include "server/store/queries.h"
#include "server/store/schema.h"
#include "server/store/worker_store.h"

namespace enavi::server {

Store::Store(const std::filesystem::path& path, StoreOptions options) {
  if (options.max_attempts < 1) throw std::invalid_argument("max_attempts: must be >= 1");
  if (options.read_only && !std::filesystem::is_regular_file(path)) {
    throw StoreError("database '" + path.string() + "': no such file");
  }
  connection_ = std::make_unique<StoreConnection>(path, options);
  CheckSchema(connection_->db, path.string(), options.read_only);
  if (!options.read_only) {
    CreateOrMigrateSchema(connection_->db);
    connection_->db.Exec("PRAGMA wal_autocheckpoint = 0");
  }
  jobs_ = std::make_unique<JobStore>(*connection_);
  leases_ = std::make_unique<LeaseStore>(*connection_);
  ingest_ = std::make_unique<ResultIngest>(*connection_);
  queries_ = std::make_unique<ResultQueries>(*connection_);
  collect_ = std::make_unique<CollectStore>(*connection_);
  workers_ = std::make_unique<WorkerStore>(*connection_);
  if (!options.read_only) checkpointer_ = std::thread([this, path] { CheckpointLoop(path); });
}

Store::~Store() {
  if (connection_->options.read_only) return;
  {
    std::lock_guard lock(checkpoint_mutex_);
    stop_checkpoints_ = true;
  }
  checkpoint_cv_.notify_all();
  if (checkpointer_.joinable()) checkpointer_.join();
  // Fold the WAL into the database file, so the file alone is the whole store.
  try {
    connection_->db.Exec("PRAGMA wal_checkpoint(TRUNCATE)");
  } catch (const StoreError&) {
    // Another connection is reading: the WAL stays and is replayed on the next open.
  }
}

int Store::max_attempts() const { return connection_->options.max_attempts; }

void Store::CheckpointLoop(std::filesystem::path path) {
  // PASSIVE: copies what no reader still needs and never blocks the writer. Once everything is
  // copied, the next commit starts the WAL from its beginning, so the WAL stays bounded.
  Database db(path, connection_->options.busy_timeout_ms);
  std::unique_lock lock(checkpoint_mutex_);
  while (!stop_checkpoints_) {
    checkpoint_cv_.wait_for(lock, std::chrono::milliseconds(500));
    if (stop_checkpoints_) break;
    lock.unlock();
    try {
      db.Exec("PRAGMA wal_checkpoint(PASSIVE)");
    } catch (const StoreError&) {
      // Busy: the next round catches up.
    }
    lock.lock();
  }
}

}  // namespace enavi::server
