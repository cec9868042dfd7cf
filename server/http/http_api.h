#pragma once
// The farm's HTTP API (routes in api/http_schema.h) and the dashboard's pages (server/dashboard),
// served with cpp-httplib. Binds loopback by default; bound anywhere else it refuses to start
// without a token, and then every request must carry it (header or cookie). With a token, every
// state-changing request needs it wherever the server is bound. Without a farm (a read-only
// store: `enavi dashboard --db FILE`) it serves the read routes only.

#include <chrono>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>

#include "api/job_spec.h"
#include "server/scheduler/farm_server.h"

namespace httplib {
class Server;
}

namespace enavi::server {

struct HttpOptions {
  std::string host = "127.0.0.1";
  int port = 0;  ///< 0: any free port (see HttpApi::port())
  /// Required on state-changing requests when non-empty ("Authorization: Bearer TOKEN").
  std::string token;
  api::JobSpecOptions job_spec;  ///< allowed roots and limits for submitted jobs
  // Limits that protect the server (docs/farm.md, "Limits"); each refusal is a JSON
  // {"error": ..., "limit": NAME} with HTTP 413 (too large) or 429 (too often).
  std::size_t max_body_bytes = 1 << 20;     ///< every request body but a policy (job specs)
  std::size_t max_policy_bytes = 32 << 20;  ///< POST /api/policies (a policy file is ~2 MB)
  std::size_t max_job_episodes = api::kMaxJobEpisodes;  ///< episodes one job may expand to
  int max_jobs_per_minute = 60;  ///< job submissions per client (peer address) and minute; 0: none
};

/// Sliding-window rate limit: at most `limit` events per `window` for each key (a client).
/// Thread-safe; keeps memory bounded by forgetting keys whose window is empty.
class RateLimiter {
 public:
  RateLimiter(int limit, std::chrono::steady_clock::duration window) : limit_(limit), window_(window) {}
  /// Counts an event for `key` at `now` and returns true, or returns false (nothing counted)
  /// when `key` already has `limit` events in the window ending at `now`. limit 0: always true.
  bool Allow(const std::string& key, std::chrono::steady_clock::time_point now);

 private:
  int limit_;
  std::chrono::steady_clock::duration window_;
  std::mutex mutex_;
  std::map<std::string, std::deque<std::chrono::steady_clock::time_point>> events_;
};

/// Cookie that carries the token for the dashboard's pages (set by opening /?token=TOKEN).
inline constexpr const char* kTokenCookie = "enavi_token";

/// The headers access depends on.
struct AccessRequest {
  std::string method;  ///< GET, POST, ...
  std::string host, origin, authorization, cookie;
  std::string token_param;  ///< ?token=
};

struct AccessDecision {
  int status = 0;  ///< 0: allowed; else the HTTP status to refuse with
  std::string message;
  bool set_cookie = false;  ///< the ?token= was right: keep it in the token cookie
};

/// The access rules: on a loopback address the Host must be a loopback name (DNS rebinding);
/// a state-changing request with an Origin must come from the same host (CSRF); with a token,
/// writes always need it and, off loopback, every request (Bearer header, cookie or ?token=).
AccessDecision CheckAccess(const HttpOptions& options, const AccessRequest& request);

/// True for 127.0.0.0/8, ::1 and "localhost".
bool IsLoopbackHost(const std::string& host);

class HttpApi {
 public:
  /// @throws std::invalid_argument when `options.host` is not loopback and there is no token.
  HttpApi(FarmServer* farm, HttpOptions options);
  /// Read-only: the dashboard and GET routes over `store`; every POST answers 405.
  HttpApi(Store* store, HttpOptions options);
  ~HttpApi();
  HttpApi(const HttpApi&) = delete;
  HttpApi& operator=(const HttpApi&) = delete;

  /// Binds and starts serving in a thread; returns the bound port.
  /// @throws std::runtime_error when the address cannot be bound.
  int Start();
  void Stop();
  int port() const { return port_; }
  std::string url() const;
  /// One raw HTTP/1.1 request (the bytes a connection reads) through the access checks, routing
  /// and handlers a connection gets; returns the raw response. No socket, no thread: the fuzz
  /// harness of the handlers (tests/fuzz/http_fuzz.cc) calls this.
  std::string HandleRaw(std::string_view request);

 private:
  HttpApi(Store* store, FarmServer* farm, HttpOptions options);
  void Routes();
  void DashboardRoutes();
  Store* store_;
  FarmServer* farm_;  // null: read-only
  HttpOptions options_;
  std::unique_ptr<httplib::Server> server_;
  RateLimiter submissions_;
  std::thread thread_;
  int port_ = 0;
};

}  // namespace enavi::server
