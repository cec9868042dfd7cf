#pragma once
// `enavi eval`: the farm in one command. An in-process server (SQLite store + scheduler) and N
// local worker processes (`enavi worker`, the same code as on a cluster) talk over DDS on a
// private loopback domain and partition, so concurrent evals and tests never cross-talk.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/http_schema.h"
#include "api/job_spec.h"
#include "server/eval/progress_pacer.h"
#include "server/http/http_api.h"

namespace enavi::server {

struct EvalReport;

struct EvalOptions {
  std::string name = "eval";  ///< the job's name (`--name`): the dashboard and `enavi status` show it
  std::vector<std::string> boards = {"tx2"};
  std::vector<std::string> scenarios = {"s1"};
  std::vector<std::string> methods = {"baseline", "enavi"};
  int seeds = 1;
  double timeout_s = 0;  ///< each episode's sim-time limit (the job's timeout_s); 0: from the distance
  std::string clock = "virtual";
  std::string cost = "model";
  /// Emulated clock: wall seconds per sim second, or "auto" (the smallest at which each board fits
  /// the host when its episode starts); not written into a virtual-clock job.
  std::string dilation = "auto";
  std::string speed_probe = "check";  ///< emulated clock: api::kSpeedProbeModes
  std::string policy;  ///< E-Navi's policy file (under an allowed root); empty: the shipped one
  api::WindSpec wind;  ///< every episode's air (the job's `wind`)
  std::string odometry_noise = "none";  ///< the job's `odometry_noise`
  std::map<std::string, std::string> labels;  ///< the job's labels (dashboard, `enavi compare`)
  std::map<std::string, std::string> world_params;  ///< `--param k=v`: every scenario's generator (the job's `world_params`)
  /// `--set NAME=VALUE`: a tunable of every listed method (the job's `overrides`).
  std::map<std::string, double> overrides;
  /// `--set METHOD:NAME=VALUE`: a tunable of one method (an `episode_overrides` entry matching
  /// it), e.g. {"enavi": {"strategy.least_load": 1}} for an ablation beside the other methods.
  std::map<std::string, std::map<std::string, double>> method_overrides;
  /// `--ros-stack FILE`: ROS methods by name, each a stack file (docs/ros.md); each is in `methods`.
  std::map<std::string, std::string> ros_stacks;
  std::filesystem::path db;      ///< empty: a temporary database, removed afterwards
  int workers = 2;
  int slots = 1;                 ///< per worker
  /// Episode command for the workers; empty: `<enavi> fly`.
  std::string episode_command;
  std::chrono::seconds episode_timeout{3600};
  /// The enavi executable the workers run; empty: this process's executable.
  std::filesystem::path enavi;
  std::optional<std::uint32_t> domain;  ///< empty: derived from the process id
  api::JobSpecOptions job_spec;
  bool progress_bar = false;     ///< redraw a bar in place (terminal); else lines (ProgressPacer)
  /// Serve the HTTP API and dashboard here while the job runs (`enavi eval --dashboard`).
  std::optional<HttpOptions> dashboard;
  /// With `dashboard`: called once the job is done and its results are read, while the
  /// dashboard still serves them; RunEval returns when it does (e.g. after Ctrl-C).
  std::function<void(const EvalReport&)> while_serving;
  std::chrono::milliseconds progress_period{500};  ///< the bar's redraw period
  std::chrono::milliseconds progress_line_period{kProgressLinePeriod};  ///< lines: at least this often
};

struct EvalReport {
  std::string job_id;
  api::JobProgress progress;
  nlohmann::json results;  ///< result objects, episode order
};

/// Runs the matrix to completion; progress goes to `progress_out`.
/// @throws std::invalid_argument for a bad matrix (message names the flag), std::runtime_error
/// when the farm cannot run (e.g. every worker exited).
EvalReport RunEval(const EvalOptions& options, std::ostream& progress_out);

/// The job spec YAML `enavi eval` submits for `options` (one flag per line).
std::string EvalJobYaml(const EvalOptions& options);

/// `yaml` (EvalJobYaml) checked as a submitted job is. @throws std::invalid_argument naming the
/// flag as typed and the reason ("--set planner.v_maxx: not a tunable of method baseline ..."),
/// never a line of the YAML the user did not write.
api::JobSpec ParseEvalJob(const EvalOptions& options, const std::string& yaml);

}  // namespace enavi::server
