#pragma once
// `enavi train`: PPO training of E-Navi's frequency adapter from farm rollouts (paper Sec. V.C).
// Each iteration uploads the current policy to a farm, submits a collection job (the policy by
// content hash, sampled actions), trains one PPO update on the rollouts that come back, and
// checkpoints; a run resumes from its checkpoint. The farm is a running one (--server) or a
// private one started for the run (server/eval/local_farm.h), so a worker that dies only delays
// an iteration: its episode runs again elsewhere.
//
// Two curves come out. The training curve is the mean return of each iteration's sampled flights;
// its worlds change every iteration, so it carries their spread. The evaluation curve flies the
// greedy policy every few iterations on one fixed set of worlds training never draws (common
// random numbers: the same worlds, seeds and boards each time, on the deterministic virtual
// clock), so what moves it is the policy alone.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "api/episode.h"
#include "navstack/rl/policy_io.h"
#include "navstack/rl/ppo.h"

namespace enavi::train {

struct TrainOptions {
  std::vector<std::string> boards = {"tx2", "pi4b"};
  /// The paper's five and the street canyons (corners at speed: what the reaction constraint is for).
  std::vector<std::string> scenarios = {"s1", "s2", "s3", "s4", "s5", "canyon"};
  int iterations = 20;
  int episodes_per_iteration = 10;
  std::string server;              ///< farm URL; empty: a private local farm
  std::string token;               ///< the farm's token (state-changing requests)
  int workers = 2;                 ///< private farm: local worker processes (one slot each)
  api::Catalog catalog;            ///< the registries: --boards, --scenarios and a private farm's jobs are checked against it
  std::uint64_t seed = 1;
  /// Training worlds use seeds from here on, so evaluation seeds (1, 2, 3 ...) stay unseen.
  std::uint64_t world_seed_base = 100;
  int world_seed_count = 400;
  std::filesystem::path out = "policy.json";
  std::filesystem::path work_dir;  ///< default: <out>.train
  std::string init_policy;         ///< start from this policy instead of a fresh one
  /// A fresh policy's head (policy.h): one logit per action, or per frequency level.
  navstack::rl::PolicyHead head = navstack::rl::PolicyHead::kJoint;
  bool resume = false;             ///< continue from <work_dir>/checkpoint.json
  navstack::rl::PpoOptions ppo;
  bool progress = true;            ///< progress line on stderr
  /// Evaluate the greedy policy before every eval_every-th update and after the last (0: never).
  int eval_every = 5;
  /// Evaluation worlds: every scenario once per seed, boards in turn. Seeds must lie outside the
  /// training range [world_seed_base, world_seed_base + world_seed_count).
  std::vector<std::uint64_t> eval_seeds = {1, 2};
};

/// One row of the learning curve.
struct IterationLog {
  std::int64_t iteration = 0;
  int episodes = 0;
  int failed_episodes = 0;  ///< episodes the farm gave up on (not flights that failed: those are data)
  double mean_return = 0;
  double success_rate = 0;
  double collision_rate = 0;
  double mean_nav_cpu = 0;
  double mean_flight_time = 0;
  double policy_loss = 0, value_loss = 0, entropy = 0, approx_kl = 0;
  double episodes_per_s = 0;
};

/// One point of the evaluation curve: the greedy policy after `policy_iteration` updates on the
/// fixed evaluation worlds.
struct EvaluationLog {
  std::int64_t policy_iteration = 0;
  int episodes = 0;
  int failed_episodes = 0;
  double mean_return = 0;
  double success_rate = 0;
  double collision_rate = 0;
  double mean_nav_cpu = 0;
  double mean_flight_time = 0;
};

struct TrainResult {
  std::vector<IterationLog> iterations;    ///< the training curve, resumed iterations included
  std::vector<EvaluationLog> evaluations;  ///< the evaluation curve, resumed points included
};

/// Runs the training. Throws std::invalid_argument for bad options (unknown board or scenario,
/// counts out of range, evaluation seeds inside the training range).
TrainResult Train(const TrainOptions& options);

std::string LearningCurveCsv(const std::vector<IterationLog>& log);
std::string EvaluationCurveCsv(const std::vector<EvaluationLog>& log);

}  // namespace enavi::train
