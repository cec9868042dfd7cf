#pragma once
// Client library for the farm's HTTP API (routes in api/http_schema.h).

#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/http_schema.h"
#include "api/rollout_records.h"

namespace enavi::api {

class FarmClient {
 public:
  /// @param url e.g. http://127.0.0.1:8717
  /// @param token sent as "Authorization: Bearer TOKEN" on state-changing requests
  /// @throws std::invalid_argument for a malformed URL.
  explicit FarmClient(std::string url, std::string token = "");
  ~FarmClient();

  struct Submitted {
    std::string job_id;
    std::string name;
    int episodes = 0;
  };
  /// Submits a job spec; `file_name` names it in validation errors.
  /// @throws std::invalid_argument when the server rejects the spec (message from the server).
  Submitted Submit(const std::string& yaml, const std::string& file_name);
  JobProgress Status(const std::string& job_id);
  /// Every job, or those carrying all of `labels`.
  std::vector<JobProgress> Jobs(const std::map<std::string, std::string>& labels = {});
  /// A list of result objects (board, scenario, method, seed, metrics) in episode order.
  nlohmann::json Results(const std::string& job_id);
  nlohmann::json Episodes(const std::string& job_id);
  /// GET /api/trend: a metric's mean per job, board and method over the jobs labelled `label`
  /// (KEY=VALUE), oldest first, with the spread over seeds and its 95 % interval.
  nlohmann::json Trend(const std::string& label, const std::string& metric);
  JobProgress Cancel(const std::string& job_id);
  nlohmann::json Workers();
  nlohmann::json Health();
  /// Stores an E-Navi policy (JSON text) on the server; returns "sha256:HEX" for job specs.
  std::string UploadPolicy(const std::string& policy_json);
  /// A collection job's stored rollouts, one per done episode, in episode order.
  std::vector<StoredRollout> Rollouts(const std::string& job_id);

  const std::string& url() const { return url_; }

 private:
  nlohmann::json Request(const std::string& method, const std::string& path,
                         const std::string& body = "", const std::string& file_name = "");
  std::string RequestRaw(const std::string& method, const std::string& path, const std::string& body,
                         const std::string& file_name, const std::string& content_type);
  std::string url_;
  std::string token_;
};

}  // namespace enavi::api
