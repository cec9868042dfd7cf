// `enavi bench ...`: measured figures of the farm's building blocks, as a table or JSON.
#include <cstdio>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "server/cli/commands.h"
#include "workers/sim/raycast_bench.h"
#include "worlds/mesh.h"
#include "worlds/resolve.h"

namespace enavi::cli {
namespace {

struct RaycastArgs {
  std::string world = "s2";
  std::uint64_t seed = 1;
  int frames = 60;
  int bullet_frames = 10;
  bool json = false;
};

void RunRaycast(const RaycastArgs& args) {
  worlds::WorldRequest request;
  request.world = args.world;
  request.seed = args.seed;
  const worlds::World world = worlds::ResolveWorld(request);
  sim::RaycastBenchOptions options;
  options.frames = args.frames;
  options.bullet_frames = args.bullet_frames;
  const sim::RaycastBenchResult r =
      sim::RunRaycastBench(worlds::BuildWorldMesh(world), world.start, world.goal, options);
  nlohmann::json j = sim::ToJson(r);
  j["world"] = args.world;
  j["seed"] = args.seed;
  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf("raycast: %s seed %llu, %zu triangles, %d frames of %dx%d (%d also by Bullet)\n",
              args.world.c_str(), static_cast<unsigned long long>(args.seed), r.triangles, r.frames, r.width,
              r.height, r.bullet_frames);
  std::printf("  embree (%s)        %8.2f Mrays/s per core\n", r.embree_mode.c_str(), r.embree_mrays_per_s_per_core);
  std::printf("  bullet rayTest          %8.2f Mrays/s per core\n", r.bullet_mrays_per_s_per_core);
  std::printf("  speedup vs bullet       %8.1f x\n", r.speedup_vs_bullet);
  std::printf("  max depth disagreement  %8.6f m interior pixels, %.3f m incl. %lld grazing-edge pixels of %lld\n",
              r.max_depth_disagreement_interior_m, r.max_depth_disagreement_m,
              static_cast<long long>(r.disagreeing_pixels + r.one_sided_pixels),
              static_cast<long long>(r.both_hit_pixels));
}

}  // namespace

void RegisterBenchCommands(CLI::App& app) {
  CLI::App* bench = app.add_subcommand("bench", "Measured figures of the farm's building blocks");
  bench->require_subcommand(1);

  auto raycast = std::make_shared<RaycastArgs>();
  CLI::App* rc = bench->add_subcommand(
      "raycast", "Depth frames along the start-goal line rendered by Embree and by Bullet rayTest");
  rc->add_option("--world", raycast->world, "world to render (s1..s5, forest, empty, FILE)")->capture_default_str();
  rc->add_option("--seed", raycast->seed, "world seed")->capture_default_str();
  rc->add_option("--frames", raycast->frames, "Embree frames")->capture_default_str()->check(CLI::Range(1, 10000));
  rc->add_option("--bullet-frames", raycast->bullet_frames, "of those, frames also rendered by Bullet")
      ->capture_default_str()
      ->check(CLI::Range(0, 10000));
  rc->add_flag("--json", raycast->json, "print the figures as JSON");
  rc->callback([raycast] { RunRaycast(*raycast); });
}

}  // namespace enavi::cli
