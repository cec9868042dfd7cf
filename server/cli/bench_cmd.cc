// `enavi bench ...`: measured figures of the farm's building blocks, as a table or JSON.
#include <cstdio>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "server/bench/raycast_bench.h"
#include "server/bench/throttle_bench.h"
#include "server/cli/commands.h"
#include "server/cli/registry_help.h"
#include "workers/board/board_profile.h"
#include "workers/board/host_calibration.h"
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
  bench::RaycastBenchOptions options;
  options.frames = args.frames;
  options.bullet_frames = args.bullet_frames;
  const bench::RaycastBenchResult r =
      bench::RunRaycastBench(worlds::BuildWorldMesh(world), world.start, world.goal, options);
  nlohmann::json j = bench::ToJson(r);
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

// --- `enavi bench throttle`: does the cgroup emulation of a board slow a workload as it should?

struct ThrottleArgs {
  std::string board = "tx2";
  double dilation = 0.0;  // 0: the smallest that fits the host
  std::int64_t period_us = 20'000;
  double work_seconds = 1.0;
  bool deadline = false;
  bool primary_only = false;
  std::string calibration;
  bool json = false;
};

void RunThrottle(const ThrottleArgs& args) {
  const board::BoardProfile profile = board::LoadBoard(args.board);
  // The board's speed relative to THIS host; without a valid calibration the bench still tests
  // the throttle, taking this host for the reference core, and says so.
  double host_speed = 1.0;
  std::string speed_source;
  const board::CalibrationCheck check = board::CheckHostCalibration(board::CalibrationPath(args.calibration));
  if (check.ok()) {
    host_speed = check.calibration->relative_speed;
    speed_source = "host calibration " + check.path;
  } else {
    speed_source = "no valid host calibration (" + check.message + "): this host taken as the reference core";
  }
  const double speed = profile.is_host ? 1.0 : profile.per_core_speed / host_speed;
  bench::ThrottleBenchOptions options;
  options.dilation = args.dilation;
  options.period_us = args.period_us;
  options.work_seconds = args.work_seconds;
  options.deadline_servers = args.deadline;
  options.extra_phases = !args.primary_only;
  const bench::ThrottleBenchResult r =
      bench::RunThrottleBench(args.board, {profile.cores, std::min(1.0, speed)}, options);
  if (!r.ok) throw std::invalid_argument("bench throttle: " + r.message);
  nlohmann::json j = bench::ToJson(r);
  j["speed_source"] = speed_source;
  if (args.json) {
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf("throttle: %s (%d cores x %.3f of a host core, dilation %.2f, %s): %d thread(s) expected %.3f x, "
              "measured %.3f x, error %+.1f %%\n",
              r.board.c_str(), r.quota.cores, r.quota.core_speed, r.quota.dilation, r.mode.c_str(),
              r.phases.front().threads, r.expected_slowdown, r.measured_slowdown, 100.0 * r.relative_error);
  for (std::size_t i = 1; i < r.phases.size(); ++i) {
    const bench::ThrottlePhase& p = r.phases[i];
    std::printf("  %-24s %2d thread(s): expected %.3f x, measured %.3f x, error %+.1f %% (worst thread %+.1f %%)\n",
                p.name.c_str(), p.threads, p.expected_slowdown, p.measured_slowdown, 100.0 * p.relative_error,
                100.0 * p.max_thread_error);
  }
  std::printf("  speed: %s\n", speed_source.c_str());
}

}  // namespace

void RegisterBenchCommands(CLI::App& app) {
  CLI::App* bench = app.add_subcommand("bench", "Measured figures of the farm's building blocks");
  bench->require_subcommand(1);

  auto raycast = std::make_shared<RaycastArgs>();
  CLI::App* rc = bench->add_subcommand(
      "raycast", "Depth frames along the start-goal line rendered by Embree and by Bullet rayTest");
  rc->add_option("--world", raycast->world, "world to render: FILE or a scenario:" + ScenariosHelp())->capture_default_str();
  rc->add_option("--seed", raycast->seed, "world seed")->capture_default_str();
  rc->add_option("--frames", raycast->frames, "Embree frames")->capture_default_str()->check(CLI::Range(1, 10000));
  rc->add_option("--bullet-frames", raycast->bullet_frames, "of those, frames also rendered by Bullet")
      ->capture_default_str()
      ->check(CLI::Range(0, 10000));
  rc->add_flag("--json", raycast->json, "print the figures as JSON");
  rc->callback([raycast] { RunRaycast(*raycast); });

  auto throttle = std::make_shared<ThrottleArgs>();
  CLI::App* th = bench->add_subcommand(
      "throttle", "A fixed CPU-bound workload unthrottled and under the cgroup emulation of a board (root)");
  th->add_option("--board", throttle->board, "board to emulate")
      ->capture_default_str()
      ->check(CLI::IsMember(board::KnownBoards()));
  th->add_option("--dilation", throttle->dilation, "1 sim second = K wall seconds (default: smallest that fits)")
      ->check(CLI::Range(1.0, 100.0));
  th->add_option("--period-us", throttle->period_us, "CFS bandwidth period, us")
      ->capture_default_str()
      ->check(CLI::Range(1000, 1000000));
  th->add_option("--work-seconds", throttle->work_seconds, "host CPU seconds of work per thread")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 60.0));
  th->add_flag("--deadline", throttle->deadline, "SCHED_DEADLINE speed servers instead of per-thread cgroup quotas");
  th->add_flag("--primary-only", throttle->primary_only, "only the one-thread-per-board-core phase");
  th->add_option("--calibration", throttle->calibration, "host calibration file (default: see enavi calibrate)");
  th->add_flag("--json", throttle->json, "print the figures as JSON");
  th->callback([throttle] { RunThrottle(*throttle); });
}

}  // namespace enavi::cli
