#include "workers/board/calibration_flights.h"

#include <sched.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <stdexcept>
#include <utility>
#include <vector>

#include "navstack/adapt/action_grid.h"
#include "navstack/methods/registry.h"
#include "navstack/rl/nav_policy.h"
#include "navstack/rl/policy_io.h"
#include "workers/sim/episode.h"

namespace enavi::board {
namespace {

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

// The host calibration from this run's fit and job samples.
HostCalibration MakeHostCalibration(const FamilyFits& fit, double speed, const ReferenceCosts& reference,
                                    const std::vector<JobSample>& samples) {
  HostCalibration cal;
  cal.relative_speed = speed;
  cal.fitted = fit.costs.families;
  cal.samples = fit.samples;
  cal.r2 = fit.r2;
  cal.cpu_model = HostCpuModel();
  cal.kernel = HostKernel();
  cal.date = UtcNow();
  cal.reference_calibration_id = reference.calibration_id;
  std::map<std::string, std::vector<double>> times;
  for (const JobSample& s : samples) times[std::string(navstack::TaskName(s.task))].push_back(s.host_cpu_s);
  for (auto& [task, t] : times) cal.tasks[task] = SummariseTimes(std::move(t));
  return cal;
}

// The scenarios flights rotate through.
const char* const kScenarios[] = {"s1", "s2", "s3", "s4", "s5"};

// A policy file for the flights of methods that read one (E-Navi's). Calibration prices work, not decisions: a freshly
// initialised network costs what a trained one does. Removed when the run ends.
class ScratchPolicy {
 public:
  ScratchPolicy()
      : path_(Scratch("policy")), nav_path_(Scratch("nav-policy")) {
    navstack::rl::SavePolicyFile(path_, navstack::rl::MakeFrequencyPolicy(navstack::ActionGrid(), 1));
    // A learned method's work does not depend on its weights: an untrained network at the
    // default stream's size.
    navstack::rl::SaveNavPolicy(nav_path_, navstack::rl::MakeNavPolicy(320, 240, 1));
  }
  ~ScratchPolicy() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
    std::filesystem::remove(nav_path_, ec);
  }
  /// The file a method of `info` reads, or "".
  std::string For(const navstack::MethodInfo& info) const {
    return info.uses_policy ? path_ : info.uses_nav_policy ? nav_path_ : "";
  }

 private:
  static std::string Scratch(const std::string& what) {
    return (std::filesystem::temp_directory_path() / ("enavi-calibrate-" + what + "-" + std::to_string(getpid()) + ".json"))
        .string();
  }
  std::string path_, nav_path_;
};

double LoadAverage() {
  std::ifstream in("/proc/loadavg");
  double load = 0;
  in >> load;
  return load;
}

}  // namespace

std::vector<CalibrationFlight> CalibrationPlan() {
  // Each method's flights (its own, or one per scenario at its defaults), the methods taking turns.
  std::vector<std::pair<std::string, std::vector<navstack::MethodCalibrationFlight>>> flights;
  std::size_t longest = 0;
  for (const navstack::MethodInfo& m : navstack::Methods()) {
    std::vector<navstack::MethodCalibrationFlight> own = m.calibration;
    if (own.empty())
      for (const char* world : kScenarios) own.push_back({world, {}});
    longest = std::max(longest, own.size());
    flights.emplace_back(m.name, std::move(own));
  }
  std::vector<CalibrationFlight> plan;
  for (std::size_t i = 0; i < longest; ++i)
    for (const auto& [method, own] : flights)
      if (i < own.size()) plan.push_back({method, own[i].world, own[i].overrides});
  return plan;
}

namespace {

// Flies `flights` in this process, each `seconds` long, with every job's host CPU time measured.
std::vector<JobSample> FlyMeasured(const std::vector<CalibrationFlight>& flights, double seconds,
                                   const std::function<void(const CalibrationFlight&)>& on_flight) {
  std::vector<JobSample> samples;
  sim::EpisodeOptions episode;
  std::string method, family;  // of the flight in progress
  episode.job_observer = [&](navstack::TaskId task, const navstack::WorkCounts& work, double cpu) {
    samples.push_back({task, method, family, work, cpu});
  };
  const ScratchPolicy policy;
  for (const CalibrationFlight& flight : flights) {
    api::EpisodeSpec spec;
    spec.world = flight.world;
    spec.seed = 1;
    spec.board = "host";
    spec.cost = "measured";
    spec.timeout_s = seconds;
    spec.method = method = flight.method;
    const navstack::MethodInfo* info = navstack::FindMethod(flight.method);
    if (info == nullptr) throw std::logic_error("calibration plan names an unknown method " + flight.method);
    family = info->cost_family;
    spec.policy = policy.For(*info);
    spec.overrides = flight.overrides;
    if (on_flight) on_flight(flight);
    sim::RunEpisode(spec, episode);
  }
  return samples;
}

// Puts the calling thread's CPU affinity back as it was, however the probe ends.
class AffinityRestore {
 public:
  explicit AffinityRestore(const cpu_set_t& allowed) : allowed_(allowed) {}
  ~AffinityRestore() { sched_setaffinity(0, sizeof allowed_, &allowed_); }
  AffinityRestore(const AffinityRestore&) = delete;
  AffinityRestore& operator=(const AffinityRestore&) = delete;

 private:
  cpu_set_t allowed_;
};

}  // namespace

std::vector<CalibrationFlight> SpeedProbePlan() {
  // Each method at its own resolution and rates, on a world of its own: the work an emulated
  // episode does, every cost family.
  std::vector<CalibrationFlight> plan;
  for (const navstack::MethodInfo& m : navstack::Methods())
    plan.push_back({m.name, kScenarios[plan.size() % std::size(kScenarios)], {}});
  return plan;
}

SpeedProbe ProbeHostSpeed() {
  const auto start = std::chrono::steady_clock::now();
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  if (sched_getaffinity(0, sizeof allowed, &allowed) != 0)
    throw std::runtime_error(std::string("host speed probe: sched_getaffinity: ") + std::strerror(errno));
  const AffinityRestore restore(allowed);
  const ReferenceCosts reference = LoadReferenceCosts();
  SpeedProbe probe;
  double sum = 0;
  for (int cpu = 0; cpu < CPU_SETSIZE && static_cast<int>(probe.per_cpu.size()) < kMaxProbedCpus; ++cpu) {
    if (!CPU_ISSET(cpu, &allowed)) continue;
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(cpu, &one);
    if (sched_setaffinity(0, sizeof one, &one) != 0) continue;  // offline since: not a CPU to run on
    const std::vector<JobSample> samples = FlyMeasured(SpeedProbePlan(), kSpeedProbeSeconds, {});
    const double speed = RelativeSpeed(samples, reference);
    probe.per_cpu.emplace_back(cpu, speed);
    probe.jobs += static_cast<int>(samples.size());
    sum += speed;
  }
  if (probe.per_cpu.empty())
    throw std::runtime_error("host speed probe: no CPU of this thread's affinity set could be used");
  probe.speed = sum / static_cast<double>(probe.per_cpu.size());
  probe.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return probe;
}

CalibrationRun RunCalibration(const CalibrationOptions& options) {
  CalibrationRun run;
  run.load_before = LoadAverage();
  // First, in a process that has flown nothing yet, as an emulated episode probes: the drift is
  // one probe against another in the same conditions.
  const double probe_speed = ProbeHostSpeed().speed;
  run.samples = FlyMeasured(CalibrationPlan(), options.episode_seconds, options.on_flight);
  run.load_after = LoadAverage();
  run.fit = FitCostFamilies(run.samples);
  run.reference = LoadReferenceCosts();
  run.relative_speed = RelativeSpeed(run.samples, run.reference);
  run.reference_agreement = ReferenceAgreement(run.samples, run.reference, run.relative_speed);
  run.fit.costs.reference_cpu = HostCpuModel();
  char id[64];
  std::snprintf(id, sizeof id, "%ld-%d", static_cast<long>(std::time(nullptr)), run.fit.samples);
  run.fit.costs.calibration_id = id;
  run.host = MakeHostCalibration(run.fit, run.relative_speed, run.reference, run.samples);
  run.host.probe_speed = probe_speed;
  return run;
}

void WriteReferenceCosts(const std::string& path, const CalibrationRun& run) {
  const FamilyFits& fit = run.fit;
  utsname uts{};
  uname(&uts);
  char load[160];
  std::snprintf(load, sizeof load, "Host load average (1 min) %.2f before the flights, %.2f after.", run.load_before,
                run.load_after);
  std::string comment = "Nanoseconds per job of each task and per work unit on the reference core, fitted by\n"
                        "`enavi calibrate --write-reference` on " + fit.costs.reference_cpu + " (" + uts.release +
                        "), R^2 " + std::to_string(fit.r2) + " over " + std::to_string(fit.samples) + " jobs of " +
                        std::to_string(CalibrationPlan().size()) + " flights.\n" + load + "\n";
  for (const auto& [family, f] : fit.fits) {
    comment += family + ": R^2 " + std::to_string(f.r2) + " over " + std::to_string(f.samples) + " jobs.\n";
    for (const std::vector<CoefficientFit>* group : {&f.overheads, &f.units})
      for (const CoefficientFit& c : *group)
        if (!c.zero_reason.empty())
          comment += family + ": " + (group == &f.units ? "" : "per job of ") + c.name + " = 0: " + c.zero_reason + "\n";
  }
  comment += "Prices are this host's fit times its speed against the reference it replaces (" +
             std::to_string(run.relative_speed) + ", id " + run.reference.calibration_id +
             "): a new fit moves prices between units,\ntasks and families, not the reference core the board "
             "profiles' per_core_speed is relative to.\n";
  ReferenceCosts costs = fit.costs;
  for (auto& [family, c] : costs.families) c = Scaled(c, run.relative_speed);
  std::ofstream out(path);
  out << ReferenceCostsYaml(costs, comment);
  if (!out) throw std::runtime_error("cannot write " + path);
}

}  // namespace enavi::board
