#include "server/eval/eval.h"

#include <charconv>
#include <sstream>
#include <thread>
#include <type_traits>

#include <spdlog/spdlog.h>

#include "api/yaml_read.h"
#include "server/eval/local_farm.h"
#include "server/http/http_api.h"
#include "server/eval/tables.h"
#include "server/scheduler/farm_server.h"
#include "server/store/jobs.h"
#include "server/store/queries.h"
#include "server/store/store.h"

namespace enavi::server {
namespace {

// Flag values are quoted, so a path or label reads back as given.
using api::YamlQuoted;

std::string YamlList(const std::vector<std::string>& items) {
  std::string out = "[";
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? ", " : "") + YamlQuoted(items[i]);
  return out + "]";
}

// A YAML flow map; numbers as the shortest text that reads back as the same double.
template <typename Value>
std::string YamlMap(const std::map<std::string, Value>& values) {
  std::string out = "{";
  for (const auto& [name, value] : values) {
    out += (out.size() > 1 ? ", " : "") + YamlQuoted(name) + ": ";
    if constexpr (std::is_same_v<Value, double>) {
      char number[32];
      out.append(number, std::to_chars(number, number + sizeof number, value).ptr);
    } else {
      out += YamlQuoted(value);
    }
  }
  return out + "}";
}

}  // namespace

std::string EvalJobYaml(const EvalOptions& o) {
  std::ostringstream y;
  y << "name: eval\n"
    << "boards: " << YamlList(o.boards) << "\n"
    << "scenarios: " << YamlList(o.scenarios) << "\n"
    << "methods: " << YamlList(o.methods) << "\n"
    << "seeds: " << o.seeds << "\n"
    << "clock: " << YamlQuoted(o.clock) << "\n"
    << "cost: " << YamlQuoted(o.cost) << "\n";
  if (o.clock == "emulated") y << "dilation: " << YamlQuoted(o.dilation) << "\n";
  // Also when asked for on the virtual clock, so that the job's check refuses it by name.
  if (o.clock == "emulated" || o.speed_probe != "check") y << "speed_probe: " << YamlQuoted(o.speed_probe) << "\n";
  if (!o.policy.empty()) y << "policy: " << YamlQuoted(o.policy) << "\n";
  if (!o.labels.empty()) y << "labels: " << YamlMap(o.labels) << "\n";
  if (!o.overrides.empty()) y << "overrides: " << YamlMap(o.overrides) << "\n";
  if (!o.method_overrides.empty()) {
    y << "episode_overrides:\n";
    for (const auto& [method, values] : o.method_overrides) {
      y << "  - {match: {method: [" << YamlQuoted(method) << "]}, overrides: " << YamlMap(values) << "}\n";
    }
  }
  return y.str();
}

EvalReport RunEval(const EvalOptions& options, std::ostream& progress_out) {
  // Validate the matrix exactly as a submitted job; errors name the line of the flag.
  const std::string yaml = EvalJobYaml(options);
  const api::JobSpec job = api::ParseJobSpec(yaml, "enavi eval flags", options.job_spec);

  LocalFarmOptions farm_options;
  farm_options.db = options.db;
  farm_options.workers = options.workers;
  farm_options.slots = options.slots;
  farm_options.episode_command = options.episode_command;
  farm_options.episode_timeout = options.episode_timeout;
  farm_options.enavi = options.enavi;
  farm_options.domain = options.domain;
  LocalFarm local(farm_options);
  Store& store = local.store();
  FarmServer& farm = local.farm();
  std::unique_ptr<HttpApi> http;
  if (options.dashboard) {
    http = std::make_unique<HttpApi>(&farm, *options.dashboard);
    http->Start();
    progress_out << "dashboard: " << http->url() << "/\n" << std::flush;
  }

  EvalReport report;
  report.job_id = farm.Submit(job, yaml);
  auto last_print = std::chrono::steady_clock::time_point{};
  while (true) {
    report.progress = *store.jobs().Progress(report.job_id, NowMs());
    const auto now = std::chrono::steady_clock::now();
    // A bar redrawn in place on a terminal; piped, only the final line (README.md, "What it does").
    if (report.progress.terminal() ||
        (options.progress_bar && now - last_print >= options.progress_period)) {
      const std::string line = ProgressLine(report.progress, options.progress_bar);
      if (options.progress_bar) {
        progress_out << "\r" << line << "\033[K" << std::flush;
      } else {
        progress_out << line << "\n" << std::flush;
      }
      last_print = now;
    }
    if (report.progress.terminal()) break;
    local.CheckWorkers();
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  if (options.progress_bar) progress_out << "\n";

  report.results = store.queries().Results(report.job_id);
  // The dashboard serves the finished job (workers idle) until the caller lets go.
  if (http && options.while_serving) options.while_serving(report);
  if (http) http->Stop();
  local.Stop();
  return report;
}

}  // namespace enavi::server
