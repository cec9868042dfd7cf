// Prints RunRaycastBench's JSON for the synthetic cluttered park (the generated worlds plug in
// through `enavi bench raycast --world ...`). Usage: bench_sim_raycast [frames] [bullet_frames]

#include <cstdlib>
#include <iostream>

#include "tests/unit/sim/mesh_builders.h"
#include "workers/sim/raycast_bench.h"

int main(int argc, char** argv) {
  using namespace enavi::sim;
  RaycastBenchOptions options;
  if (argc > 1) options.frames = std::atoi(argv[1]);
  if (argc > 2) options.bullet_frames = std::atoi(argv[2]);
  options.compare_modes = {EmbreeRayMode::kSingle, EmbreeRayMode::kPacket4,
                           EmbreeRayMode::kPacket8, EmbreeRayMode::kStream};
  const enavi::worlds::TriangleMesh park = testing::MakeClutteredPark(2024);
  const RaycastBenchResult result =
      RunRaycastBench(park, {-28.0, 0.0, 1.5}, {28.0, 0.0, 1.5}, options);
  std::cout << ToJson(result).dump(2) << "\n";
  return 0;
}
