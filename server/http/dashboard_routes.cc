// The dashboard's routes: its aggregates (docs/dashboard.md: summaries, failures, the bird's-eye
// view, compare, trend, info) and its embedded page, scripts (Chart.js among them) and style sheet.
#include <string>

// Before httplib.h: it pulls in <resolv.h>, whose `_res` macro breaks Eigen's parameter names.
#include "server/report/flight_report.h"
#include "worlds/resolve.h"

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "api/job_spec.h"
#include "api/provenance.h"
#include "server/compare/compare.h"
#include "server/compare/compare_sources.h"
#include "server/http/http_api.h"
#include "server/http/http_reply.h"
#include "server/store/jobs.h"
#include "server/store/queries.h"

namespace enavi::server {

// Generated from server/dashboard/* by cmake/EmbedFiles.cmake.
const std::map<std::string, std::string>& DashboardAssets();

void HttpApi::DashboardRoutes() {
  httplib::Server& s = *server_;
  Store& store = *store_;

  s.Get(R"(/api/jobs/([A-Za-z0-9_-]+)/summary)", [&store](const httplib::Request& req,
                                                          httplib::Response& res) {
    if (!store.jobs().Progress(req.matches[1], NowMs())) {
      return Error(res, 404, "no job '" + std::string(req.matches[1]) + "'");
    }
    Reply(res, 200, store.queries().JobSummary(req.matches[1], PageOf(req)));
  });

  s.Get(R"(/api/jobs/([A-Za-z0-9_-]+)/failures)", [&store](const httplib::Request& req,
                                                           httplib::Response& res) {
    if (!store.jobs().Progress(req.matches[1], NowMs())) {
      return Error(res, 404, "no job '" + std::string(req.matches[1]) + "'");
    }
    Reply(res, 200, store.queries().JobFailures(req.matches[1], PageOf(req)));
  });

  s.Get(R"(/api/episodes/([A-Za-z0-9_-]+)/topdown.png)", [&store](const httplib::Request& req,
                                                                  httplib::Response& res) {
    const auto r = store.queries().FullResult(req.matches[1]);
    if (!r) return Error(res, 404, "no result for episode '" + std::string(req.matches[1]) + "'");
    const int width = req.has_param("width") ? ParseInt(req.get_param_value("width"), "width", 300, 2000) : 900;
    worlds::WorldRequest w;
    w.world = r->spec.world;
    w.seed = r->spec.seed;
    w.params = r->spec.world_params;
    if (r->spec.start) w.start = Eigen::Vector3d((*r->spec.start)[0], (*r->spec.start)[1], (*r->spec.start)[2]);
    if (r->spec.goal) w.goal = Eigen::Vector3d((*r->spec.goal)[0], (*r->spec.goal)[1], (*r->spec.goal)[2]);
    const std::vector<std::uint8_t> png = report::FlightTopDownPng(*r, worlds::ResolveWorld(w), width);
    res.set_content(std::string(png.begin(), png.end()), "image/png");
  });

  s.Get("/api/compare", [&store](const httplib::Request& req, httplib::Response& res) {
    const std::string base = req.get_param_value("base"), candidate = req.get_param_value("candidate");
    for (const auto& [name, id] : {std::pair{"base", base}, {"candidate", candidate}}) {
      if (id.empty()) return Error(res, 400, std::string(name) + ": missing (a job id)");
      if (!store.jobs().Progress(id, NowMs())) return Error(res, 404, std::string(name) + ": no job '" + id + "'");
    }
    CompareOptions options;
    if (req.has_param("mode")) options.mode = req.get_param_value("mode");
    Reply(res, 200, CompareJson(Compare(CompareInputFromStore(store, base, base),
                                        CompareInputFromStore(store, candidate, candidate), options)));
  });

  s.Get("/api/trend", [&store](const httplib::Request& req, httplib::Response& res) {
    const auto labels = QueryValues(req, "label");
    if (labels.size() != 1) return Error(res, 400, "label: give exactly one key=value");
    const auto [key, value] = api::ParseLabelFilter(labels.front(), "label");
    const std::string metric = req.has_param("metric") ? req.get_param_value("metric") : "flight_time_s";
    nlohmann::json trend = store.queries().Trend(key, value, metric, PageOf(req));
    AddTrendIntervals(&trend);
    Reply(res, 200, trend);
  });

  s.Get("/api/info", [this](const httplib::Request&, httplib::Response& res) {
    nlohmann::json rules = nlohmann::json::object();
    for (const auto& [name, rule] : DefaultMetricRules()) {
      rules[name] = {{"direction", DirectionName(rule.direction)}, {"abs", rule.abs},
                     {"rel", rule.rel}, {"success_only", rule.success_only},
                     {"range", RangeName(rule.range)}};
    }
    Reply(res, 200, {{"read_only", farm_ == nullptr}, {"enavi_version", api::BuildVersion()},
                     {"git_commit", api::BuildCommit()}, {"metric_rules", rules}});
  });

  // The pages: one HTML shell, the scripts and the style sheet, all embedded in the binary.
  auto asset = [](const std::string& name, const char* type) {
    return [name, type](const httplib::Request&, httplib::Response& res) {
      const auto& files = DashboardAssets();
      const auto it = files.find(name);
      if (it == files.end()) return Error(res, 404, "no dashboard asset " + name);
      res.set_header("Cache-Control", "no-cache");
      res.set_header("X-Content-Type-Options", "nosniff");
      // Nothing but our own script and images: an injected tag could not load or run anything.
      res.set_header("Content-Security-Policy",
                     "default-src 'self'; img-src 'self' data:; style-src 'self'; script-src 'self'");
      res.set_content(it->second, type);
    };
  };
  server_->Get("/", asset("index.html", "text/html; charset=utf-8"));
  // Every embedded script and the style sheet by its file name (server/http/CMakeLists.txt).
  for (const auto& [name, content] : DashboardAssets()) {
    const bool js = name.size() > 3 && name.compare(name.size() - 3, 3, ".js") == 0;
    const bool css = name.size() > 4 && name.compare(name.size() - 4, 4, ".css") == 0;
    if (js || css) {
      std::string pattern = "/static/";  // the route is a regular expression: its dots escaped
      for (const char c : name) pattern += c == '.' ? std::string("\\.") : std::string(1, c);
      server_->Get(pattern, asset(name, js ? "text/javascript; charset=utf-8" : "text/css; charset=utf-8"));
    }
  }
}

}  // namespace enavi::server
