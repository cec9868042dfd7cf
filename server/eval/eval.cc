#include "server/eval/eval.h"

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <iterator>
#include <sstream>
#include <thread>
#include <type_traits>

#include <spdlog/spdlog.h>

#include "api/yaml_read.h"
#include "server/eval/local_farm.h"
#include "server/eval/progress_pacer.h"
#include "server/eval/tables.h"
#include "server/http/http_api.h"
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

std::string Joined(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ",") + item;
  return out;
}

// The flag of `enavi eval` that wrote `field` of its job spec (EvalJobYaml), as its user typed
// it; empty when no flag did.
std::string FlagOf(const EvalOptions& o, const std::string& field) {
  auto is = [&](const std::string& name) {
    return field == name || field.rfind(name + "[", 0) == 0 || field.rfind(name + ".", 0) == 0;
  };
  if (is("boards")) return "--boards " + Joined(o.boards);
  if (is("scenarios")) return "--scenarios " + Joined(o.scenarios);
  if (is("methods")) return "--methods " + Joined(o.methods);
  if (is("seeds")) return "--seeds " + std::to_string(o.seeds);
  if (is("name")) return "--name " + o.name;
  if (is("clock")) return "--clock " + o.clock;
  if (is("cost")) return "--cost " + o.cost;
  if (is("dilation")) return "--dilation " + o.dilation;
  if (is("speed_probe")) return "--speed-probe " + o.speed_probe;
  if (is("policy")) return "--policy " + o.policy;
  if (field.rfind("world_params.", 0) == 0) return "--param " + field.substr(13);
  if (is("world_params")) return "--param";
  if (is("odometry_noise")) return "--odometry-noise " + o.odometry_noise;
  if (is("wind.gust.speed_mps")) return "--gust";
  if (is("wind.gust.direction_deg")) return "--gust-dir";
  if (is("wind.gust.start_s")) return "--gust-start";
  if (is("wind.gust.rise_s")) return "--gust-rise";
  if (is("wind.gust.hold_s")) return "--gust-hold";
  if (is("wind.direction_deg")) return "--wind-dir";
  if (is("wind.turbulence")) return "--turbulence " + o.wind.turbulence;
  if (is("wind")) return "--wind";
  if (field == "matrix") return "--boards x --scenarios x --methods x --seeds";
  if (field.rfind("labels.", 0) == 0) {
    const std::string key = field.substr(7);
    const auto it = o.labels.find(key);
    return "--label " + key + (it == o.labels.end() ? "" : "=" + it->second);
  }
  if (field.rfind("overrides.", 0) == 0) return "--set " + field.substr(10);
  if (is("overrides")) return "--set";
  // episode_overrides[i]: the i-th method of --set METHOD:NAME=VALUE, in EvalJobYaml's order.
  if (field.rfind("episode_overrides[", 0) == 0 && !o.method_overrides.empty()) {
    const std::size_t index = std::strtoul(field.c_str() + 18, nullptr, 10);
    const auto method = std::next(o.method_overrides.begin(),
                                  static_cast<long>(std::min(index, o.method_overrides.size() - 1)));
    const std::size_t name = field.find("].overrides.");
    return "--set " + method->first + ":" + (name == std::string::npos ? "" : field.substr(name + 12));
  }
  return "";
}

}  // namespace

api::JobSpec ParseEvalJob(const EvalOptions& options, const std::string& yaml) {
  try {
    return api::ParseJobSpec(yaml, "enavi eval flags", options.job_spec);
  } catch (const api::JobSpecError& e) {
    // The YAML is ours, not the user's: name the flag they typed, never a line of it.
    const std::string flag = FlagOf(options, e.field());
    if (e.field().empty() || flag.empty()) throw std::invalid_argument("enavi eval: " + std::string(e.what()));
    const bool item = e.field().find('[') != std::string::npos && flag.rfind("--set", 0) != 0;
    throw std::invalid_argument(flag + ": " + (item ? e.field() + ": " : "") + e.reason());
  }
}

std::string EvalJobYaml(const EvalOptions& o) {
  std::ostringstream y;
  y << "name: " << YamlQuoted(o.name) << "\n"
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
  if (!o.world_params.empty()) {
    y << "world_params:\n";
    for (const auto& [k, v] : o.world_params) y << "  " << YamlQuoted(k) << ": " << YamlQuoted(v) << "\n";
  }
  if (o.timeout_s > 0) y << "timeout_s: " << o.timeout_s << "\n";
  if (o.wind != api::WindSpec{}) {
    // Shortest text that reads back to the same double: the job flies exactly what was typed.
    const auto num = [](double v) {
      char buf[32];
      return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
    };
    const api::GustSpec& g = o.wind.gust;
    y << "wind: {speed_mps: " << num(o.wind.speed_mps) << ", direction_deg: " << num(o.wind.direction_deg)
      << ", turbulence: " << YamlQuoted(o.wind.turbulence) << ", gust: {speed_mps: " << num(g.speed_mps)
      << ", direction_deg: " << num(g.direction_deg) << ", start_s: " << num(g.start_s)
      << ", rise_s: " << num(g.rise_s) << ", hold_s: " << num(g.hold_s) << "}}\n";
  }
  if (o.odometry_noise != "none") y << "odometry_noise: " << YamlQuoted(o.odometry_noise) << "\n";
  if (!o.labels.empty()) y << "labels: " << YamlMap(o.labels) << "\n";
  if (!o.ros_stacks.empty()) {
    y << "ros_methods:\n";
    for (const auto& [name, file] : o.ros_stacks) y << "  " << YamlQuoted(name) << ": " << YamlQuoted(file) << "\n";
  }
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
  // Validate the matrix exactly as a submitted job; errors name the flag as typed.
  const std::string yaml = EvalJobYaml(options);
  const api::JobSpec job = ParseEvalJob(options, yaml);

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
  ProgressPacer lines(options.progress_line_period);
  while (true) {
    report.progress = *store.jobs().Progress(report.job_id, NowMs());
    const auto now = std::chrono::steady_clock::now();
    // A bar redrawn in place on a terminal; in a log, a line every period or tenth of the job,
    // and the last one (docs/farm.md, "One command").
    const api::JobProgress& p = report.progress;
    if (options.progress_bar ? p.terminal() || now - last_print >= options.progress_period
                             : lines.Due(p.finished(), p.total, now) || p.terminal()) {
      const std::string line = ProgressLine(p, options.progress_bar);
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
