// Benchmarks of enavi::planning on a representative park: 12 x 12 x 4 m with scattered tree
// trunks and boxes (tests/unit/planning/planning_test_worlds.h), start and goal 10 m apart.
// Argument: grid resolution in mm (100 = 0.1 m, the baseline's resolution).

#include <memory>

#include <benchmark/benchmark.h>

#include "navstack/planning/collision_check.h"
#include "navstack/planning/distance_field.h"
#include "navstack/planning/planner.h"
#include "tests/unit/planning/planning_test_worlds.h"

namespace enavi::navstack {
namespace {

testing::AsciiWorld Park(const benchmark::State& state) {
  return testing::ParkWorld(12.0, 4.0, state.range(0) / 1000.0, 40, 8, 7);
}

PlanRequest ParkRequest(const testing::AsciiWorld& w, std::uint32_t seed) {
  PlanRequest r;
  r.start.p = w.start;
  r.goal_W = w.goal;
  r.flight_bounds_W = w.grid.Box();
  r.grid = std::make_shared<const VoxelGrid>(w.grid);
  r.seed = seed;
  return r;
}

void SetWorkCounters(benchmark::State& state, const WorkCounts& work) {
  for (int i = 0; i < static_cast<int>(WorkUnit::kCount); ++i) {
    if (work.n[i] != 0) state.counters[std::string(kWorkUnitNames[i])] = static_cast<double>(work.n[i]);
  }
}

// Exact EDT of the whole grid.
void BM_DistanceTransform(benchmark::State& state) {
  const testing::AsciiWorld w = Park(state);
  WorkCounts work;
  for (auto _ : state) {
    work = WorkCounts{};
    DistanceField field(w.grid, &work);
    benchmark::DoNotOptimize(field.CellDistance({0, 0, 0}));
  }
  SetWorkCounters(state, work);
  state.counters["cells_per_s"] = benchmark::Counter(
      static_cast<double>(work.Get(WorkUnit::kDistanceCell)), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_DistanceTransform)->Arg(100)->Arg(200)->Arg(500)->Unit(benchmark::kMillisecond);

// A full replan from a given grid. esdf: EDT, search, B-spline optimisation on the field, time
// allocation; rebound: straight line, A*-guided rebound optimisation, time allocation.
void BM_Replan(benchmark::State& state) {
  const testing::AsciiWorld w = Park(state);
  RouteOmplLog(nullptr);
  PlannerOptions options;
  options.optimizer = static_cast<PlannerOptimizer>(state.range(1));
  state.SetLabel(ToString(options.optimizer));
  std::uint32_t seed = 0;
  WorkCounts work;
  for (auto _ : state) {
    const PlanResult r = Plan(ParkRequest(w, seed++ % 8), options);
    if (!r.ok()) state.SkipWithError(r.message.c_str());
    work += r.work;
  }
  for (auto& n : work.n) n /= static_cast<std::int64_t>(state.iterations());
  SetWorkCounters(state, work);
}
BENCHMARK(BM_Replan)
    ->ArgNames({"mm", "optimizer"})
    ->ArgsProduct({{100, 200, 500}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

// Collision check of a whole planned trajectory (~15 m) against the grid.
void BM_CheckTrajectory(benchmark::State& state) {
  const testing::AsciiWorld w = Park(state);
  RouteOmplLog(nullptr);
  const PlanResult r = Plan(ParkRequest(w, 1));
  if (!r.ok()) {
    state.SkipWithError(r.message.c_str());
    return;
  }
  WorkCounts work;
  for (auto _ : state) {
    work = WorkCounts{};
    const CollisionCheckResult c = CheckTrajectory(*r.trajectory, r.trajectory->start_time(),
                                                   r.trajectory->end_time(), w.grid, 0.3, &work);
    benchmark::DoNotOptimize(c.collides);
  }
  SetWorkCounters(state, work);
}
BENCHMARK(BM_CheckTrajectory)->Arg(100)->Arg(200)->Arg(500)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace enavi::navstack

BENCHMARK_MAIN();
