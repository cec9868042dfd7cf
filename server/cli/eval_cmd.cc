// enavi eval: the embedded farm (server + local workers + SQLite), table at the end.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <future>
#include <iostream>
#include <tuple>
#include <memory>

#include <spdlog/spdlog.h>

#include "api/ros_stack.h"
#include "navstack/methods/registry.h"
#include "server/cli/cli_values.h"
#include "server/cli/commands.h"
#include "server/cli/farm_flags.h"
#include "server/cli/registry_help.h"
#include "server/eval/eval.h"
#include "server/eval/paper_reference.h"
#include "server/eval/tables.h"
#include "workers/sim/episode_config.h"

namespace enavi::cli {
namespace {

struct EvalFlags {
  server::EvalOptions options;
  std::string db;
  std::vector<std::string> world_roots;
  std::vector<std::string> unchecked_override_prefixes;
  int domain = -1;
  double episode_timeout_s = 3600;
  bool json = false;
  bool verbose = false;
  bool dashboard = false;
  std::string http = "127.0.0.1:0";
  std::string preset;  ///< "paper" or empty
  std::vector<std::string> overrides;  ///< --set items
  std::vector<std::string> labels;     ///< --label items
  std::vector<std::string> params;     ///< --param items
  std::vector<std::string> ros_stacks; ///< --ros-stack files
};

// --preset paper: the paper's HIL matrix (5 boards x S1-S5 x E-Navi and the baseline, 3 seeds
// unless --seeds says otherwise). --methods may add methods (e.g. fixed, for the gap split) but
// must keep both of the paper's; boards and scenarios are the preset's.
void ApplyPreset(EvalFlags* f, const CLI::App& sub) {
  if (f->preset.empty()) return;
  server::EvalOptions& o = f->options;
  for (const char* flag : {"--boards", "--scenarios"}) {
    if (sub.count(flag) > 0) {
      throw CLI::ValidationError(std::string("--preset paper fixes the boards and scenarios; drop ") + flag);
    }
  }
  o.boards = server::PaperBoards();
  o.scenarios = server::PaperScenarios();
  if (sub.count("--seeds") == 0) o.seeds = 3;
  for (const char* m : {"baseline", "enavi"}) {
    if (std::find(o.methods.begin(), o.methods.end(), m) == o.methods.end()) {
      throw CLI::ValidationError(std::string("--preset paper compares baseline and enavi; --methods lacks ") + m);
    }
  }
}

// --set NAME=VALUE: a tunable of every listed method; METHOD:NAME=VALUE: of one of --methods.
// The job spec checks names and ranges against each method's tunables.
void ApplyOverrides(EvalFlags* f) {
  server::EvalOptions& o = f->options;
  for (const auto& [key, text] : ParseNameValues("--set", f->overrides)) {
    const double value = ParseNumber("--set", key, text);
    const std::size_t colon = key.find(':');
    if (colon == std::string::npos) {
      o.overrides[key] = value;
      continue;
    }
    const std::string method = key.substr(0, colon);
    if (std::find(o.methods.begin(), o.methods.end(), method) == o.methods.end()) {
      throw std::invalid_argument("--set " + key + ": method '" + method + "' is not among --methods (" +
                                 JoinNames(o.methods, ",") + ")");
    }
    o.method_overrides[method][key.substr(colon + 1)] = value;
  }
}

void RunEvalCommand(EvalFlags f, const CLI::App& root, const CLI::App& sub) {
  ApplyPreset(&f, sub);
  ApplyOverrides(&f);
  f.options.labels = ParseNameValues("--label", f.labels);
  f.options.world_params = ParseNameValues("--param", f.params);
  RequireEpisodeUnlessEpisodeCmd(root, f.options.episode_command);
  StopSignals signals;
  SetupLogging(f.verbose);
  if (!f.verbose) spdlog::set_level(spdlog::level::warn);
  server::EvalOptions& o = f.options;
  o.db = f.db;
  for (const auto& r : f.world_roots) o.job_spec.allowed_roots.emplace_back(r);
  // ROS stacks named on the command line: their files are the user's to name, wherever they are.
  if (!f.ros_stacks.empty() && o.job_spec.allowed_roots.empty()) o.job_spec.allowed_roots.push_back(std::filesystem::current_path());
  for (const std::string& file : f.ros_stacks) {
    const api::RosStack stack = api::LoadRosStack(file, navstack::MethodNames());
    const std::filesystem::path path = std::filesystem::absolute(file);
    o.ros_stacks[stack.name] = path.string();
    o.job_spec.allowed_roots.push_back(path.parent_path());
    if (std::find(o.methods.begin(), o.methods.end(), stack.name) == o.methods.end()) o.methods.push_back(stack.name);
  }
  if (!f.ros_stacks.empty() && sub.count("--clock") == 0) o.clock = "emulated";  // the only clock a ROS stack runs on
  o.job_spec.catalog = sim::FarmCatalog();
  o.job_spec.catalog.unchecked_prefixes = f.unchecked_override_prefixes;
  if (f.domain >= 0) o.domain = static_cast<std::uint32_t>(f.domain);
  o.episode_timeout = std::chrono::seconds(static_cast<std::int64_t>(f.episode_timeout_s));
  o.progress_bar = isatty(STDERR_FILENO) == 1;

  auto print = [&f](const server::EvalReport& report) {
    if (f.json) {
      std::cout << report.results.dump(2) << "\n";
    } else {
      // A table flown with overrides says so: the method names alone would not.
      if (!f.overrides.empty()) std::cout << "with --set " << JoinNames(f.overrides, " --set ") << "\n";
      std::cout << server::PaperTable(report.results) << "\n" << server::EciRangeTable(report.results);
      if (server::HasMovingWorlds(report.results)) std::cout << "\n" << server::RobustnessTable(report.results);
      if (f.preset == "paper") std::cout << server::PaperComparison(report.results);
    }
    std::cout.flush();
  };
  // Ctrl-C: leave at once. The workers die with this process (PR_SET_PDEATHSIG) and their
  // episodes with them; a --db keeps whatever was stored. Once the job is done and only the
  // dashboard serves, Ctrl-C ends the eval normally.
  std::atomic<bool> serving_done_job{false}, stop_requested{false};
  std::promise<void> stop;
  signals.Watch([&](int) {
    if (!serving_done_job || stop_requested.exchange(true)) std::_Exit(130);
    stop.set_value();
  });
  bool printed = false;
  if (f.dashboard) {
    server::HttpOptions http;
    std::tie(http.host, http.port) = ParseHostPort(f.http, "--http");
    http.job_spec = o.job_spec;
    o.dashboard = http;
    o.while_serving = [&](const server::EvalReport& report) {
      print(report);
      printed = true;
      serving_done_job = true;  // before saying so: a Ctrl-C right after the line ends normally
      std::cerr << "job done; the dashboard keeps serving until Ctrl-C\n";
      stop.get_future().wait();
    };
  }
  const server::EvalReport report = server::RunEval(o, std::cerr);
  if (!printed) print(report);
  if (!f.db.empty()) {
    std::cerr << report.results.size() << " results stored in " << f.db << " (job "
              << report.job_id << ")\n";
  }
  if (report.progress.failed > 0) {
    for (const auto& e : report.progress.errors) std::cerr << "failed: " << e << "\n";
    throw std::runtime_error(std::to_string(report.progress.failed) + " of " +
                             std::to_string(report.progress.total) + " episodes failed");
  }
}

}  // namespace

void RegisterEvalCommand(CLI::App& app) {
  auto f = std::make_shared<EvalFlags>();
  server::EvalOptions& o = f->options;
  CLI::App* sub = app.add_subcommand(
      "eval", "Evaluate a matrix on an embedded farm (local server + workers) and print the table");
  sub->add_option("--name", o.name, "the job's name (the dashboard, `enavi status` and `enavi compare` show it)")
      ->capture_default_str();
  sub->add_option("--boards", o.boards, "boards (comma-separated)")->delimiter(',')->capture_default_str();
  sub->add_option("--scenarios", o.scenarios, "scenarios or world files (comma-separated)")
      ->delimiter(',')
      ->capture_default_str();
  std::string method_names;
  for (const std::string& m : navstack::MethodNames()) method_names += (method_names.empty() ? "" : ", ") + m;
  sub->add_option("--methods", o.methods, "methods (comma-separated): " + method_names)->delimiter(',')->capture_default_str();
  sub->add_option("--ros-stack", f->ros_stacks,
                  "a ROS 1 stack file (docs/ros.md): flies the user's stack as a method by its name, beside "
                  "--methods, on the emulated clock (repeatable)")
      ->check(CLI::ExistingFile);
  sub->add_option("--seeds", o.seeds, "seeds 1..N per cell")->capture_default_str();
  sub->add_option("--timeout", o.timeout_s, "each episode's limit in sim seconds (0: from the start-goal distance)")
      ->check(CLI::Range(0.0, api::kMaxTimeoutS));
  sub->add_option("--clock", o.clock, "clock:" + ClocksHelp())
      ->capture_default_str()
      ->check(CLI::IsMember(sim::FarmCatalog().clocks));
  sub->add_option("--cost", o.cost, "cost model: model or measured")->capture_default_str();
  sub->add_option("--dilation", o.dilation,
                  "emulated clock: 1 sim second = K wall seconds, or auto: the smallest multiple of 0.25 at which "
                  "each board fits this host when its episode starts")
      ->capture_default_str();
  AddSpeedProbeOption(sub, &o.speed_probe);
  AddAirOptions(sub, &o.wind, &o.odometry_noise);
  sub->add_option("--set", f->overrides,
                  "override a tunable, NAME=VALUE for every listed method or METHOD:NAME=VALUE for one "
                  "(repeatable; `enavi fly --help` lists each method's tunables)");
  sub->add_option("--policy", o.policy,
                  "E-Navi's frequency-adapter policy file (default: the shipped one), or the learned method's "
                  "nav policy file (one policy a job: fly learned in an eval of its own)");
  sub->add_option("--param", f->params, "world generator parameter k=v of every scenario (repeatable)");
  sub->add_option("--label", f->labels,
                  "tag the job, KEY=VALUE (repeatable): the dashboard and `enavi compare` tell jobs apart by them");
  sub->add_option("--db", f->db, "keep the results in this SQLite database (default: temporary)");
  sub->add_option("--workers", o.workers, "local worker processes")->capture_default_str();
  sub->add_option("--slots", o.slots, "episodes per worker at once")->capture_default_str();
  sub->add_option("--episode-cmd", o.episode_command,
                  "episode command for the workers (default: enavi episode)")
      ->envname("ENAVI_EPISODE_CMD");
  sub->add_option("--episode-timeout", f->episode_timeout_s, "wall-clock limit per episode, s")
      ->check(CLI::Range(1.0, 7 * 24 * 3600.0))
      ->capture_default_str();
  sub->add_option("--world-root", f->world_roots, "allowed root for world files (default: cwd)");
  sub->add_option("--unchecked-overrides", f->unchecked_override_prefixes,
                  "override-name prefix that passes unchecked, for an --episode-cmd other than `enavi fly`")
      ->group("");
  sub->add_option("--domain", f->domain, "DDS domain (default: derived from the pid)")
      ->check(CLI::Range(0, 232));
  sub->add_flag("--dashboard", f->dashboard,
                "serve the dashboard (printed URL) while the job runs, and after it until Ctrl-C");
  sub->add_option("--http", f->http, "dashboard address HOST:PORT (loopback; port 0: any)")
      ->capture_default_str();
  sub->add_flag("--json", f->json, "print the result objects as JSON instead of the table");
  sub->add_flag("-v,--verbose", f->verbose, "server log on stderr");
  sub->add_option("--preset", f->preset,
                  "paper: the paper's HIL matrix (boards " + JoinNames(server::PaperBoards(), ",") + " x " +
                      JoinNames(server::PaperScenarios(), ",") +
                      " x baseline,enavi; --seeds default 3), our table beside the paper's with the difference of "
                      "each cell")
      ->check(CLI::IsMember({"paper"}));
  sub->callback([f, &app, sub] { RunEvalCommand(*f, app, *sub); });
}

}  // namespace enavi::cli
