#pragma once
// The farm worker: announces itself and heartbeats over DDS, takes assignments up to its slots,
// runs each episode in a child process (workers/worker/episode_runner.h), and keeps every result
// (in memory and in an on-disk spool) until the server acknowledges it.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "api/farm_bus.h"
#include "workers/worker/episode_runner.h"
#include "workers/worker/spool.h"

namespace enavi::worker {

struct WorkerOptions {
  api::BusOptions bus;
  std::string worker_id;                ///< empty: <hostname>-<pid>
  int slots = 1;                        ///< episodes run at once
  std::vector<std::string> boards;      ///< boards served (required; registered names)
  std::vector<std::string> clocks;      ///< clocks served (required; registered names)
  std::vector<std::string> features;    ///< what else it runs: "ros" (api::WorkerStatus::features)
  std::string calibration_id;
  /// Episode command without its --spec-file/--result-file arguments; empty: this executable's
  /// `fly` (`/proc/self/exe fly`).
  std::vector<std::string> episode_command;
  EpisodeLimits limits;
  std::filesystem::path spool_dir;      ///< unacknowledged results (required)
  std::filesystem::path work_dir;       ///< per-episode directories (required)
  bool keep_episode_dirs = false;       ///< keep spec/result/logs of finished episodes
  std::chrono::milliseconds heartbeat{1000};
  /// First re-send of an unacknowledged result; doubles up to 60 s. (Durable DDS history already
  /// replays unacknowledged results to a restarted server; this covers a lost ack.)
  std::chrono::milliseconds resend{10000};
  /// On a graceful stop, how long running episodes may finish before they are abandoned.
  std::chrono::seconds drain_timeout{60};
  /// After the last episode, how long to wait for outstanding acknowledgements.
  std::chrono::seconds ack_grace{5};
  /// A collection episode whose policy has not arrived after this long fails.
  std::chrono::seconds policy_wait{60};
};

struct WorkerStats {
  int episodes_run = 0;
  int results_acked = 0;
  int rejected = 0;
  int aborted = 0;
};

class Worker {
 public:
  /// @throws std::invalid_argument for bad options (slots, missing directories, command).
  explicit Worker(WorkerOptions options);
  ~Worker();
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;

  /// Serves until RequestStop(); returns after draining (or abandoning) running episodes.
  void Run();
  /// Thread- and signal-thread-safe. First call: drain (finish running episodes up to
  /// drain_timeout, take no new ones); `abandon` or a second call: stop running episodes now
  /// (they are handed back to the server, not counted as attempts).
  void RequestStop(bool abandon = false);

  const std::string& id() const { return options_.worker_id; }
  WorkerStats stats() const;

 private:
  struct Slot {
    api::Assignment assignment;
    std::atomic<bool> abort{false};
    std::atomic<bool> shutdown{false};  // aborted because the worker stops: hand it back
    std::thread thread;
  };
  struct Outgoing {
    api::ResultMessage message;
    std::chrono::steady_clock::time_point next_send;
    std::chrono::milliseconds backoff;
  };
  using Key = std::pair<std::string, int>;  // episode id, attempt

  void HandleAssignment(const api::Assignment& a);
  void HandlePolicy(const api::PolicyBlob& policy);
  void StartWaiting();
  void StartSlot(const api::Assignment& a);
  std::filesystem::path PolicyPath(const std::string& hash) const;
  void HandleAck(const api::ResultAck& ack);
  void HandleEvent(const api::JobEvent& e);
  void CollectFinished();
  void Send(api::ResultMessage message, bool spool);
  void ResendDue();
  void PublishStatus();
  void SlotMain(Slot* slot);

  WorkerOptions options_;
  std::unique_ptr<api::WorkerBus> bus_;
  ResultSpool spool_;
  std::map<Key, std::unique_ptr<Slot>> running_;
  // Collection assignments waiting for their policy (they hold a slot and their lease).
  std::map<Key, std::pair<api::Assignment, std::chrono::steady_clock::time_point>> waiting_;
  std::map<Key, Outgoing> unacked_;

  std::mutex finished_mutex_;
  std::vector<std::pair<Key, EpisodeOutcome>> finished_;

  std::atomic<int> stop_requests_{0};
  std::atomic<bool> abandon_{false};
  std::uint64_t seq_ = 0;
  std::string host_;
  mutable std::mutex stats_mutex_;
  WorkerStats stats_;
};

/// Default spool and work directories for a farm identity: under $XDG_STATE_HOME/enavi (or
/// ~/.local/state/enavi, or /tmp/enavi-<uid>), one folder per domain and partition.
std::filesystem::path DefaultStateDir(const api::BusOptions& bus);

}  // namespace enavi::worker
