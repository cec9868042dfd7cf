// Prints RunRaycastBench's JSON for the synthetic cluttered park (the generated worlds plug in
// through `enavi bench raycast --world ...`). Usage: bench_sim_raycast [frames] [bullet_frames]

#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <string>

#include "server/bench/raycast_bench.h"
#include "tests/unit/sim/mesh_builders.h"

namespace {

int ParseCount(const char* arg, const char* name) {
  char* end = nullptr;
  const long v = std::strtol(arg, &end, 10);
  if (end == arg || *end != '\0' || v < 0 || v > 100000)
    throw std::invalid_argument(std::string(name) + ": expected a count in [0, 100000], got '" + arg + "'");
  return static_cast<int>(v);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace enavi::sim;
  using namespace enavi::bench;
  try {
    if (argc > 3) throw std::invalid_argument("usage: bench_sim_raycast [frames] [bullet_frames]");
    RaycastBenchOptions options;
    if (argc > 1) options.frames = ParseCount(argv[1], "frames");
    if (argc > 2) options.bullet_frames = ParseCount(argv[2], "bullet_frames");
    options.compare_modes = {EmbreeRayMode::kSingle, EmbreeRayMode::kPacket4,
                             EmbreeRayMode::kPacket8, EmbreeRayMode::kStream};
    const enavi::worlds::TriangleMesh park = testing::MakeClutteredPark(2024);
    const RaycastBenchResult result =
        RunRaycastBench(park, {-28.0, 0.0, 1.5}, {28.0, 0.0, 1.5}, options);
    std::cout << ToJson(result).dump(2) << "\n";
  } catch (const std::invalid_argument& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
