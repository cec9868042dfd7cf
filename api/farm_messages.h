#pragma once
// The farm's messages as plain C++ records, mirroring api/farm.idl one to one. Server and
// worker code use these; only api/farm_bus.cc converts them to and from the DDS samples.

#include <cstdint>
#include <string>
#include <vector>

#include "api/episode.h"

namespace enavi::api {

/// Bumped with every change to api/farm.idl; also part of the topic names (enavi_v2_*).
inline constexpr int kFarmProtocolVersion = 2;

struct EpisodeRef {
  std::string episode_id;
  int attempt = 0;
  bool operator==(const EpisodeRef&) const = default;
};

/// A worker's announcement and heartbeat.
struct WorkerStatus {
  std::string worker_id;
  int protocol = kFarmProtocolVersion;
  std::string host;
  int pid = 0;
  int slots = 0;
  int free_slots = 0;
  std::vector<std::string> boards;
  std::vector<std::string> clocks;
  std::string calibration_id;
  bool draining = false;
  std::uint64_t seq = 0;
  std::vector<EpisodeRef> running;
  int unacked_results = 0;
  std::string version;
  /// What else it can run beyond boards and clocks: "ros" where the ROS bridge and Debian's ROS
  /// are installed (episodes of ROS methods need it).
  std::vector<std::string> features;
};

/// The server leases one attempt of one episode to one worker.
struct Assignment {
  std::string worker_id;
  std::string episode_id;
  int attempt = 0;
  std::string job_id;
  std::int64_t lease_deadline_ms = 0;  ///< server wall clock (Unix ms)
  std::int64_t lease_ms = 0;           ///< lease length, renewed by heartbeats
  EpisodeSpec spec;
  /// Collection jobs: fly with the policy of this content hash (PolicyBlob) and send the rollout.
  std::string policy_hash;
};

/// A policy file distributed by content hash (SHA-256 hex of `json`).
struct PolicyBlob {
  std::string hash;
  std::string json;
};

/// A rollout travels in one sample, so one episode's experience stays bounded on the bus. Sized
/// for the learned method's depth images: 64x48 steps take ~3.7 kB compressed, so 16 MiB hold
/// ~4,500 decisions (150 s at 30 Hz); E-Navi's take 170 bytes.
inline constexpr std::size_t kMaxRolloutBytes = std::size_t{16} << 20;

enum class ResultStatus { kOk, kError, kRejected };
const char* ToString(ResultStatus s);

/// A worker's outcome for one attempt.
struct ResultMessage {
  std::string episode_id;
  int attempt = 0;
  std::string worker_id;
  std::string job_id;
  ResultStatus status = ResultStatus::kOk;
  std::string error;        ///< kError / kRejected: the reason
  double wall_time_s = 0;   ///< host wall time of the episode process
  EpisodeResult result;     ///< kOk: the full record, series and events included
  /// Collection jobs: the policy the episode flew and its rollout (navstack::rl::EncodeRollout,
  /// binary); sent on the rollout topic together with the result.
  std::string policy_hash;
  std::string rollout;
};

enum class AckStatus { kStored, kDuplicate, kDiscarded, kUnknown, kRecorded };
const char* ToString(AckStatus s);

/// The server has durably handled a result; the worker may forget it.
struct ResultAck {
  std::string worker_id;
  std::string episode_id;
  int attempt = 0;
  AckStatus status = AckStatus::kStored;
  std::string detail;
};

/// Job progress and control (cancellation) for observers and workers.
struct JobEvent {
  std::string job_id;
  std::string kind;  ///< submitted, episode_done, episode_failed, requeued, episode_closed,
                     ///< finished, cancelled
  std::string episode_id;
  int done = 0;
  int failed = 0;
  int total = 0;
  std::string message;
  std::int64_t time_ms = 0;
};

/// The JSON a worker spools to disk for an unacknowledged result (and reads back on restart).
nlohmann::json ToJson(const ResultMessage& m);
ResultMessage ResultMessageFromJson(const nlohmann::json& j);

}  // namespace enavi::api
