#pragma once
// The farm's message bus: the server's and the worker's view of the DDS topics in api/farm.idl.
// No DDS type appears here; topics, QoS and the IDL conversion live in farm_bus.cc and are
// documented in api/README.md.

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "api/farm_messages.h"

namespace enavi::api {

/// Where the bus lives. Two processes talk when domain id, partition and network agree.
struct BusOptions {
  std::uint32_t domain_id = 0;     ///< DDS domain, 0..232
  std::string partition = "enavi"; ///< DDS partition: farms sharing a domain stay apart
  /// Cyclone XML configuration (see CycloneConfigXml); empty: Cyclone's own (CYCLONEDDS_URI).
  std::string config_xml;
  /// Liveliness lease of worker status writers: a worker that stops (crash, SIGKILL, network)
  /// is seen as gone this long after its last sign of life.
  std::chrono::milliseconds liveliness_lease{4000};
};

/// Server side: reads worker status and results; writes assignments, acks and job events.
/// Publish*/Retire/Wake are thread-safe; Wait is called from one thread.
class ServerBus {
 public:
  explicit ServerBus(const BusOptions& options);
  ~ServerBus();
  ServerBus(const ServerBus&) = delete;
  ServerBus& operator=(const ServerBus&) = delete;

  struct Inbox {
    std::vector<WorkerStatus> statuses;
    std::vector<std::string> workers_gone;  ///< liveliness lost (crash, SIGKILL, network)
    std::vector<std::string> workers_left;  ///< status disposed: a graceful stop
    std::vector<ResultMessage> results;
    std::vector<std::string> bad_samples;   ///< samples that did not convert (reason each)
    bool empty() const {
      return statuses.empty() && workers_gone.empty() && workers_left.empty() && results.empty() &&
             bad_samples.empty();
    }
  };
  /// Blocks until data arrives, Wake() is called or `timeout` passes; then takes every status
  /// and up to `max_results` results.
  Inbox Wait(std::chrono::milliseconds timeout, std::size_t max_results = 512);
  void Wake();

  void Publish(const Assignment& assignment);
  /// Drops an assignment instance (plain or collection) from the durable history (its attempt is
  /// over). @throws when neither topic holds it.
  void Retire(const Assignment& assignment);
  void Publish(const ResultAck& ack);
  void Publish(const JobEvent& event);
  /// Publishes a collection job's policy (durable: workers that join later get it too).
  void Publish(const PolicyBlob& policy);
  /// Drops a policy from the durable history (no running job uses it).
  void Retire(const PolicyBlob& policy);

  /// Worker status writers currently matched (diagnostics, tests).
  std::size_t MatchedWorkers() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Worker side: writes status and results; reads its assignments, acks and job events.
class WorkerBus {
 public:
  WorkerBus(const BusOptions& options, std::string worker_id);
  ~WorkerBus();
  WorkerBus(const WorkerBus&) = delete;
  WorkerBus& operator=(const WorkerBus&) = delete;

  struct Inbox {
    std::vector<Assignment> assignments;  ///< addressed to this worker
    std::vector<ResultAck> acks;          ///< addressed to this worker
    std::vector<JobEvent> events;
    std::vector<PolicyBlob> policies;     ///< policies of collection jobs (verify the hash)
    std::vector<std::string> bad_samples;
  };
  Inbox Wait(std::chrono::milliseconds timeout);
  void Wake();

  void Publish(const WorkerStatus& status);
  /// Graceful leave: the server sees the worker gone at once instead of after the lease.
  void DisposeStatus();
  /// A result with a rollout goes out on the rollout topic, in the same sample.
  /// @throws std::invalid_argument for a rollout above kMaxRolloutBytes.
  void Publish(const ResultMessage& result);
  /// Drops an acknowledged result from the durable history.
  void Retire(const ResultMessage& result);

  /// Assignment writers currently matched: > 0 once a server is discovered.
  std::size_t MatchedServers() const;
  const std::string& worker_id() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace enavi::api
