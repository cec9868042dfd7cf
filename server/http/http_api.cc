#include "server/http/http_api.h"

#include <arpa/inet.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <map>
#include <regex>
#include <stdexcept>

#include <httplib.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "api/farm_messages.h"
#include "api/http_schema.h"
#include "server/http/http_reply.h"
#include "server/scheduler/collection.h"
#include "server/store/collect_store.h"
#include "server/store/jobs.h"
#include "server/store/queries.h"
#include "server/store/worker_store.h"

namespace enavi::server {
namespace {

// A refusal by one of the server's limits names it, so a client can tell which one to raise.
void LimitError(httplib::Response& res, int status, const std::string& limit,
                const std::string& message) {
  Reply(res, status, {{"error", message + " (enavi serve --" + limit + ")"}, {"limit", limit}});
}

// Constant-time comparison: the token check must not leak how much of a guess was right.
bool SameToken(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (std::size_t i = 0; i < a.size(); ++i) diff |= a[i] ^ (i < b.size() ? b[i] : 0);
  return diff == 0;
}

nlohmann::json WorkerJson(const WorkerView& w) {
  nlohmann::json running = nlohmann::json::array();
  for (const auto& r : w.status.running) {
    running.push_back({{"episode_id", r.episode_id}, {"attempt", r.attempt}});
  }
  return {{"worker_id", w.status.worker_id},   {"host", w.status.host},
          {"pid", w.status.pid},               {"slots", w.status.slots},
          {"free_slots", w.status.free_slots}, {"boards", w.status.boards},
          {"clocks", w.status.clocks},         {"calibration_id", w.status.calibration_id},
          {"draining", w.status.draining},     {"alive", w.alive},
          {"last_seen_s", w.last_seen_s},      {"leased", w.leased},
          {"running", running},                {"unacked_results", w.status.unacked_results},
          {"version", w.status.version}};
}

// "host:port", "[v6]:port" or "host" -> host.
std::string HostName(const std::string& host_header) {
  if (!host_header.empty() && host_header.front() == '[') {
    const auto end = host_header.find(']');
    return end == std::string::npos ? host_header : host_header.substr(1, end - 1);
  }
  const auto colon = host_header.find(':');
  return colon == std::string::npos ? host_header : host_header.substr(0, colon);
}

// "http://host:port" -> "host:port".
std::string OriginHost(const std::string& origin) {
  const auto scheme = origin.find("://");
  return scheme == std::string::npos ? origin : origin.substr(scheme + 3);
}

std::string CookieValue(const std::string& cookies, const std::string& name) {
  std::size_t at = 0;
  while (at < cookies.size()) {
    const auto end = std::min(cookies.find(';', at), cookies.size());
    std::string item = cookies.substr(at, end - at);
    item.erase(0, item.find_first_not_of(' '));
    if (item.rfind(name + "=", 0) == 0) return item.substr(name.size() + 1);
    at = end + 1;
  }
  return "";
}

// A connection in memory: reads the request bytes, collects the response.
class MemoryStream final : public httplib::Stream {
 public:
  explicit MemoryStream(std::string_view request) : request_(request) {}
  bool is_readable() const override { return true; }
  bool is_writable() const override { return true; }
  ssize_t read(char* ptr, size_t size) override {
    size = std::min(size, request_.size() - at_);
    std::copy_n(request_.data() + at_, size, ptr);
    at_ += size;
    return static_cast<ssize_t>(size);
  }
  ssize_t write(const char* ptr, size_t size) override {
    response_.append(ptr, size);
    return static_cast<ssize_t>(size);
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    ip = "127.0.0.1";
    port = 0;
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    ip = "127.0.0.1";
    port = 0;
  }
  socket_t socket() const override { return INVALID_SOCKET; }
  const std::string& response() const { return response_; }

 private:
  std::string_view request_;
  std::size_t at_ = 0;
  std::string response_;
};

// httplib's per-request entry point is protected: this subclass lends it to HandleRaw.
class RoutingServer final : public httplib::Server {
 public:
  std::string Handle(std::string_view request) {
    MemoryStream stream(request);
    bool closed = false;
    process_request(stream, /*close_connection=*/true, closed, nullptr);
    return stream.response();
  }
};

}  // namespace

AccessDecision CheckAccess(const HttpOptions& options, const AccessRequest& r) {
  AccessDecision d;
  const bool loopback = IsLoopbackHost(options.host);
  // Bound to loopback, only loopback names may be in Host: a DNS-rebound name that resolves to
  // 127.0.0.1 must not let another site's scripts read the farm.
  if (loopback && !IsLoopbackHost(HostName(r.host))) {
    d.status = 403;
    d.message = "Host '" + r.host + "' is not a loopback name";
    return d;
  }
  const bool write = r.method != "GET" && r.method != "HEAD";
  // A page from another origin must not change state (CSRF): a cross-site form POST carries
  // its Origin; the CLI sends none.
  if (write && !r.origin.empty() && HostName(OriginHost(r.origin)) != HostName(r.host)) {
    d.status = 403;
    d.message = "cross-origin request refused";
    return d;
  }
  if (options.token.empty() || (!write && loopback)) return d;
  if (!r.token_param.empty() && SameToken(r.token_param, options.token)) {
    d.set_cookie = true;
    return d;
  }
  const std::string prefix = "Bearer ";
  const bool header_ok = r.authorization.rfind(prefix, 0) == 0 &&
                         SameToken(r.authorization.substr(prefix.size()), options.token);
  if (!header_ok && !SameToken(CookieValue(r.cookie, kTokenCookie), options.token)) {
    d.status = 401;
    d.message = write ? "this farm server needs its token: pass --token (Authorization: Bearer)"
                      : "this farm server needs its token: open /?token=TOKEN or send Authorization: Bearer";
  }
  return d;
}

bool RateLimiter::Allow(const std::string& key, std::chrono::steady_clock::time_point now) {
  if (limit_ <= 0) return true;
  std::lock_guard lock(mutex_);
  // Bounded memory under many clients: drop those with nothing left in their window.
  if (events_.size() > 1024) {
    for (auto it = events_.begin(); it != events_.end();) {
      it = it->second.back() <= now - window_ ? events_.erase(it) : std::next(it);
    }
  }
  auto& stamps = events_[key];
  while (!stamps.empty() && stamps.front() <= now - window_) stamps.pop_front();
  if (stamps.size() >= static_cast<std::size_t>(limit_)) return false;
  stamps.push_back(now);
  return true;
}

bool IsLoopbackHost(const std::string& host) {
  if (host == "localhost" || host == "::1") return true;
  in_addr addr{};
  if (inet_pton(AF_INET, host.c_str(), &addr) == 1) {
    return (ntohl(addr.s_addr) >> 24) == 127;
  }
  return false;
}

HttpApi::HttpApi(FarmServer* farm, HttpOptions options)
    : HttpApi(&farm->store(), farm, std::move(options)) {}

HttpApi::HttpApi(Store* store, HttpOptions options) : HttpApi(store, nullptr, std::move(options)) {}

HttpApi::HttpApi(Store* store, FarmServer* farm, HttpOptions options)
    : store_(store), farm_(farm), options_(std::move(options)),
      server_(std::make_unique<RoutingServer>()),
      submissions_(options_.max_jobs_per_minute, std::chrono::minutes(1)) {
  if (!IsLoopbackHost(options_.host) && options_.token.empty()) {
    throw std::invalid_argument("--token: required when --http binds a non-loopback address ('" +
                                options_.host + "')");
  }
  // No SO_REUSEPORT (httplib's default sets it): with it a second server on a port in use
  // started and the kernel split the connections between the two, each answering from its own
  // database. SO_REUSEADDR stays, so a restarted server binds while old connections linger.
  server_->set_socket_options([](socket_t sock) {
    const int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  // httplib refuses a declared Content-Length above this before reading the body; the POST
  // handler applies the per-route limit to what was read.
  server_->set_payload_max_length(std::max(options_.max_body_bytes, options_.max_policy_bytes));
  // Make httplib's own refusals (an empty 413) as explicit as ours.
  using Handled = httplib::Server::HandlerResponse;
  server_->set_error_handler(httplib::Server::HandlerWithResponse(
      [this](const httplib::Request&, httplib::Response& res) {
    if (res.status != 413 || !res.body.empty()) return Handled::Unhandled;
    LimitError(res, 413, "max-body-bytes",
               "request body above the server's limit of " +
                   std::to_string(std::max(options_.max_body_bytes, options_.max_policy_bytes)) +
                   " bytes");
    return Handled::Handled;
  }));
  Routes();
}

HttpApi::~HttpApi() { Stop(); }

std::string HttpApi::HandleRaw(std::string_view request) {
  return static_cast<RoutingServer&>(*server_).Handle(request);
}

std::string HttpApi::url() const {
  return "http://" + options_.host + ":" + std::to_string(port_);
}

int HttpApi::Start() {
  errno = 0;
  if (options_.port == 0) {
    port_ = server_->bind_to_any_port(options_.host.c_str());
  } else {
    port_ = server_->bind_to_port(options_.host.c_str(), options_.port) ? options_.port : -1;
  }
  if (port_ <= 0) {
    const int error = errno;
    throw std::runtime_error("--http: cannot listen on " + options_.host + ":" + std::to_string(options_.port) +
                             (error == EADDRINUSE ? ": address already in use (another enavi serve or dashboard "
                                                    "there? --http HOST:PORT picks another, port 0 any free one)"
                              : error != 0       ? std::string(": ") + std::strerror(error)
                                                 : std::string()));
  }
  thread_ = std::thread([this] { server_->listen_after_bind(); });
  return port_;
}

void HttpApi::Stop() {
  if (server_) server_->stop();
  if (thread_.joinable()) thread_.join();
}

void HttpApi::Routes() {
  httplib::Server& s = *server_;
  Store& store = *store_;
  using Handled = httplib::Server::HandlerResponse;

  // Access: see the header. Checked before any route, so no handler can forget it.
  // Access rules (CheckAccess) before any route, so no handler can forget them.
  s.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    AccessRequest a;
    a.method = req.method;
    a.host = req.get_header_value("Host");
    a.origin = req.get_header_value("Origin");
    a.authorization = req.get_header_value("Authorization");
    a.cookie = req.get_header_value("Cookie");
    if (req.has_param("token")) a.token_param = req.get_param_value("token");
    const AccessDecision d = CheckAccess(options_, a);
    if (d.set_cookie) {
      // Opening /?token=T once keeps the token in a cookie for the dashboard's requests.
      res.set_header("Set-Cookie", std::string(kTokenCookie) + "=" + options_.token +
                                       "; Path=/; HttpOnly; SameSite=Strict");
      if (req.path == "/") {
        res.set_redirect("/");
        return Handled::Handled;
      }
    }
    if (d.status != 0) {
      Error(res, d.status, d.message);
      return Handled::Handled;
    }
    return Handled::Unhandled;
  });

  s.set_exception_handler([](const httplib::Request& req, httplib::Response& res,
                             std::exception_ptr ep) {
    try {
      std::rethrow_exception(ep);
    } catch (const std::invalid_argument& e) {
      Error(res, 400, e.what());
    } catch (const std::exception& e) {
      spdlog::error("HTTP {} {}: {}", req.method, req.path, e.what());
      Error(res, 500, e.what());
    }
  });

  s.Get("/api/health", [this](const httplib::Request&, httplib::Response& res) {
    if (!farm_) return Reply(res, 200, {{"ok", true}, {"protocol", api::kFarmProtocolVersion}, {"read_only", true}});
    const FarmServerStats st = farm_->stats();
    Reply(res, 200,
          {{"ok", true},
           {"protocol", api::kFarmProtocolVersion},
           {"stats",
            {{"results_received", st.results_received}, {"results_stored", st.results_stored},
             {"duplicates", st.duplicates}, {"assignments", st.assignments},
             {"leases_lost", st.leases_lost}, {"oversized", st.oversized}}}});
  });

  s.Post(".*", [this, &store](const httplib::Request& req, httplib::Response& res) {
    if (!farm_) return Error(res, 405, "read-only dashboard: this server accepts no changes");
    // Job specs are small; a policy (the shipped one is 1.8 MB of JSON) has a limit of its own.
    const bool policy = req.path == "/api/policies";
    const std::size_t limit = policy ? options_.max_policy_bytes : options_.max_body_bytes;
    if (req.body.size() > limit) {
      return LimitError(res, 413, policy ? "max-policy-bytes" : "max-body-bytes",
                        "request body of " + std::to_string(req.body.size()) +
                            " bytes, above the server's limit of " + std::to_string(limit));
    }
    if (req.path == "/api/jobs") {
      const std::string file = req.has_header("X-Enavi-File") ? req.get_header_value("X-Enavi-File")
                                                              : std::string("job.yaml");
      // One client must not flood the store with jobs. Clients are told apart by address: a
      // farm has one token, shared by all its clients, and an unchecked header could be varied.
      if (!submissions_.Allow(req.remote_addr, std::chrono::steady_clock::now())) {
        return LimitError(res, 429, "max-jobs-per-minute",
                          "more than " + std::to_string(options_.max_jobs_per_minute) +
                              " jobs in one minute from this client; try again later");
      }
      // Validation failures are bad input: 400 with the FILE:LINE: field: reason message. The
      // parser's own cap only bounds the expansion; this server's limit is checked below.
      api::JobSpecOptions spec_options = options_.job_spec;
      spec_options.max_episodes = std::max(spec_options.max_episodes, options_.max_job_episodes);
      const api::JobSpec job = api::ParseJobSpec(req.body, file, spec_options);
      if (job.MatrixSize() > options_.max_job_episodes) {
        return LimitError(res, 413, "max-job-episodes",
                          file + ": " + std::to_string(job.MatrixSize()) +
                              " episodes, above the server's limit of " +
                              std::to_string(options_.max_job_episodes) + " per job");
      }
      const std::string id = farm_->Submit(job, req.body);
      const auto progress = store.jobs().Progress(id, NowMs());
      return Reply(res, 201, {{"job_id", id}, {"name", job.name}, {"episodes", progress ? progress->total : 0}});
    }
    // A policy for collection jobs, by content hash: {"hash": "sha256:HEX"}.
    if (req.path == "/api/policies") {
      const std::string hash = StorePolicy(&store, req.body, "uploaded policy");
      return Reply(res, 201, {{"hash", api::kPolicyHashPrefix + hash}});
    }
    static const std::regex kCancel(R"(/api/jobs/([A-Za-z0-9_-]+)/cancel)");
    std::smatch m;
    if (std::regex_match(req.path, m, kCancel)) {
      if (!farm_->Cancel(m[1])) return Error(res, 404, "no job '" + std::string(m[1]) + "'");
      return Reply(res, 200, *farm_->store().jobs().Progress(m[1], NowMs()));
    }
    Error(res, 404, "no route POST " + req.path);
  });

  // A collection job's rollouts, exactly one per done episode (api/rollout_records.h stream).
  s.Get(R"(/api/jobs/([A-Za-z0-9_-]+)/rollouts)", [&store](const httplib::Request& req,
                                                           httplib::Response& res) {
    if (!store.jobs().Progress(req.matches[1], NowMs())) {
      return Error(res, 404, "no job '" + std::string(req.matches[1]) + "'");
    }
    if (!store.collect().Collection(req.matches[1])) {
      return Error(res, 400, "job '" + std::string(req.matches[1]) + "' is not a collection job (collect: rollouts)");
    }
    res.status = 200;
    res.set_content(api::EncodeRolloutStream(store.collect().Rollouts(req.matches[1])), "application/octet-stream");
  });

  s.Get("/api/jobs", [this, &store](const httplib::Request& req, httplib::Response& res) {
    std::map<std::string, std::string> labels;
    for (const std::string& filter : QueryValues(req, "label")) {
      auto [k, v] = api::ParseLabelFilter(filter, "label");
      if (labels.count(k) && labels[k] != v) return Reply(res, 200, nlohmann::json::array());
      labels[k] = v;
    }
    std::vector<api::JobProgress> jobs = store.jobs().ListJobs(NowMs(), labels);
    if (farm_) for (api::JobProgress& p : jobs) farm_->ExplainWaiting(&p);
    Reply(res, 200, jobs);
  });

  s.Get(R"(/api/jobs/([A-Za-z0-9_-]+))", [this, &store](const httplib::Request& req,
                                                        httplib::Response& res) {
    auto p = store.jobs().Progress(req.matches[1], NowMs());
    if (!p) return Error(res, 404, "no job '" + std::string(req.matches[1]) + "'");
    if (farm_) farm_->ExplainWaiting(&*p);
    Reply(res, 200, *p);
  });

  s.Get(R"(/api/jobs/([A-Za-z0-9_-]+)/results)", [&store](const httplib::Request& req,
                                                          httplib::Response& res) {
    if (!store.jobs().Progress(req.matches[1], NowMs())) {
      return Error(res, 404, "no job '" + std::string(req.matches[1]) + "'");
    }
    // Paged when asked (the dashboard); the whole list otherwise (scripts, `enavi results`).
    if (req.has_param("offset") || req.has_param("limit")) {
      return Reply(res, 200, store.queries().ResultsPage(req.matches[1], PageOf(req)));
    }
    Reply(res, 200, store.queries().Results(req.matches[1]));
  });

  s.Get(R"(/api/jobs/([A-Za-z0-9_-]+)/episodes)", [&store](const httplib::Request& req,
                                                           httplib::Response& res) {
    if (!store.jobs().Progress(req.matches[1], NowMs())) {
      return Error(res, 404, "no job '" + std::string(req.matches[1]) + "'");
    }
    nlohmann::json list = nlohmann::json::array();
    for (const auto& e : store.jobs().Episodes(req.matches[1])) {
      list.push_back({{"id", e.id}, {"index", e.index}, {"state", e.state},
                      {"attempts", e.attempts}, {"lease_owner", e.lease_owner},
                      {"last_error", e.last_error}, {"board", e.spec.board},
                      {"world", e.spec.world}, {"method", e.spec.method}, {"seed", e.spec.seed},
                      {"spec", e.spec}});
    }
    Reply(res, 200, list);
  });

  s.Get(R"(/api/episodes/([A-Za-z0-9_-]+)/result)", [&store](const httplib::Request& req,
                                                             httplib::Response& res) {
    const auto r = store.queries().FullResult(req.matches[1]);
    if (!r) return Error(res, 404, "no result for episode '" + std::string(req.matches[1]) + "'");
    Reply(res, 200, *r);
  });

  s.Get("/api/workers", [this, &store](const httplib::Request&, httplib::Response& res) {
    nlohmann::json list = nlohmann::json::array();
    if (farm_) {
      for (const auto& w : farm_->Workers()) list.push_back(WorkerJson(w));
    } else {
      // A finished database: the workers it saw, none of them known to be alive.
      for (auto w : store.workers().KnownWorkers()) {
        w["alive"] = false;
        list.push_back(std::move(w));
      }
    }
    Reply(res, 200, list);
  });

  DashboardRoutes();
}

}  // namespace enavi::server
