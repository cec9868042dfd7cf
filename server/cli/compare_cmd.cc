// enavi compare BASE CANDIDATE: did the candidate job get worse than the base job?
// enavi trend: how a metric moved over a label series of jobs, with the seeds' draw beside it.
#include <filesystem>
#include <iostream>
#include <memory>
#include <regex>

#include "api/client.h"
#include "api/job_spec.h"
#include "server/cli/commands.h"
#include "server/compare/compare.h"
#include "server/compare/compare_sources.h"
#include "server/eval/tables.h"
#include "server/store/jobs.h"
#include "server/store/queries.h"
#include "server/store/store.h"

namespace enavi::cli {
namespace {

struct CompareFlags {
  std::string base, candidate;
  std::string server = api::DefaultServerUrl();
  std::string token;
  std::string thresholds;
  std::string format = "table";
  std::string mode = "auto";
};

// A job id as a farm makes them (server/store/jobs.cc): "j" and 12 hex digits.
bool IsJobId(const std::string& text) {
  static const std::regex kJobId("^j[0-9a-f]{12}$");
  return std::regex_match(text, kJobId);
}

// "FILE.db" (its only job) or "FILE.db:JOB" reads a database; a job id asks the server. Anything
// else is bad input, named as typed (it is neither a file here nor a job id).
server::CompareInput LoadJob(const std::string& source, const CompareFlags& f, const char* which) {
  std::string path = source, job;
  const auto colon = source.rfind(':');
  if (!std::filesystem::is_regular_file(path)) {
    if (colon != std::string::npos && std::filesystem::is_regular_file(source.substr(0, colon))) {
      path = source.substr(0, colon);
      job = source.substr(colon + 1);
    } else {
      path.clear();
    }
  }
  if (path.empty()) {
    if (!IsJobId(source)) {
      const std::string file = colon == std::string::npos ? source : source.substr(0, colon);
      throw std::invalid_argument(std::string(which) + ": '" + source + "': no such database file" +
                                  (file == source ? "" : " '" + file + "'") +
                                  ", and not a job id (j and 12 hex digits, as `enavi submit` prints)");
    }
    api::FarmClient client(f.server, f.token);
    try {
      return server::CompareInputFromServer(client, source, source);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string(which) + ": " + e.what());  // the server's 4xx: unknown job
    }
  }
  server::StoreOptions options;
  options.read_only = true;
  server::Store store(path, options);
  if (job.empty()) {
    const auto jobs = store.jobs().ListJobs(0);
    if (jobs.size() != 1) {
      std::string ids;
      for (const auto& p : jobs) ids += " " + p.id;
      throw std::invalid_argument(std::string(which) + ": " + path + " holds " +
                                  std::to_string(jobs.size()) + " jobs; name one as " + path +
                                  ":JOB (jobs:" + (ids.empty() ? " none" : ids) + ")");
    }
    job = jobs.front().id;
  } else if (!store.jobs().Progress(job, 0)) {
    throw std::invalid_argument(std::string(which) + ": " + path + " has no job '" + job + "'");
  }
  return server::CompareInputFromStore(store, job, source);
}

void RunCompare(const CompareFlags& f) {
  server::CompareOptions options;
  options.mode = f.mode;
  if (!f.thresholds.empty()) options.rules = server::LoadMetricRules(f.thresholds);
  const server::CompareInput base = LoadJob(f.base, f, "BASE");
  const server::CompareInput candidate = LoadJob(f.candidate, f, "CANDIDATE");
  const server::CompareReport report = server::Compare(base, candidate, options);
  if (f.format == "json") {
    std::cout << server::CompareJson(report).dump(2) << "\n";
  } else if (f.format == "junit") {
    std::cout << server::CompareJunit(report);
  } else {
    std::cout << server::CompareTable(report);
  }
  std::cout.flush();
  const std::string verdict = report.verdict();
  if (verdict == "regression") throw ExitStatus{kExitRegression};
  if (verdict == "cannot_judge") throw ExitStatus{kExitCannotJudge};
}

struct TrendFlags {
  std::string label, metric = "flight_time_s", method, db, format = "table";
  std::string server = api::DefaultServerUrl();
};

void RunTrend(const TrendFlags& f) {
  nlohmann::json trend;
  const auto [key, value] = api::ParseLabelFilter(f.label, "--label");
  try {
    if (!f.db.empty()) {
      if (!std::filesystem::is_regular_file(f.db)) throw std::invalid_argument("--db: " + f.db + ": no such database file");
      server::StoreOptions options;
      options.read_only = true;
      server::Store store(f.db, options);
      trend = store.queries().Trend(key, value, f.metric, server::Page{0, 1000});
      server::AddTrendIntervals(&trend);
    } else {
      trend = api::FarmClient(f.server).Trend(f.label, f.metric);
    }
  } catch (const std::invalid_argument& e) {
    // The store and the API name the parameter `metric`; here the user typed --metric.
    const std::string what = e.what();
    throw std::invalid_argument(what.rfind("metric: ", 0) == 0 ? "--" + what : what);
  }
  // No job carries the label: nothing to show is not a trend that stayed flat.
  if (trend.value("total", 0) == 0) {
    throw std::invalid_argument("--label: '" + f.label + "': no job carries this label" +
                                (f.db.empty() ? " on " + f.server : " in " + f.db));
  }
  if (f.format == "json") {
    std::cout << trend.dump(2) << "\n";
  } else {
    std::cout << server::TrendTable(trend, f.method);
  }
}

}  // namespace

void RegisterTrendCommand(CLI::App& app) {
  auto f = std::make_shared<TrendFlags>();
  CLI::App* sub = app.add_subcommand(
      "trend", "A metric over the jobs of a label series (oldest first): mean per board and method with its 95 % interval");
  sub->add_option("--label", f->label, "the series: jobs labelled KEY=VALUE")->required();
  sub->add_option("--metric", f->metric, "a result metric (flight_time_s, nav_cpu_util_pct, eci.mean, ...)")
      ->capture_default_str();
  sub->add_option("--method", f->method, "only this method's rows");
  sub->add_option("--db", f->db, "read a farm database instead of asking --server");
  sub->add_option("--format", f->format, "table or json")->check(CLI::IsMember({"table", "json"}))->capture_default_str();
  sub->add_option("--server", f->server, "farm server URL")->envname("ENAVI_SERVER")->capture_default_str();
  sub->callback([f] { RunTrend(*f); });
}

void RegisterCompareCommand(CLI::App& app) {
  auto f = std::make_shared<CompareFlags>();
  CLI::App* sub = app.add_subcommand(
      "compare", "Compare two jobs episode by episode; exit 3 when the candidate regressed, 4 when the mode "
                 "cannot judge (paired mode with one seed pair)");
  sub->add_option("base", f->base, "base job: a job id on --server, FILE.db or FILE.db:JOB")->required();
  sub->add_option("candidate", f->candidate, "candidate job (same forms)")->required();
  sub->add_option("--thresholds", f->thresholds,
                  "YAML file changing metric directions and thresholds (metrics: {name: {rel: 0.1}})")
      ->check(CLI::ExistingFile);
  sub->add_option("--format", f->format, "table, json or junit")
      ->check(CLI::IsMember({"table", "json", "junit"}))
      ->capture_default_str();
  sub->add_option("--mode", f->mode,
                  "auto (exact on the virtual clock with the cost model, else paired), exact, paired")
      ->check(CLI::IsMember({"auto", "exact", "paired"}))
      ->capture_default_str();
  sub->add_option("--server", f->server, "farm server URL for job ids")
      ->envname("ENAVI_SERVER")
      ->capture_default_str();
  sub->add_option("--token", f->token, "farm server token")->envname("ENAVI_TOKEN");
  sub->callback([f] { RunCompare(*f); });
}

}  // namespace enavi::cli
