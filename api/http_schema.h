#pragma once
// The farm's HTTP API: routes and the JSON of its replies, shared by the server (server/http)
// and the client library (api/client.h).
//
//   POST /api/jobs                 body: job spec YAML; header X-Enavi-File: name for errors
//                                  -> 201 {"job_id", "name", "episodes"}; 400 {"error"}
//   GET  /api/jobs[?label=k=v]     -> [JobProgress]  (every label filter must match)
//   GET  /api/jobs/{id}            -> JobProgress                    404 {"error"}
//   GET  /api/jobs/{id}/results    -> [result object]  (board, scenario, method, seed, metrics)
//   GET  /api/jobs/{id}/episodes   -> [{"id", "state", "attempts", "last_error", "spec", ...}]
//   POST /api/jobs/{id}/cancel     -> JobProgress
//   GET  /api/episodes/{id}/result -> full result JSON (time series and events included)
//   GET  /api/workers              -> [{"worker_id", "host", "slots", "free_slots", ...}]
//   GET  /api/health               -> {"ok": true, "protocol": 1, "stats": {results_received,
//                                      results_stored, duplicates, assignments, leases_lost}}
//   GET  /api/jobs/{id}/summary | failures | results?offset=&limit=, /api/compare, /api/trend,
//        /api/episodes/{id}/topdown.png, /api/info, /: the dashboard (docs/dashboard.md)
// With a token, state-changing requests (POST) carry "Authorization: Bearer TOKEN"; off
// loopback every request does (or the dashboard's cookie).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace enavi::api {

inline constexpr int kDefaultHttpPort = 8717;

/// http://127.0.0.1:<kDefaultHttpPort>
std::string DefaultServerUrl();

/// Progress of one job.
struct JobProgress {
  std::string id;
  std::string name;
  std::string state;  ///< running, done, cancelled
  int total = 0, pending = 0, leased = 0, done = 0, failed = 0, cancelled = 0;
  std::int64_t created_ms = 0;   ///< server wall clock, Unix ms
  std::int64_t started_ms = 0;   ///< first lease; 0: not started
  std::int64_t finished_ms = 0;  ///< 0 while running
  std::int64_t now_ms = 0;       ///< when this was produced
  std::vector<std::string> errors;  ///< recent reasons episodes failed ("EPISODE: reason")
  std::map<std::string, std::string> labels;      ///< the job spec's labels
  std::map<std::string, std::string> provenance;  ///< the server build and inputs at submission
  /// Pending episodes by the worker feature they need ("ros": 4).
  std::map<std::string, int> pending_needs;
  /// Why pending episodes wait, when no connected worker can run them (empty otherwise).
  std::string waiting;

  int finished() const { return done + failed + cancelled; }
  bool terminal() const { return state != "running"; }
  /// Finished episodes per second since the first lease (0 before any finished).
  double rate_per_s() const;
  /// Seconds until all episodes finish at the current rate; < 0 when unknown.
  double eta_s() const;
};

void to_json(nlohmann::json& j, const JobProgress& p);
void from_json(const nlohmann::json& j, JobProgress& p);

}  // namespace enavi::api
