#include "api/http_schema.h"

#include <nlohmann/json.hpp>

namespace enavi::api {

std::string DefaultServerUrl() { return "http://127.0.0.1:" + std::to_string(kDefaultHttpPort); }

double JobProgress::rate_per_s() const {
  const std::int64_t end = finished_ms > 0 ? finished_ms : now_ms;
  if (started_ms <= 0 || end <= started_ms || finished() == 0) return 0.0;
  return finished() / ((end - started_ms) / 1000.0);
}

double JobProgress::eta_s() const {
  if (terminal()) return 0.0;
  const double rate = rate_per_s();
  if (rate <= 0) return -1.0;
  return (total - finished()) / rate;
}

void to_json(nlohmann::json& j, const JobProgress& p) {
  j = {{"id", p.id},           {"name", p.name},         {"state", p.state},
       {"total", p.total},     {"pending", p.pending},   {"leased", p.leased},
       {"done", p.done},       {"failed", p.failed},     {"cancelled", p.cancelled},
       {"created_ms", p.created_ms}, {"started_ms", p.started_ms},
       {"finished_ms", p.finished_ms}, {"now_ms", p.now_ms}, {"errors", p.errors},
       {"rate_per_s", p.rate_per_s()}, {"eta_s", p.eta_s()},
       {"labels", p.labels},   {"provenance", p.provenance}};
  if (!p.pending_needs.empty()) j["pending_needs"] = p.pending_needs;
  if (!p.waiting.empty()) j["waiting"] = p.waiting;
}

void from_json(const nlohmann::json& j, JobProgress& p) {
  p = JobProgress{};
  j.at("id").get_to(p.id);
  p.name = j.value("name", std::string());
  j.at("state").get_to(p.state);
  j.at("total").get_to(p.total);
  p.pending = j.value("pending", 0);
  p.leased = j.value("leased", 0);
  p.done = j.value("done", 0);
  p.failed = j.value("failed", 0);
  p.cancelled = j.value("cancelled", 0);
  p.created_ms = j.value("created_ms", std::int64_t{0});
  p.started_ms = j.value("started_ms", std::int64_t{0});
  p.finished_ms = j.value("finished_ms", std::int64_t{0});
  p.now_ms = j.value("now_ms", std::int64_t{0});
  p.errors = j.value("errors", std::vector<std::string>{});
  p.labels = j.value("labels", std::map<std::string, std::string>{});
  p.provenance = j.value("provenance", std::map<std::string, std::string>{});
  p.pending_needs = j.value("pending_needs", std::map<std::string, int>{});
  p.waiting = j.value("waiting", std::string());
}

}  // namespace enavi::api
