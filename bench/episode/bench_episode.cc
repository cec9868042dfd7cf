// bench_episode: whole-episode throughput and where an episode's host CPU goes.
//
//   bench_episode [--world ID]... [--board ID]... [--method ID] [--param k=v]... [--set k=v]...
//                 [--seed N] [--no-replay] [--turbulence LEVEL] [--odometry-noise PRESET]
//   (default: --world s1 --world s2 --board host --board tx2 --method baseline --seed 1)
//
// --param sets world parameters, --set the episode's tunables (as `enavi fly --set`, e.g.
// camera.decimation=1 for the full 640x480 frame).
//
// For each world x board it flies one episode (virtual clock, cost model) and prints one JSON
// object with:
//   - sim seconds per wall second (and per host-CPU second of the episode's thread);
//   - the episode's host CPU split: navstack jobs (the four navigation tasks' code and commits,
//     as the executor measures them: TaskStats.host_cpu_s, seen through the job observer) vs
//     everything else (rendering, eci for the metrics, physics, controller, executor bookkeeping,
//     recording), as share_outside_navstack (goal <= 10 %);
//   - per-frame figures from the same run: eci per frame, map update per frame (0.1 m),
//     replan and collision-check time (mean host CPU per job);
//   - a replay of the flown path without the navstack (same world, camera, physics and
//     controller, tracking the recorded path) that times rendering, eci, physics and controller
//     separately, so the CPU outside the navstack can be attributed;
//   - for a world with movers, the price of the movers: the same world without them flown too,
//     and the replay of the mover flight's path once with the movers (moved per physics step
//     and per frame) and once without, as ratios (movers_vs_static; issue 45 asks for <= 1.2);
//   - with --turbulence or --odometry-noise, the price of the air and the odometry: the wind
//     field and the odometry noise stepped alone as often as the episode stepped them (host CPU
//     per physics step, against the episode's), and the same episode flown in still air with
//     perfect odometry (air_vs_still).
// Host CPU is the calling thread's CPU time (clock_gettime(CLOCK_THREAD_CPUTIME_ID)): immune to
// other processes' load; wall-clock rates are not, so run on a quiet machine.
#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "navstack/methods/registry.h"
#include "navstack/common/cpu_time.h"
#include "navstack/control/controller.h"
#include "navstack/eci/eci.h"
#include "workers/sim/depth_camera.h"
#include "workers/sim/episode.h"
#include "workers/sim/episode_config.h"
#include "workers/sim/episode_movers.h"
#include "workers/sim/odometry_noise.h"
#include "workers/sim/quadrotor.h"
#include "workers/sim/wind.h"
#include "worlds/resolve.h"

namespace enavi {
namespace {

using navstack::TaskId;
using navstack::ThreadCpuSeconds;

double ProcessCpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double WallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

bool HasWork(const navstack::WorkCounts& w) {
  return std::any_of(w.n.begin(), w.n.end(), [](std::int64_t c) { return c != 0; });
}

// Per task: jobs seen, jobs that did work, host CPU of code + commit.
struct TaskCpu {
  std::int64_t jobs = 0, jobs_with_work = 0;
  double cpu_s = 0, cpu_with_work_s = 0;
};

struct Replay {
  double frames = 0, steps = 0, control_updates = 0;
  double render_s = 0, eci_s = 0, physics_s = 0, controller_s = 0, total_s = 0;
};

// The episode loop without the navstack: the controller tracks the recorded path (linear
// interpolation of the 10 Hz series) with physics at 1 kHz, and a depth frame and its eci at
// f_sen are rendered from the recorded path (level, heading along the recorded velocity), so the
// views match the episode's even where the replayed vehicle strays or touches something.
// With `with_movers` the world's movers move as in an episode (kinematic bodies every step, the
// moving scene every frame); without, the static world alone is replayed.
Replay ReplayWithoutNavstack(const api::EpisodeSpec& spec, const sim::PreparedWorld& world,
                             const api::EpisodeResult& flown, bool with_movers = true) {
  const sim::EpisodeConfig config = sim::MakeEpisodeConfig(spec);
  const navstack::VehicleParams vehicle;
  const sim::DepthCamera camera(config.nav.camera, config.noise);
  sim::QuadrotorOptions quad_options;
  quad_options.vehicle = vehicle;
  const Eigen::Vector3d to_goal = world.world.goal - world.world.start;
  const double goal_heading = std::atan2(to_goal.y(), to_goal.x());
  sim::QuadrotorSim quad(world.collision, quad_options, world.world.start, goal_heading);
  std::optional<sim::EpisodeMovers> movers;
  if (with_movers && world.movers) movers.emplace(world.movers, world.scene, &quad);
  navstack::Controller controller(vehicle);
  const api::TimeSeries& s = flown.series;
  auto recorded = [&](double t) {
    navstack::TrajectorySample ref;
    const double u = std::clamp(t / 0.1, 0.0, static_cast<double>(s.size() - 1));
    const std::size_t i = std::min(static_cast<std::size_t>(u), s.size() - 1), j = std::min(i + 1, s.size() - 1);
    const double f = u - static_cast<double>(i);
    for (int d = 0; d < 3; ++d) {
      ref.p[d] = (1 - f) * s.position[i][d] + f * s.position[j][d];
      ref.v[d] = (1 - f) * s.velocity[i][d] + f * s.velocity[j][d];
    }
    ref.yaw = ref.v.head<2>().norm() > 0.2 ? std::atan2(ref.v.y(), ref.v.x()) : goal_heading;
    return ref;
  };

  Replay r;
  const double dt = quad_options.dt, frame_dt = 1.0 / config.nav.f_sen;
  const long steps = std::lround(flown.sim_time_s / dt);
  double next_frame_t = 0;
  navstack::DepthImage image;
  const double total0 = ThreadCpuSeconds();
  for (long k = 0; k < steps; ++k) {
    const double t = static_cast<double>(k) * dt;
    const navstack::VehicleState state = quad.State();
    const navstack::TrajectorySample ref = recorded(t);
    if (t >= next_frame_t - 1e-9) {
      next_frame_t += frame_dt;
      Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
      X_WB.linear() = Eigen::AngleAxisd(ref.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      X_WB.translation() = ref.p;
      const Eigen::Isometry3d X_WC = sim::CameraPoseInWorld(X_WB, vehicle);
      const double c0 = ThreadCpuSeconds();
      const std::uint64_t noise_seed = spec.seed * 1000003ULL + static_cast<std::uint64_t>(r.frames);
      if (movers) camera.Render(movers->SceneAt(t), X_WC, &image, noise_seed);
      else camera.Render(*world.scene, X_WC, &image, noise_seed);
      const double c1 = ThreadCpuSeconds();
      navstack::ComputeEci(image, config.nav.camera, X_WC.linear().transpose() * ref.v, navstack::EciOptions{});
      const double c2 = ThreadCpuSeconds();
      r.render_s += c1 - c0;
      r.eci_s += c2 - c1;
      ++r.frames;
    }
    if (k % 5 == 0) {
      const double c0 = ThreadCpuSeconds();
      quad.SetCommand(controller.Update(state, ref));
      r.controller_s += ThreadCpuSeconds() - c0;
      ++r.control_updates;
    }
    const double c0 = ThreadCpuSeconds();
    if (movers) movers->PoseBodies(t, &quad);
    quad.Step();
    r.physics_s += ThreadCpuSeconds() - c0;
    ++r.steps;
  }
  r.total_s = ThreadCpuSeconds() - total0;
  return r;
}

// What wind and odometry noise cost: each model stepped alone as often as the episode stepped it
// (the wind every physics step at the flight's altitude and speed, the odometry's error at every
// frame and applied every step), and the same episode in still air with perfect odometry.
nlohmann::json PriceOfTheAir(const api::EpisodeSpec& spec, const sim::PreparedWorld& world,
                             const api::EpisodeResult& result, double episode_cpu_s) {
  const sim::EpisodeOptions defaults;
  const long steps = std::lround(result.sim_time_s / defaults.physics_dt);
  const Eigen::Vector3d v_W(1.8, 0.0, 0.0);  // cruise
  double wind_s = 0, odometry_s = 0;
  if (spec.wind.Active()) {
    sim::WindField air(spec.wind, defaults.physics_dt, spec.seed);
    Eigen::Vector3d sink = Eigen::Vector3d::Zero();
    const double c0 = ThreadCpuSeconds();
    for (long k = 0; k < steps; ++k) sink += air.Step(1.5, v_W);
    wind_s = ThreadCpuSeconds() - c0;
    if (!sink.allFinite()) throw std::runtime_error("wind: not finite");
  }
  if (spec.odometry_noise != "none") {
    sim::OdometryNoise noise(sim::OdometryNoisePreset(spec.odometry_noise), spec.seed);
    navstack::VehicleState truth;
    double sink = 0;
    const long frame_every = std::lround(1.0 / 30.0 / defaults.physics_dt);
    const double c0 = ThreadCpuSeconds();
    for (long k = 0; k < steps; ++k) {
      if (k % frame_every == 0) noise.Update(k * defaults.physics_dt);
      sink += noise.Apply(truth).p_WB.x();
    }
    odometry_s = ThreadCpuSeconds() - c0;
    if (!std::isfinite(sink)) throw std::runtime_error("odometry: not finite");
  }
  api::EpisodeSpec still = spec;
  still.wind = {};
  still.odometry_noise = "none";
  const double c0 = ThreadCpuSeconds();
  const api::EpisodeResult calm = sim::RunEpisode(still, world);
  const double calm_cpu = ThreadCpuSeconds() - c0;
  const double per_step = episode_cpu_s / std::max(1L, steps);
  return {{"turbulence", spec.wind.turbulence},
          {"odometry_noise", spec.odometry_noise},
          {"wind_us_per_step", 1e6 * wind_s / std::max(1L, steps)},
          {"odometry_us_per_step", 1e6 * odometry_s / std::max(1L, steps)},
          {"share_of_episode_cpu", (wind_s + odometry_s) / std::max(1L, steps) / per_step},
          {"still_episode", {{"end_reason", calm.end_reason}, {"sim_s", calm.sim_time_s}, {"cpu_s", calm_cpu}}},
          // Host CPU per sim second, in this air over still air (different flights: noisy).
          {"episode_cpu_per_sim_s_ratio", (episode_cpu_s / result.sim_time_s) / (calm_cpu / calm.sim_time_s)}};
}

nlohmann::json Bench(const std::string& world_id, const std::map<std::string, std::string>& params,
                     const std::map<std::string, double>& overrides, const std::string& board,
                     const std::string& method, std::uint64_t seed, const sim::PreparedWorld& world, bool replay,
                     const sim::PreparedWorld* static_twin, const api::WindSpec& wind, const std::string& odometry) {
  api::EpisodeSpec spec;
  spec.world = world_id;
  spec.world_params = params;
  spec.overrides = overrides;
  spec.seed = seed;
  spec.board = board;
  spec.method = method;
  spec.wind = wind;
  spec.odometry_noise = odometry;

  std::array<TaskCpu, navstack::kTaskCount> tasks{};
  sim::EpisodeOptions options;
  options.job_observer = [&](TaskId task, const navstack::WorkCounts& work, double cpu) {
    TaskCpu& t = tasks[static_cast<int>(task)];
    ++t.jobs;
    t.cpu_s += cpu;
    if (HasWork(work)) {
      ++t.jobs_with_work;
      t.cpu_with_work_s += cpu;
    }
  };
  const double wall0 = WallSeconds(), cpu0 = ThreadCpuSeconds(), proc0 = ProcessCpuSeconds();
  const api::EpisodeResult result = sim::RunEpisode(spec, world, options);
  const double wall = WallSeconds() - wall0, cpu = ThreadCpuSeconds() - cpu0, proc = ProcessCpuSeconds() - proc0;

  double navstack_s = 0;
  for (int i = 0; i < navstack::kTaskCount; ++i)
    if (static_cast<TaskId>(i) != TaskId::kEci) navstack_s += tasks[i].cpu_s;  // eci here: the metrics'
  const TaskCpu& eci = tasks[static_cast<int>(TaskId::kEci)];
  auto ms_per_job = [](double s, std::int64_t n) { return n > 0 ? 1e3 * s / static_cast<double>(n) : 0.0; };

  nlohmann::json j;
  j["world"] = world_id;
  j["params"] = params;
  j["board"] = board;
  j["method"] = method;
  j["overrides"] = overrides;
  j["seed"] = seed;
  j["end_reason"] = result.end_reason;
  j["sim_s"] = result.sim_time_s;
  j["wall_s"] = wall;
  j["sim_per_wall"] = result.sim_time_s / wall;
  j["episode_cpu_s"] = cpu;
  j["process_cpu_s"] = proc;  // > episode_cpu_s only if helper threads worked
  j["sim_per_cpu"] = result.sim_time_s / cpu;
  j["navstack_cpu_s"] = navstack_s;
  j["outside_navstack_cpu_s"] = cpu - navstack_s;
  j["share_outside_navstack"] = (cpu - navstack_s) / cpu;
  j["eci_for_metrics_cpu_s"] = eci.cpu_s;
  nlohmann::json per_task;
  for (int i = 0; i < navstack::kTaskCount; ++i) {
    const TaskCpu& t = tasks[i];
    if (t.jobs == 0) continue;
    per_task[std::string(navstack::TaskName(static_cast<TaskId>(i)))] = {
        {"jobs", t.jobs}, {"jobs_with_work", t.jobs_with_work}, {"cpu_s", t.cpu_s},
        {"ms_per_job_with_work", ms_per_job(t.cpu_with_work_s, t.jobs_with_work)}};
  }
  j["tasks"] = per_task;
  j["per_frame_ms"] = {
      {"eci", ms_per_job(eci.cpu_s, eci.jobs)},
      {"map_update", ms_per_job(tasks[0].cpu_with_work_s, tasks[0].jobs_with_work)},
      {"replan", ms_per_job(tasks[1].cpu_with_work_s, tasks[1].jobs_with_work)},
      {"collision_check", ms_per_job(tasks[2].cpu_with_work_s, tasks[2].jobs_with_work)}};
  if (replay) {
    const Replay r = ReplayWithoutNavstack(spec, world, result);
    const double others = r.total_s - r.render_s - r.eci_s - r.physics_s - r.controller_s;
    const double outside = cpu - navstack_s;
    j["replay_without_navstack"] = {
        {"cpu_s", r.total_s},
        {"render_ms_per_frame", 1e3 * r.render_s / std::max(1.0, r.frames)},
        {"eci_ms_per_frame", 1e3 * r.eci_s / std::max(1.0, r.frames)},
        {"physics_us_per_step", 1e6 * r.physics_s / std::max(1.0, r.steps)},
        {"controller_us_per_update", 1e6 * r.controller_s / std::max(1.0, r.control_updates)},
        // Shares of the episode's CPU outside the navstack; "unattributed" is what the replay
        // does not have: executor bookkeeping, nav link, recorder and time series.
        {"share_of_outside",
         {{"render", r.render_s / outside},
          {"eci", r.eci_s / outside},
          {"physics", r.physics_s / outside},
          {"controller", r.controller_s / outside},
          {"replay_loop_rest", others / outside},
          {"unattributed", (outside - r.total_s) / outside}}}};
  }
  if (static_twin != nullptr) {
    // The same world without its movers: a whole episode (its own flight), and the replay of the
    // mover flight's path through the static world (the same views and steps, no movers).
    const double c0 = ThreadCpuSeconds();
    const api::EpisodeResult alone = sim::RunEpisode(spec, *static_twin);
    const double static_cpu = ThreadCpuSeconds() - c0;
    const Replay with = ReplayWithoutNavstack(spec, world, result, true);
    const Replay without = ReplayWithoutNavstack(spec, *static_twin, result, false);
    j["movers_vs_static"] = {
        {"movers", world.world.movers.size()},
        {"static_episode", {{"end_reason", alone.end_reason}, {"sim_s", alone.sim_time_s}, {"cpu_s", static_cpu}}},
        // Host CPU per sim second, with movers over without (different flights: noisy).
        {"episode_cpu_per_sim_s_ratio", (cpu / result.sim_time_s) / (static_cpu / alone.sim_time_s)},
        // The same path replayed: what the movers cost the simulation itself.
        {"replay_cpu_ratio", with.total_s / without.total_s},
        {"replay_render_ms_per_frame", {{"movers", 1e3 * with.render_s / std::max(1.0, with.frames)},
                                        {"static", 1e3 * without.render_s / std::max(1.0, without.frames)}}},
        {"replay_physics_us_per_step", {{"movers", 1e6 * with.physics_s / std::max(1.0, with.steps)},
                                        {"static", 1e6 * without.physics_s / std::max(1.0, without.steps)}}}};
  }
  if (spec.wind.Active() || spec.odometry_noise != "none") j["air_vs_still"] = PriceOfTheAir(spec, world, result, cpu);
  return j;
}

}  // namespace
}  // namespace enavi

int main(int argc, char** argv) {
  using namespace enavi;
  std::vector<std::string> world_ids, boards;
  std::map<std::string, std::string> params;
  std::map<std::string, double> overrides;
  std::string method = "baseline";
  std::uint64_t seed = 1;
  bool replay = true;
  api::WindSpec wind;
  std::string odometry = "none";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--world" && has_value) {
      world_ids.push_back(argv[++i]);
    } else if (a == "--board" && has_value) {
      boards.push_back(argv[++i]);
    } else if (a == "--seed" && has_value) {
      seed = std::stoull(argv[++i]);
    } else if (a == "--param" && has_value) {
      const std::string kv = argv[++i];
      const auto eq = kv.find('=');
      if (eq == std::string::npos) {
        std::fprintf(stderr, "--param: expected k=v, got '%s'\n", kv.c_str());
        return 2;
      }
      params[kv.substr(0, eq)] = kv.substr(eq + 1);
    } else if (a == "--method" && has_value) {
      method = argv[++i];
      if (!navstack::FindMethod(method)) {
        std::string known;
        for (const std::string& n : navstack::MethodNames()) known += (known.empty() ? "" : ", ") + n;
        std::fprintf(stderr, "--method: unknown method '%s' (known: %s)\n", method.c_str(), known.c_str());
        return 2;
      }
    } else if (a == "--set" && has_value) {
      const std::string kv = argv[++i];
      const auto eq = kv.find('=');
      char* end = nullptr;
      const double v = eq == std::string::npos ? 0.0 : std::strtod(kv.c_str() + eq + 1, &end);
      if (eq == std::string::npos || end == kv.c_str() + eq + 1 || *end != '\0') {
        std::fprintf(stderr, "--set: expected name=number, got '%s'\n", kv.c_str());
        return 2;
      }
      overrides[kv.substr(0, eq)] = v;
    } else if (a == "--no-replay") {
      replay = false;
    } else if (a == "--turbulence" && has_value) {
      wind.turbulence = argv[++i];
      if (const std::string e = api::WindSpecError(wind); !e.empty()) {
        std::fprintf(stderr, "--turbulence: %s\n", e.c_str());
        return 2;
      }
    } else if (a == "--odometry-noise" && has_value) {
      odometry = argv[++i];
      if (const std::string e = api::OdometryNoiseError(odometry); !e.empty()) {
        std::fprintf(stderr, "--odometry-noise: %s\n", e.c_str());
        return 2;
      }
    } else {
      std::fprintf(stderr,
                   "usage: bench_episode [--world ID]... [--board ID]... [--method ID] [--param k=v]... [--set k=v]...\n"
                   "                     [--seed N] [--no-replay] [--turbulence LEVEL] [--odometry-noise PRESET]\n");
      return a == "--help" ? 0 : 2;
    }
  }
  if (world_ids.empty()) world_ids = {"s1", "s2"};
  if (boards.empty()) boards = {"host", "tx2"};

  nlohmann::json runs = nlohmann::json::array();
  try {
    for (const std::string& id : world_ids) {
      worlds::WorldRequest request;
      request.world = id;
      request.seed = seed;
      request.params = params;
      const double c0 = navstack::ThreadCpuSeconds();
      const auto world = sim::PrepareWorld(worlds::ResolveWorld(request));
      const double prepare_s = navstack::ThreadCpuSeconds() - c0;
      std::shared_ptr<const sim::PreparedWorld> static_twin;
      if (!world->world.movers.empty()) {
        worlds::World without = world->world;
        without.movers.clear();
        static_twin = sim::PrepareWorld(std::move(without));
      }
      for (const std::string& board : boards) {
        nlohmann::json run = Bench(id, params, overrides, board, method, seed, *world, replay, static_twin.get(), wind, odometry);
        run["prepare_world_cpu_s"] = prepare_s;  // once per world, not part of the episode
        std::fprintf(stderr, "%s on %s: %.1f sim s in %.1f wall s, %.1f %% of the episode's CPU outside the navstack\n",
                     id.c_str(), board.c_str(), run["sim_s"].get<double>(), run["wall_s"].get<double>(),
                     100.0 * run["share_outside_navstack"].get<double>());
        runs.push_back(std::move(run));
      }
    }
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  std::printf("%s\n", nlohmann::json{{"bench", "episode"}, {"method", method}, {"runs", runs}}.dump(2).c_str());
  return 0;
}
