// `enavi calibrate`: fits the board cost model to this host (DESIGN.md section 4).
#include <sys/utsname.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <ctime>
#include <fstream>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "navstack/adapt/action_grid.h"
#include "navstack/rl/policy_io.h"
#include "server/cli/commands.h"
#include "workers/board/board_profile.h"
#include "workers/board/calibration.h"
#include "workers/sim/episode.h"

namespace enavi::cli {
namespace {

struct CalibrateArgs {
  std::string write_reference;
  double episode_seconds = 15.0;
  bool json = false;
};

std::string CpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

void Run(const CalibrateArgs& args) {
  // A mix of scenes and resolutions so every unit of work varies independently enough to fit.
  std::vector<board::JobSample> samples;
  sim::EpisodeOptions options;
  options.job_observer = [&](navstack::TaskId task, const navstack::WorkCounts& work, double cpu) {
    samples.push_back({task, work, cpu});
  };
  struct Run {
    std::string world;
    double res;
    double f_dif;  // difference detection is off in the baseline; two runs turn it on
    bool enavi;    // E-Navi prices the eci and the adapter's network on the board
  };
  const std::vector<Run> runs = {{"s1", 0.1, 0, false},  {"s2", 0.1, 15, false}, {"s3", 0.1, 0, false},
                                 {"s4", 0.1, 0, false},  {"s5", 0.1, 30, false}, {"s2", 0.2, 0, false},
                                 {"s3", 0.3, 0, false},  {"s2", 0.0, 0, true}};
  // Calibration prices work, not decisions: a freshly initialised network costs what a trained one does.
  const std::string policy = (std::filesystem::temp_directory_path() / ("enavi-calibrate-policy-" + std::to_string(getpid()) + ".json")).string();
  navstack::rl::SavePolicyFile(policy, navstack::rl::MakeFrequencyPolicy(navstack::ActionGrid(), 1));
  for (const auto& [world, res, f_dif, enavi] : runs) {
    api::EpisodeSpec spec;
    spec.world = world;
    spec.seed = 1;
    spec.board = "host";
    spec.cost = "measured";
    spec.timeout_s = args.episode_seconds;
    if (enavi) {
      spec.method = "enavi";
      spec.policy = policy;
    } else {
      spec.overrides["map.resolution"] = res;
      spec.overrides["rates.f_dif"] = f_dif;
    }
    if (!args.json)
      std::fprintf(stderr, "calibrate: flying %s %s for %.0f s\n", world.c_str(),
                   enavi ? "with E-Navi" : ("at " + std::to_string(res).substr(0, 4) + " m").c_str(), args.episode_seconds);
    sim::RunEpisode(spec, options);
  }
  std::filesystem::remove(policy);
  board::CostFit fit = board::FitCosts(samples);
  const board::ReferenceCosts reference = board::LoadReferenceCosts();
  const double speed = board::RelativeSpeed(samples, reference);

  utsname uts{};
  uname(&uts);
  fit.costs.reference_cpu = CpuModel();
  char id[64];
  std::snprintf(id, sizeof id, "%ld-%d", static_cast<long>(std::time(nullptr)), fit.samples);
  fit.costs.calibration_id = id;

  if (!args.write_reference.empty()) {
    std::ofstream out(args.write_reference);
    out << board::ReferenceCostsYaml(fit.costs, "Nanoseconds per work unit on the reference core, fitted by `enavi calibrate --write-reference` on " +
                                                    fit.costs.reference_cpu + " (" + uts.release + "), R^2 " +
                                                    std::to_string(fit.r2) + " over " + std::to_string(fit.samples) + " jobs.");
    if (!out) throw std::runtime_error("cannot write " + args.write_reference);
  }
  nlohmann::json j;
  j["cpu"] = fit.costs.reference_cpu;
  j["samples"] = fit.samples;
  j["r2"] = fit.r2;
  j["relative_speed_vs_reference"] = speed;
  j["reference_calibration_id"] = reference.calibration_id;
  j["ns_per_job"] = fit.costs.ns.ns_per_job;
  for (std::size_t u = 0; u < navstack::kWorkUnitNames.size(); ++u)
    j["ns_per_unit"][std::string(navstack::kWorkUnitNames[u])] = fit.costs.ns.ns_per_unit[u];
  for (const auto& [task, q] : fit.per_task)
    j["tasks"][task] = {{"jobs", q.jobs}, {"measured_s", q.measured_s}, {"predicted_s", q.predicted_s}};
  j["unobserved_units"] = fit.unobserved_units;
  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf("calibration of %s: %d jobs, R^2 %.3f, speed %.3f x the reference core\n", fit.costs.reference_cpu.c_str(),
              fit.samples, fit.r2, speed);
  std::printf("  %-18s %12s\n", "unit", "ns/unit");
  std::printf("  %-18s %12.1f\n", "(per job)", fit.costs.ns.ns_per_job);
  for (std::size_t u = 0; u < navstack::kWorkUnitNames.size(); ++u)
    std::printf("  %-18s %12.4f\n", std::string(navstack::kWorkUnitNames[u]).c_str(), fit.costs.ns.ns_per_unit[u]);
  std::printf("  %-12s %6s %12s %12s\n", "task", "jobs", "measured s", "model s");
  for (const auto& [task, q] : fit.per_task)
    std::printf("  %-12s %6d %12.3f %12.3f\n", task.c_str(), q.jobs, q.measured_s, q.predicted_s);
}

}  // namespace

void RegisterCalibrateCommand(CLI::App& app) {
  auto args = std::make_shared<CalibrateArgs>();
  CLI::App* cmd = app.add_subcommand("calibrate", "Fit the board cost model's ns-per-unit coefficients to this host");
  cmd->add_option("--episode-seconds", args->episode_seconds, "sim seconds per calibration flight")
      ->capture_default_str()
      ->check(CLI::Range(2.0, 600.0));
  cmd->add_option("--write-reference", args->write_reference,
                  "write the fit as the reference costs file (workers/board/profiles/reference_costs.yaml)");
  cmd->add_flag("--json", args->json, "print the fit as JSON");
  cmd->callback([args] { Run(*args); });
}

}  // namespace enavi::cli
