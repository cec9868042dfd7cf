#pragma once
// Registration of the `enavi` subcommand families; each lives in its own *_cmd.cc file.
// Handlers throw std::invalid_argument for bad input (exit 2) and anything else for failures
// (exit 1); main() maps them.

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "api/episode.h"

namespace enavi::emulation {
struct EmulationOptions;
}

namespace enavi::cli {

/// Exit codes shared by every subcommand (README.md, "Commands").
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitBadInput = 2;
/// `enavi compare`: the candidate regressed (a CI job gates on this).
inline constexpr int kExitRegression = 3;
/// `enavi compare`: a metric changed for the worse beyond its threshold but the mode cannot
/// judge it (paired mode with one seed pair: no interval). Never reported as "no regression".
inline constexpr int kExitCannotJudge = 4;

/// Thrown by a handler to end with a specific exit status after printing its output.
struct ExitStatus {
  int code = kExitOk;
};

/// --units, --scale, --up, --recenter (mesh worlds) and --model-path (SDF worlds), shared by
/// `enavi fly` and `enavi world` (server/cli/world_cmd.cc).
void AddPlacementOptions(CLI::App* app, std::string* units, double* scale, std::string* up, bool* recenter,
                         std::vector<std::string>* model_path);

/// --speed-probe check|use|off of the commands that start emulated episodes (`enavi fly`,
/// `enavi eval`): an episode spec's or a job's `speed_probe` (server/cli/fly_cmd.cc).
void AddSpeedProbeOption(CLI::App* app, std::string* mode);
/// --wind, --wind-dir, --turbulence, --gust*, --odometry-noise of `enavi fly` and `enavi eval`:
/// the air an episode flies in and the odometry its stack is given (server/cli/fly_cmd.cc).
void AddAirOptions(CLI::App* app, api::WindSpec* wind, std::string* odometry_noise);

/// `enavi world gen|check|show|convert` (server/cli/world_cmd.cc).
void RegisterWorldCommands(CLI::App& app);
/// `enavi fly` (server/cli/fly_cmd.cc).
void RegisterFlyCommand(CLI::App& app);
/// `enavi episode`, the farm worker's child (server/cli/episode_cmd.cc).
void RegisterEpisodeCommand(CLI::App& app);
/// `enavi bench raycast|...` (server/cli/bench_cmd.cc).
void RegisterBenchCommands(CLI::App& app);
/// `enavi calibrate` (server/cli/calibrate_cmd.cc).
void RegisterCalibrateCommand(CLI::App& app);
/// `enavi train` (server/cli/train_cmd.cc).
void RegisterTrainCommand(CLI::App& app);
// The farm (server/cli/{serve,worker,client,eval}_cmd.cc).
void RegisterServeCommand(CLI::App& app);
void RegisterWorkerCommand(CLI::App& app);
void RegisterClientCommands(CLI::App& app);  // submit, status, results, cancel
void RegisterEvalCommand(CLI::App& app);
/// `enavi dataset export` (server/cli/dataset_cmd.cc).
void RegisterDatasetCommands(CLI::App& app);
/// `enavi compare` (server/cli/compare_cmd.cc).
void RegisterCompareCommand(CLI::App& app);
/// `enavi trend` (server/cli/compare_cmd.cc): a metric over a label series, per board and method.
void RegisterTrendCommand(CLI::App& app);
/// `enavi dashboard` (server/cli/dashboard_cmd.cc).
void RegisterDashboardCommand(CLI::App& app);
/// `enavi policy convert` (server/cli/policy_cmd.cc).
void RegisterPolicyCommands(CLI::App& app);

}  // namespace enavi::cli
