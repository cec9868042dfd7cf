// Micro-benchmarks of the perception module and eci on a cluttered synthetic view.
//   build/bin/bench_perception --benchmark_counters_tabular=true
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "navstack/eci/eci.h"
#include "navstack/perception/difference.h"
#include "navstack/perception/occupancy_map.h"
#include "tests/unit/perception/synthetic_depth.h"

namespace enavi::navstack {
namespace {

using testing::BoxAt;
using testing::CameraPose;
using testing::Scene;

// A forest-like view: ground plane, 60 pillars and 15 floating blocks within 12 m ahead.
const Scene& ClutteredScene() {
  static const Scene scene = [] {
    Scene s;
    s.planes.push_back({Eigen::Vector3d::UnitZ(), 0.0});
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> x(1.5, 14.0), y(-7.0, 7.0), w(0.2, 0.9), h(1.0, 6.0);
    for (int i = 0; i < 60; ++i) {
      const double height = h(rng), width = w(rng);
      s.boxes.push_back(BoxAt({x(rng), y(rng), 0.5 * height}, {width, width, height}));
    }
    for (int i = 0; i < 15; ++i) {
      s.boxes.push_back(BoxAt({x(rng), y(rng), 1.0 + h(rng) * 0.5}, {w(rng), w(rng), w(rng)}));
    }
    return s;
  }();
  return scene;
}

// The stream the stack reads: the 640x480 sensor decimated to 320x240.
const CameraIntrinsics kStream = CameraIntrinsics::DefaultStream();

// Frame i of a flight at 2 m/s through the scene at 1.5 m height, 30 Hz.
DepthFrame RenderFlightFrame(const CameraIntrinsics& k, int i) {
  const Eigen::Vector3d p(i * 2.0 / 30.0, 0.3 * std::sin(i * 0.1), 1.5);
  DepthFrame f = testing::RenderFrame(ClutteredScene(), k, CameraPose(p, 0.05 * std::sin(i * 0.2)), i);
  f.v_W = Eigen::Vector3d(2.0, 0.0, 0.0);
  return f;
}

// 30 frames (one second) of the stream.
const std::vector<DepthFrame>& Frames() {
  static const std::vector<DepthFrame> frames = [] {
    std::vector<DepthFrame> f;
    for (int i = 0; i < 30; ++i) f.push_back(RenderFlightFrame(kStream, i));
    return f;
  }();
  return frames;
}

void ReportPerUnit(benchmark::State& state, const WorkCounts& w, WorkUnit unit, const char* name) {
  const double n = static_cast<double>(w.Get(unit)) / static_cast<double>(state.iterations());
  state.counters[name] = n;
}

// Arg: decimation. 1 = the full 640x480 frame (min_pixels 50), 2 = the 320x240 stream the
// stack reads (min_pixels 12, the same solid angle).
void BM_Eci(benchmark::State& state) {
  const int decimation = static_cast<int>(state.range(0));
  const CameraIntrinsics k = CameraIntrinsics::Default().Decimated(decimation);
  const DepthFrame frame = RenderFlightFrame(k, 0);
  EciOptions options;
  if (decimation == 1) options.min_pixels = 50;
  const Eigen::Vector3d v_C(0.0, 0.0, 2.0);
  EciResult r;
  for (auto _ : state) {
    r = ComputeEci(frame.image, k, v_C, options);
    benchmark::DoNotOptimize(r.eci);
  }
  state.counters["eci"] = r.eci;
  state.counters["layers"] = r.layers;
  state.counters["px/s"] = benchmark::Counter(static_cast<double>(k.width) * k.height,
                                              benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(std::to_string(k.width) + "x" + std::to_string(k.height));
}
BENCHMARK(BM_Eci)->ArgName("decimation")->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

void BM_BackProject(benchmark::State& state) {
  PerceptionOptions p;
  p.stride = static_cast<int>(state.range(0));
  WorkCounts w;
  const DepthFrame& frame = Frames()[0];  // rendered before timing starts
  for (auto _ : state) benchmark::DoNotOptimize(BackProject(frame, kStream, p, &w));
  ReportPerUnit(state, w, WorkUnit::kBackProjection, "pixels");
}
BENCHMARK(BM_BackProject)->Arg(2)->Unit(benchmark::kMicrosecond);

// A map warmed up with the 30 frames, as in steady flight.
OccupancyMap WarmMap(double res, bool discretize = true) {
  MapOptions o;
  o.resolution = res;
  o.discretize_endpoints = discretize;
  OccupancyMap map(o);
  for (const DepthFrame& f : Frames()) map.Insert(f, kStream, {});
  return map;
}

// ComputeUpdate + Apply per frame: args = resolution in cm, stride, discretize endpoints,
// mapping max range in m.
void BM_MapUpdate(benchmark::State& state) {
  const CameraIntrinsics& k = kStream;
  const double res = state.range(0) / 100.0;
  PerceptionOptions p;
  p.stride = static_cast<int>(state.range(1));
  p.max_range = static_cast<double>(state.range(3));
  OccupancyMap map = WarmMap(res, state.range(2) != 0);
  WorkCounts w;
  std::size_t i = 0;
  for (auto _ : state) {
    map.Apply(map.ComputeUpdate(Frames()[i], k, p, &w), &w);
    i = (i + 1) % Frames().size();
  }
  ReportPerUnit(state, w, WorkUnit::kBackProjection, "pixels");
  ReportPerUnit(state, w, WorkUnit::kRayStep, "ray_steps");
  ReportPerUnit(state, w, WorkUnit::kVoxelUpdate, "voxel_updates");
}
BENCHMARK(BM_MapUpdate)
    ->ArgNames({"res_cm", "stride", "discretize", "range_m"})
    ->Args({10, 2, 1, 5})  // the defaults
    ->Args({10, 2, 0, 5})
    ->Args({10, 1, 1, 5})
    ->Args({10, 4, 1, 5})
    ->Args({10, 2, 1, 10})
    ->Args({20, 2, 1, 5})
    ->Args({30, 2, 1, 5})
    ->Args({50, 2, 1, 5})
    ->Unit(benchmark::kMillisecond);

// The two phases apart, at the default settings.
void BM_MapComputeUpdate(benchmark::State& state) {
  const CameraIntrinsics& k = kStream;
  const OccupancyMap map = WarmMap(0.1);
  WorkCounts w;
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(map.ComputeUpdate(Frames()[i], k, {}, &w));
    i = (i + 1) % Frames().size();
  }
  ReportPerUnit(state, w, WorkUnit::kRayStep, "ray_steps");
}
BENCHMARK(BM_MapComputeUpdate)->Unit(benchmark::kMillisecond);

void BM_MapApply(benchmark::State& state) {
  const CameraIntrinsics& k = kStream;
  OccupancyMap map = WarmMap(0.1);
  std::vector<MapUpdate> updates;
  for (const DepthFrame& f : Frames()) updates.push_back(map.ComputeUpdate(f, k, {}));
  WorkCounts w;
  std::size_t i = 0;
  for (auto _ : state) {
    map.Apply(updates[i], &w);
    i = (i + 1) % updates.size();
  }
  ReportPerUnit(state, w, WorkUnit::kVoxelUpdate, "voxel_updates");
}
BENCHMARK(BM_MapApply)->Unit(benchmark::kMillisecond);

void BM_SetResolution(benchmark::State& state) {
  OccupancyMap map = WarmMap(0.1);
  WorkCounts w;
  bool fine = true;
  for (auto _ : state) {
    map.SetResolution(fine ? 0.2 : 0.1, &w);
    fine = !fine;
  }
  ReportPerUnit(state, w, WorkUnit::kRayStep, "ray_steps");
  ReportPerUnit(state, w, WorkUnit::kVoxelUpdate, "voxel_updates");
}
BENCHMARK(BM_SetResolution)->Unit(benchmark::kMillisecond);

// 12 x 12 x 4 m around the vehicle at 0.1 m: 576k cells.
const Eigen::AlignedBox3d kBox(Eigen::Vector3d(-4.0, -6.0, 0.0), Eigen::Vector3d(8.0, 6.0, 4.0));

void BM_ExtractGrid(benchmark::State& state) {
  const OccupancyMap map = WarmMap(0.1);
  WorkCounts w;
  for (auto _ : state) benchmark::DoNotOptimize(map.ExtractGrid(kBox, &w));
  ReportPerUnit(state, w, WorkUnit::kGridCell, "cells");
  state.counters["leaves"] = static_cast<double>(map.num_leaves());
}
BENCHMARK(BM_ExtractGrid)->Unit(benchmark::kMillisecond);

// The alternative ExtractGrid does not use: one tree search per cell.
void BM_ExtractGridByQuery(benchmark::State& state) {
  const OccupancyMap map = WarmMap(0.1);
  const VoxelGrid shape = map.ExtractGrid(kBox);
  for (auto _ : state) {
    VoxelGrid grid = shape;
    for (int z = 0; z < grid.dims.z(); ++z)
      for (int y = 0; y < grid.dims.y(); ++y)
        for (int x = 0; x < grid.dims.x(); ++x) {
          const Eigen::Vector3i c(x, y, z);
          grid.cells[grid.Index(c)] = map.Query(grid.CenterOf(c));
        }
    benchmark::DoNotOptimize(grid.cells.data());
  }
}
BENCHMARK(BM_ExtractGridByQuery)->Unit(benchmark::kMillisecond);

void BM_Stats(benchmark::State& state) {
  const OccupancyMap map = WarmMap(0.1);
  for (auto _ : state) benchmark::DoNotOptimize(map.Stats(kBox));
}
BENCHMARK(BM_Stats)->Unit(benchmark::kMillisecond);

void BM_Difference(benchmark::State& state) {
  const CameraIntrinsics& k = kStream;
  WorkCounts w;
  DifferenceResult r;
  std::size_t i = 1;
  for (auto _ : state) {
    r = DetectDifference(Frames()[i - 1], Frames()[i], k, {}, &w);
    i = i % (Frames().size() - 1) + 1;
  }
  ReportPerUnit(state, w, WorkUnit::kWarpPixel, "pixels");
  state.counters["changed"] = r.changed_fraction;
}
BENCHMARK(BM_Difference)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace enavi::navstack

BENCHMARK_MAIN();
