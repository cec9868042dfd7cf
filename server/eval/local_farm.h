#pragma once
// A private farm in this process: SQLite store, scheduler, HTTP API on loopback, and N local
// `enavi worker` processes (the same code as on a cluster) on a private loopback DDS domain and
// partition, so concurrent evals, trainings and tests never cross-talk. `enavi eval` and
// `enavi train` without --server fly their episodes here.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "api/job_spec.h"

namespace enavi::server {

class Store;
class FarmServer;
class HttpApi;

struct LocalFarmOptions {
  std::filesystem::path db;      ///< empty: a temporary database, removed afterwards
  int workers = 2;               ///< [1, 64]
  int slots = 1;                 ///< per worker, [1, 64]
  std::string episode_command;   ///< empty: `<enavi> fly`
  std::chrono::seconds episode_timeout{3600};
  std::filesystem::path enavi;   ///< the executable the workers run; empty: this one
  std::optional<std::uint32_t> domain;  ///< empty: derived from the process id
  std::string name = "eval";     ///< temp dir, partition and worker id prefix
  bool http = false;             ///< also serve the HTTP API on 127.0.0.1 (any port)
  api::JobSpecOptions job_spec;  ///< the HTTP API's job validation (method catalog, roots)
};

class LocalFarm {
 public:
  /// Starts the server and the workers. @throws std::invalid_argument for bad counts.
  explicit LocalFarm(const LocalFarmOptions& options);
  /// Stops the workers gracefully (they drain and leave), then the server.
  ~LocalFarm();
  LocalFarm(const LocalFarm&) = delete;
  LocalFarm& operator=(const LocalFarm&) = delete;

  Store& store();
  FarmServer& farm();
  /// The HTTP API's URL (options.http).
  std::string url() const;
  /// @throws std::runtime_error (with a worker's log tail) when every worker has exited; the
  ///   temporary directory is kept then.
  void CheckWorkers();
  /// Stops workers and server now (also done by the destructor).
  void Stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace enavi::server
