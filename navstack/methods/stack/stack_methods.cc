#include "navstack/methods/stack/stack_methods.h"

#include <stdexcept>
#include <vector>

#include "navstack/stack/nav_stack.h"

namespace enavi::navstack {

TaskRates FixedRates() {
  TaskRates r;
  r.f_per = 30.0;
  r.f_plan = 20.0;
  r.f_col = 0.0;
  r.collision_on_map_update = true;
  r.f_dif = 0.0;
  r.resolution = 0.1;
  return r;
}

TaskRates EnaviInitialRates() {
  TaskRates r;
  r.f_per = 10.0;
  r.f_plan = 0.0;  // planning on triggers: collision, difference, end of trajectory
  r.f_col = 5.0;
  r.collision_on_map_update = false;
  r.f_dif = 5.0;
  r.resolution = 0.5;  // the Resolution Adapter's coarsest level; it refines from there
  return r;
}

// Both methods of our stack turn on the spot when boxed in (NavStack::Scan) and reset the far map
// after a fruitless full turn.
MethodTunable ScanResetTunable() {
  return {"scan.reset_distance", 0.0, 50.0, NavStackOptions{}.scan_reset_distance, false,
          "after a full scan turn without a plan, forget occupied cells farther than this, m (0: never)"};
}

// The scenarios calibration flights rotate through, so that no resolution is tied to one scene.
const char* const kScenarios[] = {"s1", "s2", "s3", "s4", "s5"};

MethodInfo FixedMethod() {
  MethodInfo m;
  m.name = "fixed";
  m.summary = "our stack at fixed 30 Hz perception / 20 Hz planning timer / 0.1 m, no adaptation";
  m.scheduler = {SchedulingPolicy::kFifoNonPreemptive, 1};
  m.cost_family = "navstack";
  // Calibration: each level of E-Navi's ladder once, difference detection on some flights.
  const std::vector<double> ladder = ResolutionAdapterOptions{}.ladder;
  const double f_dif[] = {0, 15, 0, 30};
  for (std::size_t i = 0; i < ladder.size(); ++i)
    m.calibration.push_back({kScenarios[(i + 2) % 5], {{"map.resolution", ladder[i]}, {"rates.f_dif", f_dif[i % 4]}}});
  m.tunables = {
      {"rates.f_per", 1.0, 30.0, 30.0, false, "perception rate, Hz"},
      {"rates.f_plan", 0.0, 50.0, 20.0, false, "planning timer, Hz (0: triggered)"},
      {"rates.f_dif", 0.0, 30.0, 0.0, false, "difference detection rate, Hz"},
      {"map.resolution", 0.05, 1.0, 0.1, false, "map resolution, m"},
      ScanResetTunable(),
  };
  m.make = [](const MethodOptions& options, TaskExecutor* executor, const VehicleState& initial) {
    NavStackOptions o = StackOptionsFrom(options);
    o.rates = FixedRates();
    o.rates.f_per = options.Param("rates.f_per");
    o.rates.f_plan = options.Param("rates.f_plan");
    o.rates.f_dif = options.Param("rates.f_dif");
    o.rates.resolution = o.map.resolution = options.Param("map.resolution");
    o.scan_reset_distance = options.Param("scan.reset_distance");
    return std::unique_ptr<Navigator>(std::make_unique<NavStack>(o, executor, initial));
  };
  return m;
}

MethodInfo EnaviMethod() {
  MethodInfo m;
  m.name = "enavi";
  m.summary = "E-Navi: eci-driven map resolution and task frequencies under C1-C4, PPO policy";
  m.scheduler = {SchedulingPolicy::kGlobalEdf, 0};
  m.cost_family = "navstack";
  m.uses_policy = true;
  m.external_decisions = true;
  m.records_rollouts = true;
  // Calibration: once on each scenario with sampled actions, so that its adapter walks the
  // resolution ladder and the rates across the policy's grid.
  for (const char* world : kScenarios) m.calibration.push_back({world, {{"strategy.explore", 1}}});
  m.tunables = {
      {"strategy.explore", 0, 1, 0, true, "1 samples the policy's actions (training), 0 greedy"},
      {"strategy.least_load", 0, 1, 0, true,
       "1 runs the feasible action with the least CPU load instead of the policy's (an ablation: the constraints without the learned choice)"},
      {"strategy.f_adapt", 1.0, 30.0, 5.0, false, "strategy controller decisions per second, Hz"},
      {"resolution.step_lifetime", 0.5, 60.0, ResolutionAdapterOptions{}.step_lifetime, false,
       "each map refinement step expires this long after its trigger (the map goes one level coarser), sim s"},
      ScanResetTunable(),
  };
  m.configure = [](const MethodSetup& setup, MethodOptions*) {
    if (!setup.policy) throw std::invalid_argument("policy: method enavi needs a frequency-adapter policy");
  };
  m.make = [](const MethodOptions& options, TaskExecutor* executor, const VehicleState& initial) {
    NavStackOptions o = StackOptionsFrom(options);
    o.rates = EnaviInitialRates();
    StrategyOptions& strategy = o.strategy.emplace();
    strategy.policy = options.policy;
    strategy.seed = options.seed;
    strategy.record = options.record_rollout;
    strategy.decisions = options.decisions;
    strategy.mode = options.Param("strategy.explore") > 0 ? rl::ActMode::kSample : rl::ActMode::kGreedy;
    strategy.choice = options.Param("strategy.least_load") > 0 ? rl::ActionChoice::kLeastLoad : rl::ActionChoice::kPolicy;
    strategy.f_adapt = options.Param("strategy.f_adapt");
    strategy.resolution.step_lifetime = options.Param("resolution.step_lifetime");
    o.scan_reset_distance = options.Param("scan.reset_distance");
    return std::unique_ptr<Navigator>(std::make_unique<NavStack>(o, executor, initial));
  };
  return m;
}

}  // namespace enavi::navstack
