// `enavi fly`: one episode, locally, no server.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/atomic_file.h"
#include "api/episode.h"
#include "api/job_spec.h"
#include "api/ros_stack.h"
#include "navstack/methods/registry.h"
#include "server/cli/cli_values.h"
#include "server/cli/commands.h"
#include "server/cli/registry_help.h"
#include "server/eval/progress_pacer.h"
#include "server/report/flight_report.h"
#include "workers/board/board_profile.h"
#include "workers/board/calibration_flights.h"
#include "workers/sim/episode.h"
#include "workers/sim/episode_config.h"

namespace enavi::cli {
namespace {

// Every depth frame's eci with what it was computed from: where a flight's extremes come from
// (d0, the layers and zones, the camera's pitch), at the sensor's rate.
std::string EciFramesCsv(const std::vector<sim::EciFrame>& frames) {
  std::string out =
      "t,eci,d0,d_ahead,layers,occupied_zones,valid_pixels,velocity_aligned,speed,camera_pitch_deg,in_flight\n";
  char line[256];
  for (const sim::EciFrame& f : frames) {
    std::snprintf(line, sizeof line, "%.3f,%.4f,%.3f,%.3f,%d,%d,%lld,%d,%.3f,%.2f,%d\n", f.t, f.eci.eci, f.eci.d0,
                  f.eci.d_ahead, f.eci.layers, f.eci.occupied_zones, static_cast<long long>(f.eci.valid_pixels),
                  f.eci.velocity_aligned ? 1 : 0, f.speed, f.camera_pitch_deg, f.in_flight ? 1 : 0);
    out += line;
  }
  return out;
}

struct FlyArgs {
  api::EpisodeSpec spec;
  std::string start, goal;
  std::vector<std::string> params;
  std::vector<std::string> overrides;
  std::string out_dir;
  bool json = false;
  double dilation = 0.0;  // emulated clock; 0 (absent): the smallest that fits the host
  std::string calibration;
  emulation::EmulationOptions emulation;  // experiments: hidden flags
  std::string ros_stack;  // a ROS stack file: the method
  bool rosbag = false;
  bool method_given = false, clock_given = false;
};

void Run(FlyArgs args) {
  api::EpisodeSpec spec = args.spec;
  if (!args.ros_stack.empty()) {
    spec.ros = api::LoadRosStack(args.ros_stack, navstack::MethodNames());
    if (args.method_given && spec.method != spec.ros->name)
      throw api::RosStackError("--method: '" + spec.method + "' is not the ROS stack's name '" + spec.ros->name +
                               "' (--ros-stack names the method)");
    spec.method = spec.ros->name;
    if (!args.clock_given) spec.clock = "emulated";  // the only clock a ROS stack runs on
  } else if (args.rosbag) {
    throw std::invalid_argument("--rosbag: records the topics of a ROS stack (--ros-stack FILE)");
  }
  if (!args.start.empty()) spec.start = ParsePoint("--start", args.start);
  if (!args.goal.empty()) spec.goal = ParsePoint("--goal", args.goal);
  spec.world_params = ParseNameValues("--param", args.params);
  for (const auto& [k, v] : ParseNameValues("--set", args.overrides)) spec.overrides[k] = ParseNumber("--set", k, v);

  sim::EpisodeOptions options;
  options.emulation = args.emulation;
  options.emulation.calibration_file = args.calibration;
  options.emulation.probe_host_speed = board::ProbeHostSpeed;  // spec.speed_probe says what for
  // An absent --dilation means "the smallest that fits" (spec.dilation 0; the value used is in
  // the result's notes).
  if (spec.clock == "emulated" || args.dilation > 0) spec.dilation = args.dilation;
  const bool tty = isatty(STDERR_FILENO) && !args.json;
  // On a terminal the line is redrawn in place; in a log it is a line every 10 s of wall time.
  server::ProgressPacer lines;
  if (tty) {
    options.progress = [](double t, double distance) {
      std::fprintf(stderr, "\r  sim %6.1f s, %5.1f m to goal", t, distance);
      std::fflush(stderr);
    };
  } else if (!args.json) {
    options.progress = [&lines](double t, double distance) {
      if (t > 0 && lines.Due(0, 0, std::chrono::steady_clock::now())) {
        std::fprintf(stderr, "  sim %.1f s, %.1f m to goal\n", t, distance);
      }
    };
  }
  if (spec.ros) {
    if (!args.out_dir.empty()) options.ros_output_dir = (std::filesystem::path(args.out_dir) / "ros").string();
    if (args.rosbag)
      options.ros_bag_file = std::filesystem::absolute(args.out_dir.empty() ? std::filesystem::path(spec.method + ".bag")
                                                                            : std::filesystem::path(args.out_dir) / "episode.bag")
                                 .string();
  }
  std::vector<sim::EciFrame> eci_frames;
  if (!args.out_dir.empty()) options.eci_observer = [&eci_frames](const sim::EciFrame& f) { eci_frames.push_back(f); };
  const auto world = sim::PrepareSpecWorld(spec);
  const api::EpisodeResult result = sim::RunEpisode(spec, *world, options);
  if (tty) std::fprintf(stderr, "\n");

  if (!args.out_dir.empty()) {
    const std::filesystem::path dir(args.out_dir);
    std::filesystem::create_directories(dir);
    nlohmann::json full = result;
    full.erase("series");
    api::WriteFileAtomic(dir / "result.json", full.dump(2) + "\n");
    api::WriteFileAtomic(dir / "timeseries.csv", report::TimeSeriesCsv(result.series));
    api::WriteFileAtomic(dir / "eci_frames.csv", EciFramesCsv(eci_frames));
    report::WriteFlightPlots(result, world->world, dir.string());
    report::EciFrameSeries plot;
    for (const sim::EciFrame& f : eci_frames) {
      plot.t.push_back(f.t);
      plot.eci.push_back(f.eci.eci);
      plot.d0.push_back(f.eci.d0);
      plot.camera_pitch_deg.push_back(f.camera_pitch_deg);
    }
    report::WriteEciFramesPlot(result, plot, (dir / "eci_frames.png").string());
  }
  if (args.json) {
    std::printf("%s\n", api::ResultSummaryJson(result).dump().c_str());
  } else {
    std::printf("%s %s on %s (seed %llu): %s, %.1f s, %.1f m, nav CPU %.1f %%, deadline misses %.2f %%\n",
                spec.method.c_str(), result.scenario.c_str(), spec.board.c_str(),
                static_cast<unsigned long long>(spec.seed), result.end_reason.c_str(), result.flight_time_s,
                result.path_length_m, result.nav_cpu_util_pct, 100.0 * result.deadline_miss_ratio);
  }
}

}  // namespace

void AddSpeedProbeOption(CLI::App* app, std::string* mode) {
  app->add_option("--speed-probe", *mode,
                  "emulated clock: measure this host's speed on each CPU before the episode (~2 s of flights "
                  "a CPU) against its calibration's:\n"
                  "    use: emulate the board on the host's speed now\n"
                  "    check: report the drift (a warning beyond 10 %), keep the calibration's speed\n"
                  "    off: no probe")
      ->capture_default_str()
      ->check(CLI::IsMember(std::vector<std::string>(api::kSpeedProbeModes.begin(), api::kSpeedProbeModes.end())));
}

void AddAirOptions(CLI::App* app, api::WindSpec* wind, std::string* odometry_noise) {
  const auto levels = std::vector<std::string>(api::kTurbulenceLevels.begin(), api::kTurbulenceLevels.end());
  const auto presets = std::vector<std::string>(api::kOdometryNoisePresets.begin(), api::kOdometryNoisePresets.end());
  const auto speed = CLI::Range(0.0, api::kMaxWindSpeed);
  const auto angle = CLI::Range(-360.0, 360.0);
  app->add_option("--wind", wind->speed_mps, "mean wind, m/s (the stack is not told; the vehicle's drag feels it)")
      ->check(speed)->group("Air and odometry");
  app->add_option("--wind-dir", wind->direction_deg, "where the mean wind blows to, degrees from world +x toward +y")
      ->check(angle)->group("Air and odometry");
  app->add_option("--turbulence", wind->turbulence,
                  "Dryden turbulence of MIL-F-8785C, low altitude: none, light, moderate, severe")
      ->capture_default_str()->check(CLI::IsMember(levels))->group("Air and odometry");
  app->add_option("--gust", wind->gust.speed_mps, "a 1-cosine gust (MIL-F-8785C) of this speed, m/s")
      ->check(speed)->group("Air and odometry");
  app->add_option("--gust-dir", wind->gust.direction_deg, "where the gust blows to, degrees from +x toward +y")
      ->check(angle)->group("Air and odometry");
  app->add_option("--gust-start", wind->gust.start_s, "the gust's start, sim s")
      ->capture_default_str()->check(CLI::Range(0.0, api::kMaxTimeoutS))->group("Air and odometry");
  app->add_option("--gust-rise", wind->gust.rise_s, "its rise (and fall) time, s")
      ->capture_default_str()->check(CLI::Range(0.01, api::kMaxTimeoutS))->group("Air and odometry");
  app->add_option("--gust-hold", wind->gust.hold_s, "how long it holds its speed, s")
      ->capture_default_str()->check(CLI::Range(0.0, api::kMaxTimeoutS))->group("Air and odometry");
  app->add_option("--odometry-noise", *odometry_noise,
                  "the stack's odometry as a VIO gives it (white noise and drift of position and yaw): none, good, "
                  "typical, poor; metrics use the truth")
      ->capture_default_str()->check(CLI::IsMember(presets))->group("Air and odometry");
}

void RegisterFlyCommand(CLI::App& app) {
  auto args = std::make_shared<FlyArgs>();
  CLI::App* fly = app.add_subcommand("fly", "Fly one episode locally (no server) and print or write its results");
  fly->add_option("--world", args->spec.world,
                  "a scenario, FILE.yaml, a mesh (.obj .gltf .glb .dae .stl .ply .fbx) or a Gazebo world (.sdf .world); "
                  "scenarios:" + ScenariosHelp())->capture_default_str();
  fly->add_option("--seed", args->spec.seed, "world and episode seed")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& text) {
            // CLI11 would wrap "-3" around to 2^64 - 3.
            return text.find('-') == std::string::npos ? std::string() : "must be >= 0 (got " + text + ")";
          },
          ""));
  fly->add_option("--start", args->start, "start x,y,z (required for mesh and SDF worlds)");
  fly->add_option("--goal", args->goal, "goal x,y,z (required for mesh and SDF worlds)");
  fly->add_option("--param", args->params, "world generator parameter k=v (repeatable)");
  AddPlacementOptions(fly, &args->spec.units, &args->spec.scale, &args->spec.up, &args->spec.recenter,
                      &args->spec.model_path);
  fly->add_option("--board", args->spec.board, "onboard computer to emulate:" + BoardsHelp())
      ->capture_default_str()
      ->check(CLI::IsMember(board::KnownBoards()));
  std::string methods = "navigation method:";
  for (const navstack::MethodInfo& m : navstack::Methods()) methods += "\n    " + m.name + ": " + m.summary;
  fly->add_option("--method", args->spec.method, methods)
      ->capture_default_str()
      ->check(CLI::IsMember(navstack::MethodNames()))
      ->each([args](const std::string&) { args->method_given = true; });
  fly->add_option("--ros-stack", args->ros_stack,
                  "a ROS 1 stack file (docs/ros.md): fly the user's ROS stack as the method (its name), on the "
                  "emulated clock")
      ->check(CLI::ExistingFile);
  fly->add_flag("--rosbag", args->rosbag,
                "ROS stacks: record the episode's topics into a bag (DIR/episode.bag with --out, else NAME.bag)");
  fly->add_option("--clock", args->spec.clock, "clock:" + ClocksHelp())
      ->capture_default_str()
      ->check(CLI::IsMember(sim::FarmCatalog().clocks))
      ->each([args](const std::string&) { args->clock_given = true; });
  fly->add_option("--dilation", args->dilation,
                  "emulated clock: 1 sim second = K wall seconds, quota divided by K (default: the smallest "
                  "multiple of 0.25 at which the board fits this host)")
      ->check(CLI::Range(1.0, 100.0));
  fly->add_option("--calibration", args->calibration,
                  "emulated clock: host calibration file (default: $ENAVI_CALIBRATION, else "
                  "$XDG_STATE_HOME/enavi/calibration.json or ~/.local/state/enavi/calibration.json)");
  AddSpeedProbeOption(fly, &args->spec.speed_probe);
  AddAirOptions(fly, &args->spec.wind, &args->spec.odometry_noise);
  // Experiments with the emulation itself (defaults documented in workers/emulation/emulation_options.h).
  fly->add_option("--emulation-server-period-us", args->emulation.server_period_us)->group("")->check(CLI::Range(100, 1000000));
  fly->add_option("--emulation-lead-us", args->emulation.lead_us)->group("")->check(CLI::Range(0, 1000000));
  fly->add_option("--emulation-cpus", args->emulation.cpus)->group("");
  fly->add_flag("!--emulation-no-deadline", args->emulation.sched_deadline)->group("");
  fly->add_flag("!--emulation-no-fifo", args->emulation.simulator_fifo)->group("");
  fly->add_option("--cost", args->spec.cost, "virtual clock cost mode: model (work counts) or measured (host CPU)")
      ->capture_default_str()
      ->check(CLI::IsMember(std::vector<std::string>(api::kCostModes.begin(), api::kCostModes.end())));
  fly->add_option("--timeout", args->spec.timeout_s, "episode timeout in sim seconds (0: from the distance)")
      ->check(CLI::Range(0.0, api::kMaxTimeoutS));
  fly->add_option("--policy", args->spec.policy,
                  "E-Navi frequency-adapter policy (default: the shipped one), or the learned method's nav policy");
  std::string tunables = "override a tunable, name=value (repeatable); every method's:";
  auto list = [&](const std::vector<sim::Tunable>& ts) {
    for (const auto& t : ts)
      tunables += "\n    " + t.name + " [" + CLI::detail::to_string(t.min) + ", " + CLI::detail::to_string(t.max) +
                  "] (" + CLI::detail::to_string(t.default_value) + "): " + t.help;
  };
  list(sim::CommonTunables());
  for (const navstack::MethodInfo& m : navstack::Methods()) {
    tunables += "\n  method " + m.name + ":";
    list(m.tunables);
  }
  fly->add_option("--set", args->overrides, tunables);
  fly->add_option("--out", args->out_dir,
                  "write result.json, timeseries.csv (10 Hz), eci_frames.csv (every depth frame) and plots "
                  "(PNG) here; a ROS stack's logs in DIR/ros");
  fly->add_flag("--json", args->json, "print one JSON object with the results on stdout");
  fly->callback([args] { Run(*args); });
}

}  // namespace enavi::cli
