// `enavi calibrate`: fits the board cost model to this host (docs/design.md, "Time: two clocks").
#include <sched.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "server/cli/commands.h"
#include "workers/board/board_profile.h"
#include "workers/board/calibration_flights.h"
#include "workers/board/host_calibration.h"
#include "workers/emulation/board_emulation.h"
#include "workers/emulation/cgroup_manager.h"

namespace enavi::cli {
namespace {

struct CalibrateArgs {
  std::string write_reference;
  double episode_seconds = 15.0;
  bool json = false;
  // Host calibration file (emulated clock): where, whether to write it, or only check it.
  std::string calibration;
  bool no_store = false;
  bool status = false;
  bool probe = false;   // with --status: also measure the host's speed now
  std::string samples;  // CSV of every job sample, for analysis outside
};

// One row per job: task, method, host CPU ns, then every work unit's count.
void WriteSamplesCsv(const std::string& path, const std::vector<board::JobSample>& samples) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("calibrate: cannot write --samples " + path);
  out << "task,method,host_ns";
  for (std::string_view u : navstack::kWorkUnitNames) out << ',' << u;
  out << '\n';
  for (const board::JobSample& s : samples) {
    out << navstack::TaskName(s.task) << ',' << s.method << ',' << static_cast<std::int64_t>(s.host_cpu_s * 1e9);
    for (std::int64_t n : s.work.n) out << ',' << n;
    out << '\n';
  }
  if (!out.flush()) throw std::runtime_error("calibrate: cannot write --samples " + path);
}

// --- Host calibration file and board emulation table (emulated clock, docs/design.md, "Time: two clocks") ---

// Host CPUs an emulation may use: this process's CPUs minus what the simulator keeps.
double EmulationCpusFree() {
  cpu_set_t set;
  CPU_ZERO(&set);
  const double cpus = sched_getaffinity(0, sizeof(set), &set) == 0 ? CPU_COUNT(&set) : 1.0;
  return cpus - emulation::CgroupOptions{}.host_reserve_cpus;
}

nlohmann::json BoardTableJson(const board::HostCalibration& cal) {
  nlohmann::json rows = nlohmann::json::array();
  for (const std::string& id : board::KnownBoards()) {
    const emulation::BoardEmulation e = emulation::DescribeBoardEmulation(board::LoadBoard(id), cal, EmulationCpusFree());
    nlohmann::json wcet, p99;
    for (const auto& [task, s] : e.wcet_s) wcet[task] = s;
    for (const auto& [task, s] : e.p99_s) p99[task] = s;
    rows.push_back({{"board", e.board},
                    {"cores", e.cores},
                    {"speed_vs_host", e.speed_vs_host},
                    {"quota_cpus_k1", e.quota_cpus_k1},
                    {"min_dilation", e.min_dilation},
                    {"wcet_s", wcet},
                    {"p99_s", p99}});
  }
  return rows;
}

void PrintBoardTable(const board::HostCalibration& cal) {
  const char* tasks[] = {"perception", "planning", "collision", "difference", "eci", "adapter"};
  std::printf("boards on this host (speed %.3f x the reference core, %.2f host CPUs for emulations):\n",
              cal.relative_speed, EmulationCpusFree());
  std::printf("  %-6s %5s %8s %10s %6s   job ms, p99 / max:", "board", "cores", "speed", "quota k=1", "min k");
  for (const char* t : tasks) std::printf(" %13s", t);
  std::printf("\n");
  for (const std::string& id : board::KnownBoards()) {
    const emulation::BoardEmulation e = emulation::DescribeBoardEmulation(board::LoadBoard(id), cal, EmulationCpusFree());
    std::printf("  %-6s %5d %8.3f %10.2f %6s                     ", e.board.c_str(), e.cores, e.speed_vs_host,
                e.quota_cpus_k1, std::to_string(e.min_dilation).substr(0, 4).c_str());
    for (const char* t : tasks) {
      const auto it = e.wcet_s.find(t);
      if (it == e.wcet_s.end()) {
        std::printf(" %13s", "-");
      } else {
        char cell[32];
        std::snprintf(cell, sizeof cell, "%.1f/%.1f", 1e3 * e.p99_s.at(t), 1e3 * it->second);
        std::printf(" %13s", cell);
      }
    }
    if (e.speed_vs_host > 1.0)
      std::printf("  (%.0f %% faster than the host: dilation >= %.3f)", 100 * (e.speed_vs_host - 1), e.speed_vs_host);
    std::printf("\n");
  }
}

// Writes the host calibration unless --no-store; returns the path written (empty if none).
std::string StoreHostCalibration(const CalibrateArgs& args, const board::HostCalibration& cal) {
  if (args.no_store) return {};
  const std::string path = board::CalibrationPath(args.calibration);
  board::SaveHostCalibration(cal, path);
  return path;
}

// `enavi calibrate --status`: no flights; is the stored calibration usable here, and what it gives.
void RunStatus(const CalibrateArgs& args) {
  const board::CalibrationCheck check = board::CheckHostCalibration(board::CalibrationPath(args.calibration));
  if (args.json) {
    nlohmann::json j;
    j["path"] = check.path;
    j["valid"] = check.ok();
    j["message"] = check.message;
    if (check.calibration) {
      const board::HostCalibration& c = *check.calibration;
      j["relative_speed"] = c.relative_speed;
      j["cpu_model"] = c.cpu_model;
      j["kernel"] = c.kernel;
      j["date"] = c.date;
      j["reference_calibration_id"] = c.reference_calibration_id;
      j["probe_speed"] = c.probe_speed;
      if (check.ok()) j["boards"] = BoardTableJson(c);
      if (check.ok() && args.probe) {
        const board::SpeedProbe probe = board::ProbeHostSpeed();
        const board::SpeedDrift d = board::DriftSinceCalibration(c, probe.speed);
        nlohmann::json per_cpu = nlohmann::json::object();
        for (const auto& [cpu, s] : probe.per_cpu) per_cpu[std::to_string(cpu)] = s;
        j["probe"] = {{"speed", probe.speed}, {"per_cpu", per_cpu}, {"spread", probe.Spread()},
                      {"at_calibration", d.at_calibration}, {"drift", d.ratio - 1}, {"jobs", probe.jobs},
                      {"wall_s", probe.wall_s}};
      }
    }
    std::printf("%s\n", j.dump(2).c_str());
  } else if (check.ok()) {
    const board::HostCalibration& c = *check.calibration;
    std::printf("host calibration %s: valid (%s, kernel %s, %s, reference %s)\n", check.path.c_str(),
                c.cpu_model.c_str(), c.kernel.c_str(), c.date.c_str(), c.reference_calibration_id.c_str());
    PrintBoardTable(c);
    if (args.probe) {
      const board::SpeedProbe probe = board::ProbeHostSpeed();
      const board::DriftText text = board::DescribeDrift(c, probe);
      std::printf("%s; %s (%.1f s, %d jobs)\n", text.drift.c_str(), text.spread.c_str(), probe.wall_s, probe.jobs);
    }
  }
  if (!check.ok()) throw std::invalid_argument(check.message);
}

void Run(const CalibrateArgs& args) {
  if (args.status) return RunStatus(args);
  board::CalibrationOptions options;
  options.episode_seconds = args.episode_seconds;
  const std::size_t total = board::CalibrationPlan().size();
  std::size_t flown = 0;
  std::chrono::steady_clock::time_point start;  // of the first flight (the probe before it is no guide)
  if (!args.json) {
    std::fprintf(stderr, "calibrate: speed probe (%zu flights of %.0f s on each CPU)\n", board::SpeedProbePlan().size(),
                 board::kSpeedProbeSeconds);
    options.on_flight = [&](const board::CalibrationFlight& f) {
      if (flown == 0) start = std::chrono::steady_clock::now();
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const std::string eta =
          flown > 0 ? ", ETA " + std::to_string(static_cast<int>(elapsed / flown * (total - flown))) + " s" : "";
      std::string with;
      for (const auto& [name, value] : f.overrides) {
        char v[32];
        std::snprintf(v, sizeof v, "%g", value);
        with += (with.empty() ? " with " : ", ") + name + " " + v;
      }
      std::fprintf(stderr, "calibrate: [%zu/%zu%s] flying %s on %s%s for %.0f s\n", ++flown, total, eta.c_str(),
                   f.method.c_str(), f.world.c_str(), with.c_str(), args.episode_seconds);
    };
  }
  const board::CalibrationRun run = board::RunCalibration(options);
  const board::FamilyFits& fit = run.fit;
  if (!args.write_reference.empty()) board::WriteReferenceCosts(args.write_reference, run);
  if (!args.samples.empty()) WriteSamplesCsv(args.samples, run.samples);
  auto coefficient_json = [](const board::CoefficientFit& c) {
    nlohmann::json j = {{"ns", c.ns}, {"jobs", c.jobs}, {"share", c.share}};
    if (!c.zero_reason.empty()) j["zero_reason"] = c.zero_reason;
    return j;
  };
  auto quality_json = [](const board::TaskFitQuality& q) {
    return nlohmann::json{{"jobs", q.jobs},
                          {"r2", q.r2},
                          {"measured_s", q.measured_s},
                          {"predicted_s", q.predicted_s},
                          {"relative_residual", q.relative_residual()}};
  };
  nlohmann::json j;
  j["cpu"] = fit.costs.reference_cpu;
  j["samples"] = fit.samples;
  j["idle_jobs"] = fit.idle;
  j["r2"] = fit.r2;
  j["load_average"] = {{"before", run.load_before}, {"after", run.load_after}};
  j["relative_speed_vs_reference"] = run.relative_speed;
  j["probe_speed_vs_reference"] = run.host.probe_speed;
  j["reference_calibration_id"] = run.reference.calibration_id;
  const std::vector<std::string> unpriced = board::UnpricedFamilies(run.samples, run.reference);
  j["unpriced_families"] = unpriced;
  for (const auto& [family, f] : fit.fits) {
    nlohmann::json& fj = j["families"][family];
    fj["samples"] = f.samples;
    fj["r2"] = f.r2;
    for (const board::CoefficientFit& c : f.overheads) {
      fj["ns_per_job"][c.name] = c.ns;
      fj["overheads"][c.name] = coefficient_json(c);
    }
    for (const board::CoefficientFit& c : f.units) {
      fj["ns_per_unit"][c.name] = c.ns;
      fj["units"][c.name] = coefficient_json(c);
    }
    for (const board::TaskFitQuality& q : f.per_task) fj["tasks"][q.task] = quality_json(q);
    for (const board::TaskFitQuality& q : f.per_method_task) j["methods"][q.method][q.task] = quality_json(q);
  }
  for (const board::TaskFitQuality& q : run.reference_agreement) {
    nlohmann::json a = quality_json(q);
    a["reference_s"] = a["predicted_s"];
    a.erase("predicted_s");
    j["reference_agreement"][q.method][q.task] = a;
  }
  const board::HostCalibration& host = run.host;
  const std::string stored = StoreHostCalibration(args, host);
  j["host_calibration_file"] = stored;
  j["boards"] = BoardTableJson(host);
  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf("calibration of %s: %d jobs (%d idle: no work counted, priced 0, not fitted), R^2 %.3f, speed %.3f x "
              "the reference core (load %.2f -> %.2f)\n",
              fit.costs.reference_cpu.c_str(), fit.samples, fit.idle, fit.r2, run.relative_speed, run.load_before,
              run.load_after);
  std::printf("speed probe (%zu flights of %.0f s on each CPU, before the plan; what an emulated episode "
              "compares its own with): %.3f x the reference core\n",
              board::SpeedProbePlan().size(), board::kSpeedProbeSeconds, run.host.probe_speed);
  auto print_coefficient = [](const std::string& label, const board::CoefficientFit& c) {
    std::printf("  %-22s %12.4f %7d %7.1f%s%s\n", label.c_str(), c.ns, c.jobs, 100 * c.share,
                c.zero_reason.empty() ? "" : "  0: ", c.zero_reason.c_str());
  };
  auto print_quality = [](const board::TaskFitQuality& q) {
    std::printf("  %-12s %-9s %7d %7.3f %12.3f %12.3f %+8.1f%%\n", q.task.c_str(),
                q.method.empty() ? "all" : q.method.c_str(), q.jobs, q.r2, q.measured_s, q.predicted_s,
                100 * q.relative_residual());
  };
  auto print_quality_header = [] {
    std::printf("  %-12s %-9s %7s %7s %12s %12s %9s\n", "task", "method", "jobs", "R^2", "measured s", "model s",
                "residual");
  };
  for (const auto& [family, f] : fit.fits) {
    std::printf("cost family %s: %d jobs, R^2 %.3f\n", family.c_str(), f.samples, f.r2);
    std::printf("  %-22s %12s %7s %7s\n", "coefficient", "ns", "jobs", "time %");
    for (const board::CoefficientFit& c : f.overheads) print_coefficient("per job of " + c.name, c);
    for (const board::CoefficientFit& c : f.units) print_coefficient(c.name, c);
    print_quality_header();
    for (const board::TaskFitQuality& q : f.per_task) print_quality(q);
    for (const board::TaskFitQuality& q : f.per_method_task) print_quality(q);
  }
  std::printf("the reference costs (%s) against this host at speed %.3f (residual > 0: the virtual clock over-prices):\n",
              run.reference.calibration_id.c_str(), run.relative_speed);
  print_quality_header();
  for (const board::TaskFitQuality& q : run.reference_agreement) print_quality(q);
  for (const std::string& family : unpriced)
    std::printf("  cost family %s: not priced by the reference (the speed is measured on the others; "
                "--write-reference adds its prices)\n",
                family.c_str());
  PrintBoardTable(host);
  if (!stored.empty()) std::printf("host calibration written to %s\n", stored.c_str());
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
  cmd->add_option("--samples", args->samples, "also write every job's task, method, host CPU ns and work counts as CSV");
  cmd->add_option("--calibration", args->calibration,
                  "host calibration file to write or check (default: $ENAVI_CALIBRATION, else "
                  "$XDG_STATE_HOME/enavi/calibration.json or ~/.local/state/enavi/calibration.json)");
  cmd->add_flag("--no-store", args->no_store, "do not write the host calibration file");
  CLI::Option* status = cmd->add_flag(
      "--status", args->status, "fly nothing: check the stored host calibration (missing, stale) and print the board table");
  cmd->add_flag("--probe", args->probe,
                "with --status: also run the speed probe an emulated episode runs first (~2 s a CPU) and say how "
                "far this host's speed moved since the calibration")
      ->needs(status);
  cmd->callback([args] { Run(*args); });
}

}  // namespace enavi::cli
