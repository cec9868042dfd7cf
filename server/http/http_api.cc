#include "server/http/http_api.h"

#include <arpa/inet.h>

#include <algorithm>
#include <stdexcept>

#include <httplib.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "api/farm_messages.h"
#include "api/http_schema.h"
#include "server/scheduler/collection.h"

namespace enavi::server {
namespace {

void Reply(httplib::Response& res, int status, const nlohmann::json& body) {
  res.status = status;
  res.set_content(body.dump(), "application/json");
}

void Error(httplib::Response& res, int status, const std::string& message) {
  Reply(res, status, {{"error", message}});
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

}  // namespace

bool IsLoopbackHost(const std::string& host) {
  if (host == "localhost" || host == "::1") return true;
  in_addr addr{};
  if (inet_pton(AF_INET, host.c_str(), &addr) == 1) {
    return (ntohl(addr.s_addr) >> 24) == 127;
  }
  return false;
}

HttpApi::HttpApi(FarmServer* farm, HttpOptions options)
    : farm_(farm), options_(std::move(options)), server_(std::make_unique<httplib::Server>()) {
  if (!IsLoopbackHost(options_.host) && options_.token.empty()) {
    throw std::invalid_argument("--token: required when --http binds a non-loopback address ('" +
                                options_.host + "')");
  }
  server_->set_payload_max_length(std::max(options_.max_body_bytes, options_.max_policy_bytes));
  Routes();
}

HttpApi::~HttpApi() { Stop(); }

std::string HttpApi::url() const {
  return "http://" + options_.host + ":" + std::to_string(port_);
}

int HttpApi::Start() {
  if (options_.port == 0) {
    port_ = server_->bind_to_any_port(options_.host.c_str());
  } else {
    port_ = server_->bind_to_port(options_.host.c_str(), options_.port) ? options_.port : -1;
  }
  if (port_ <= 0) {
    throw std::runtime_error("--http: cannot listen on " + options_.host + ":" +
                             std::to_string(options_.port));
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
  Store& store = farm_->store();

  // Every POST changes state: check the token first.
  s.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    if (req.method != "POST" || options_.token.empty()) return httplib::Server::HandlerResponse::Unhandled;
    const std::string auth = req.get_header_value("Authorization");
    const std::string prefix = "Bearer ";
    if (auth.rfind(prefix, 0) != 0 || !SameToken(auth.substr(prefix.size()), options_.token)) {
      Error(res, 401, "this farm server needs its token: pass --token (Authorization: Bearer)");
      return httplib::Server::HandlerResponse::Handled;
    }
    return httplib::Server::HandlerResponse::Unhandled;
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
    const FarmServerStats st = farm_->stats();
    Reply(res, 200,
          {{"ok", true},
           {"protocol", api::kFarmProtocolVersion},
           {"stats",
            {{"results_received", st.results_received}, {"results_stored", st.results_stored},
             {"duplicates", st.duplicates}, {"assignments", st.assignments},
             {"leases_lost", st.leases_lost}}}});
  });

  s.Post("/api/jobs", [this](const httplib::Request& req, httplib::Response& res) {
    const std::string file = req.has_header("X-Enavi-File") ? req.get_header_value("X-Enavi-File")
                                                            : std::string("job.yaml");
    // Validation failures are bad input: 400 with the FILE:LINE: field: reason message.
    if (req.body.size() > options_.max_body_bytes) {
      return Error(res, 413, "job spec of " + std::to_string(req.body.size()) + " bytes, above " +
                                 std::to_string(options_.max_body_bytes));
    }
    const api::JobSpec job = api::ParseJobSpec(req.body, file, options_.job_spec);
    auto episodes = api::ExpandJob(job);
    const auto collect = PrepareCollection(&farm_->store(), job, &episodes);
    const std::string id = farm_->Submit(job.name, req.body, episodes, collect);
    Reply(res, 201, {{"job_id", id}, {"name", job.name}, {"episodes", episodes.size()}});
  });

  // A policy for collection jobs, by content hash: {"hash": "sha256:HEX"}.
  s.Post("/api/policies", [&store](const httplib::Request& req, httplib::Response& res) {
    const std::string hash = StorePolicy(&store, req.body, "uploaded policy");
    Reply(res, 201, {{"hash", api::kPolicyHashPrefix + hash}});
  });

  // A collection job's rollouts, exactly one per done episode (api/rollout_records.h stream).
  s.Get(R"(/api/jobs/([A-Za-z0-9_-]+)/rollouts)", [&store](const httplib::Request& req,
                                                           httplib::Response& res) {
    if (!store.Progress(req.matches[1], NowMs())) {
      return Error(res, 404, "no job '" + std::string(req.matches[1]) + "'");
    }
    if (!store.Collection(req.matches[1])) {
      return Error(res, 400, "job '" + std::string(req.matches[1]) + "' is not a collection job (collect: rollouts)");
    }
    res.status = 200;
    res.set_content(api::EncodeRolloutStream(store.Rollouts(req.matches[1])), "application/octet-stream");
  });

  s.Get("/api/jobs", [&store](const httplib::Request&, httplib::Response& res) {
    Reply(res, 200, store.ListJobs(NowMs()));
  });

  s.Get(R"(/api/jobs/([A-Za-z0-9_-]+))", [&store](const httplib::Request& req,
                                                  httplib::Response& res) {
    const auto p = store.Progress(req.matches[1], NowMs());
    if (!p) return Error(res, 404, "no job '" + std::string(req.matches[1]) + "'");
    Reply(res, 200, *p);
  });

  s.Get(R"(/api/jobs/([A-Za-z0-9_-]+)/results)", [&store](const httplib::Request& req,
                                                          httplib::Response& res) {
    if (!store.Progress(req.matches[1], NowMs())) {
      return Error(res, 404, "no job '" + std::string(req.matches[1]) + "'");
    }
    Reply(res, 200, store.Results(req.matches[1]));
  });

  s.Get(R"(/api/jobs/([A-Za-z0-9_-]+)/episodes)", [&store](const httplib::Request& req,
                                                           httplib::Response& res) {
    if (!store.Progress(req.matches[1], NowMs())) {
      return Error(res, 404, "no job '" + std::string(req.matches[1]) + "'");
    }
    nlohmann::json list = nlohmann::json::array();
    for (const auto& e : store.Episodes(req.matches[1])) {
      list.push_back({{"id", e.id}, {"index", e.index}, {"state", e.state},
                      {"attempts", e.attempts}, {"lease_owner", e.lease_owner},
                      {"last_error", e.last_error}, {"board", e.spec.board},
                      {"world", e.spec.world}, {"method", e.spec.method}, {"seed", e.spec.seed}});
    }
    Reply(res, 200, list);
  });

  s.Post(R"(/api/jobs/([A-Za-z0-9_-]+)/cancel)", [this, &store](const httplib::Request& req,
                                                                httplib::Response& res) {
    if (!farm_->Cancel(req.matches[1])) {
      return Error(res, 404, "no job '" + std::string(req.matches[1]) + "'");
    }
    Reply(res, 200, *store.Progress(req.matches[1], NowMs()));
  });

  s.Get(R"(/api/episodes/([A-Za-z0-9_-]+)/result)", [&store](const httplib::Request& req,
                                                             httplib::Response& res) {
    const auto r = store.FullResult(req.matches[1]);
    if (!r) return Error(res, 404, "no result for episode '" + std::string(req.matches[1]) + "'");
    Reply(res, 200, *r);
  });

  s.Get("/api/workers", [this](const httplib::Request&, httplib::Response& res) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& w : farm_->Workers()) list.push_back(WorkerJson(w));
    Reply(res, 200, list);
  });
}

}  // namespace enavi::server
