// Benchmarks of enavi::planning on a representative park: 12 x 12 x 4 m with scattered tree
// trunks and boxes (tests/unit/planning/planning_test_worlds.h), start and goal 10 m apart.
// Argument: grid resolution in mm (100 = 0.1 m, the baseline's resolution).

#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>

#include "navstack/planning/collision_check.h"
#include "navstack/planning/distance_field.h"
#include "navstack/planning/grid_astar.h"
#include "navstack/planning/inflated_occupancy.h"
#include "navstack/planning/planner.h"
#include "navstack/planning/rebound_optimizer.h"
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

// The rebound pipeline's map: occupancy packed into bits and dilated by the search clearance,
// the vehicle's radius and Ego-Planner's inflation, as Plan() builds it. Counter units_per_s:
// inflate_cell per CPU second (1e9 / units_per_s = its ns in reference_costs.yaml).
void BM_InflateGrid(benchmark::State& state) {
  const testing::AsciiWorld w = Park(state);
  const PlannerOptions o;
  WorkCounts work;
  for (auto _ : state) {
    work = WorkCounts{};
    const OccupancyBits bits(w.grid, &work);
    const InflatedOccupancy search(bits, o.robot_radius + o.search_margin, &work);
    const InflatedOccupancy collision(bits, o.robot_radius, &work);
    const InflatedOccupancy guide(bits, kEgoPlannerInflation, &work);
    benchmark::DoNotOptimize(guide.CellOccupied({0, 0, 0}));
  }
  SetWorkCounters(state, work);
  state.counters["units_per_s"] = benchmark::Counter(
      static_cast<double>(work.Get(WorkUnit::kInflateCell)), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_InflateGrid)->Arg(100)->Arg(200)->Unit(benchmark::kMicrosecond);

// The grid A* around the park's obstacles on the vehicle-radius inflation, across the park
// (start and goal 10 m apart, the straight line blocked). Counter units_per_s: astar_expansion
// per CPU second, bit look-ups included (1e9 / units_per_s = its ns in reference_costs.yaml).
void BM_GridAstar(benchmark::State& state) {
  const testing::AsciiWorld w = Park(state);
  const PlannerOptions o;
  const OccupancyBits bits(w.grid, nullptr);
  const InflatedOccupancy collision(bits, o.robot_radius, nullptr);
  Eigen::AlignedBox3d bounds = w.grid.Box();
  bounds.min().z() = o.min_altitude;
  WorkCounts work;
  for (auto _ : state) {
    work = WorkCounts{};
    const AstarResult r = GridAstar(collision, bounds, w.start, w.goal, &work);
    if (!r.ok()) state.SkipWithError("A* found no path across the park");
    benchmark::DoNotOptimize(r.path.data());
  }
  SetWorkCounters(state, work);
  state.counters["units_per_s"] = benchmark::Counter(
      static_cast<double>(work.Get(WorkUnit::kAstarExpansion)), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_GridAstar)->Arg(100)->Arg(200)->Unit(benchmark::kMillisecond);

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

// Console output, then the rebound / esdf replan time ratio at 0.1 m of this very run.
class ReplanRatioReporter : public benchmark::ConsoleReporter {
 public:
  ReplanRatioReporter() : ConsoleReporter(OO_None) {}
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.run_type != Run::RT_Iteration || r.error_occurred) continue;
      const std::string name = r.benchmark_name();
      if (name == "BM_Replan/mm:100/optimizer:0") esdf_ = {true, r};
      if (name == "BM_Replan/mm:100/optimizer:1") rebound_ = {true, r};
    }
    ConsoleReporter::ReportRuns(runs);
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    if (!esdf_.first || !rebound_.first) return;
    const Run& e = esdf_.second;
    const Run& b = rebound_.second;
    std::printf(
        "\nReplan at 0.1 m (BM_Replan/mm:100): esdf %.3f ms wall, %.3f ms CPU; rebound %.3f ms "
        "wall, %.3f ms CPU; rebound / esdf = %.3f wall, %.3f CPU\n",
        e.GetAdjustedRealTime(), e.GetAdjustedCPUTime(), b.GetAdjustedRealTime(),
        b.GetAdjustedCPUTime(), b.GetAdjustedRealTime() / e.GetAdjustedRealTime(),
        b.GetAdjustedCPUTime() / e.GetAdjustedCPUTime());
  }

 private:
  std::pair<bool, Run> esdf_{false, {}}, rebound_{false, {}};
};

}  // namespace
}  // namespace enavi::navstack

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  enavi::navstack::ReplanRatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
