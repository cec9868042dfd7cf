#pragma once
// Navigation methods as plug-ins (STYLE.md rule 13, after MuJoCo's engine plugins): a method is
// one MethodInfo of name, scheduler, tunables and factory, registered once by name. Every list a
// user sees (CLI choices, job validation, tables, bench_episode) reads the registry (registry.h).
//
// Adding a method: a folder under navstack/methods/ with a function returning its MethodInfo and
// a CMakeLists.txt calling enavi_add_method() (cmake/EnaviHelpers.cmake), and one add_subdirectory
// line in navstack/methods/CMakeLists.txt: the registry's list of built-ins is generated from those
// folders. A test or a tool may also RegisterMethod() at run time.

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "navstack/methods/navigator.h"
#include "navstack/runtime/executor.h"
#include "navstack/runtime/task.h"
#include "navstack/runtime/virtual_executor.h"

namespace enavi::navstack {

/// One parameter a job spec may override (STYLE.md rule 10: names and ranges).
struct MethodTunable {
  std::string name;  ///< e.g. "ego.latency_compensation"
  double min = 0, max = 0;
  double default_value = 0;
  bool integer = false;
  std::string help;
};

/// How the method's jobs share the board.
struct MethodScheduler {
  SchedulingPolicy policy = SchedulingPolicy::kGlobalEdf;
  /// Threads the jobs may use: 0 = all board cores.
  int threads = 0;
};

/// What the episode hands a method besides its tunables (ConfigureMethod copies it into the
/// MethodOptions the factory reads).
struct MethodSetup {
  std::uint64_t seed = 1;
  /// The frequency-adapter policy, loaded for methods with `uses_policy` (else null).
  std::shared_ptr<const rl::PolicyFile> policy;
  /// Record a training rollout (methods with `records_rollouts`).
  bool record_rollout = false;
  /// Decisions taken outside the method, or null (methods with `external_decisions`).
  rl::DecisionPort* decisions = nullptr;
  /// The job's navigation policy, loaded once for methods with `uses_nav_policy` (null: none given).
  std::shared_ptr<const rl::NavPolicyNet> nav_policy;
};

/// One flight of `enavi calibrate` (workers/board/calibration_flights.h): a scenario and overrides
/// of the method's tunables, chosen so that its units of work and its tasks' per-job overheads vary
/// independently enough to fit its cost family's prices.
struct MethodCalibrationFlight {
  std::string world;  ///< a scenario, "s1".."s5"
  std::map<std::string, double> overrides;
};

struct MethodInfo {
  std::string name;
  std::string summary;  ///< one line for --help and tables
  MethodScheduler scheduler;
  std::vector<MethodTunable> tunables;
  /// The code base its work counts come from, which prices them (reference_costs.yaml has one set
  /// of prices per family): the same work unit is different code in two code bases. Required:
  /// "navstack" if its jobs run our stack's code (perception, planning), else a family of its own,
  /// priced once `enavi calibrate --write-reference` has flown it (until then it flies with
  /// `cost: measured`).
  std::string cost_family;
  /// Its flights in `enavi calibrate`'s plan (the methods take turns, flight by flight); empty: one
  /// flight on each of s1-s5 at its defaults.
  std::vector<MethodCalibrationFlight> calibration;
  bool uses_policy = false;      ///< reads a frequency-adapter policy (--policy)
  bool uses_nav_policy = false;  ///< reads a navigation policy file (--policy, navstack/rl/nav_policy.h)
  /// Can take its decisions from outside, one at a time (EpisodeOptions::decisions: the Python
  /// environments).
  bool external_decisions = false;
  bool records_rollouts = false;  ///< can record a training rollout
  /// What each task's CPU is for this method (results' per-task utilisation), by TaskId.
  std::array<std::string, kTaskCount> task_labels = {"perception", "planning", "collision", "difference", "eci", "adapter"};
  /// The key of each navigation task's CPU in results (`task_cpu_util_pct.<key>`: tables, `enavi
  /// compare`, the dashboard), by TaskId: lower-case letters, digits and '_', distinct. A method
  /// whose tasks are other work than our stack's names them for what they are.
  std::array<std::string, kTaskCount> task_keys = {"perception", "planning", "collision", "difference", "eci", "adapter"};
  /// Checks the setup and sets the method's defaults of the common options (planner.*) before
  /// the overrides apply; optional.
  std::function<void(const MethodSetup&, MethodOptions*)> configure;
  /// Builds the method on `executor` from the common options and its tunables; the vehicle hovers
  /// at `initial` until its first plan.
  std::function<std::unique_ptr<Navigator>(const MethodOptions&, TaskExecutor*, const VehicleState&)> make;
};

}  // namespace enavi::navstack
