#pragma once
// The one SQLite connection the store's rooms share, with the lock that serialises them (the
// scheduler and the HTTP threads use it). Rooms take `mutex` for each call and open their own
// transactions on `db`.

#include <filesystem>
#include <mutex>

#include "server/store/sqlite.h"
#include "server/store/store.h"

namespace enavi::server {

struct StoreConnection {
  StoreConnection(const std::filesystem::path& path, const StoreOptions& store_options)
      : options(store_options), db(path, store_options.busy_timeout_ms, store_options.read_only) {}

  const StoreOptions options;
  std::mutex mutex;
  Database db;
};

}  // namespace enavi::server
