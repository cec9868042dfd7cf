// Micro-benchmarks of enavi::sim: depth rendering (Embree modes, Bullet reference) on a
// cluttered synthetic park, and quadrotor physics steps.

#include <memory>
#include <vector>

#include <benchmark/benchmark.h>

#include "tests/unit/sim/mesh_builders.h"
#include "workers/sim/bullet_raycaster.h"
#include "workers/sim/depth_camera.h"
#include "workers/sim/quadrotor.h"
#include "workers/sim/static_world.h"

namespace enavi::sim {
namespace {

const worlds::TriangleMesh& Park() {
  static const worlds::TriangleMesh mesh = testing::MakeClutteredPark(2024);
  return mesh;
}

// Camera poses along the free corridor of the park, looking down it (+x).
std::vector<Eigen::Isometry3d> CorridorPoses(int n) {
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < n; ++i) {
    Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
    X_WB.translation() = Eigen::Vector3d(-28.0 + 56.0 * i / (n - 1), 0.0, 1.5);
    poses.push_back(CameraPoseInWorld(X_WB, navstack::VehicleParams{}));
  }
  return poses;
}

void BM_EmbreeRender(benchmark::State& state) {
  static const EmbreeScene scene(Park());
  const DepthCamera camera(navstack::CameraIntrinsics::Default(), DepthNoise{},
                           static_cast<EmbreeRayMode>(state.range(0)));
  const std::vector<Eigen::Isometry3d> poses = CorridorPoses(60);
  navstack::DepthImage image;
  std::size_t i = 0;
  for (auto _ : state) {
    camera.Render(scene, poses[i++ % poses.size()], &image);
    benchmark::DoNotOptimize(image.data.data());
  }
  const double rays = static_cast<double>(image.data.size()) * state.iterations();
  state.counters["rays_per_s"] = benchmark::Counter(rays, benchmark::Counter::kIsRate);
  state.counters["triangles"] = static_cast<double>(scene.triangle_count());
  state.SetLabel(ToString(camera.mode()));
}
BENCHMARK(BM_EmbreeRender)
    ->Arg(static_cast<int>(EmbreeRayMode::kSingle))
    ->Arg(static_cast<int>(EmbreeRayMode::kPacket4))
    ->Arg(static_cast<int>(EmbreeRayMode::kPacket8))
    ->Arg(static_cast<int>(EmbreeRayMode::kPacket16))
    ->Arg(static_cast<int>(EmbreeRayMode::kStream))
    ->Unit(benchmark::kMillisecond);

void BM_EmbreeRenderWithNoise(benchmark::State& state) {
  static const EmbreeScene scene(Park());
  const DepthCamera camera(navstack::CameraIntrinsics::Default(), DepthNoise{0.002});
  const std::vector<Eigen::Isometry3d> poses = CorridorPoses(60);
  navstack::DepthImage image;
  std::uint64_t i = 0;
  for (auto _ : state) {
    camera.Render(scene, poses[i % poses.size()], &image, i);
    ++i;
    benchmark::DoNotOptimize(image.data.data());
  }
  const double rays = static_cast<double>(image.data.size()) * state.iterations();
  state.counters["rays_per_s"] = benchmark::Counter(rays, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_EmbreeRenderWithNoise)->Unit(benchmark::kMillisecond);

void BM_BulletRender(benchmark::State& state) {
  static const auto world = std::make_shared<const StaticCollisionWorld>(Park());
  BulletRayCaster caster(world, navstack::CameraIntrinsics::Default());
  const std::vector<Eigen::Isometry3d> poses = CorridorPoses(60);
  navstack::DepthImage image;
  std::size_t i = 0;
  for (auto _ : state) {
    caster.Render(poses[i++ % poses.size()], &image);
    benchmark::DoNotOptimize(image.data.data());
  }
  const double rays = static_cast<double>(image.data.size()) * state.iterations();
  state.counters["rays_per_s"] = benchmark::Counter(rays, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BulletRender)->Unit(benchmark::kMillisecond);

void BM_EmbreeSceneBuild(benchmark::State& state) {
  for (auto _ : state) {
    EmbreeScene scene(Park());
    benchmark::DoNotOptimize(&scene);
  }
  state.counters["triangles"] = static_cast<double>(Park().triangle_count());
}
BENCHMARK(BM_EmbreeSceneBuild)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_StaticCollisionWorldBuild(benchmark::State& state) {
  for (auto _ : state) {
    StaticCollisionWorld world(Park());
    benchmark::DoNotOptimize(&world);
  }
}
BENCHMARK(BM_StaticCollisionWorldBuild)->Unit(benchmark::kMillisecond);

// One 1 kHz physics step, hovering in the park at height range(0) cm (low: the vehicle's box
// overlaps ground triangles, so the mesh narrow phase runs every step).
void BM_QuadrotorStep(benchmark::State& state) {
  static const auto world = std::make_shared<const StaticCollisionWorld>(Park());
  const double z = state.range(0) * 0.01;
  QuadrotorSim sim(world, QuadrotorOptions{}, {0.0, 0.0, z}, 0.0);
  for (auto _ : state) {
    sim.Step();
  }
  benchmark::DoNotOptimize(sim.State());
  state.counters["steps_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_QuadrotorStep)->Arg(150)->Arg(10);  // 1.5 m; 0.1 m (ground within reach)

void BM_QuadrotorConstruct(benchmark::State& state) {
  static const auto world = std::make_shared<const StaticCollisionWorld>(Park());
  for (auto _ : state) {
    QuadrotorSim sim(world, QuadrotorOptions{}, {0.0, 0.0, 1.5}, 0.0);
    benchmark::DoNotOptimize(&sim);
  }
}
BENCHMARK(BM_QuadrotorConstruct)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace enavi::sim

BENCHMARK_MAIN();
