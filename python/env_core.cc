#include "python/env_core.h"

#include <algorithm>
#include <stdexcept>

#include "navstack/adapt/action_grid.h"
#include "navstack/adapt/policy_state.h"
#include "workers/sim/episode_config.h"

namespace enavi::python {

void CheckBoard(const std::string& board) {
  const std::vector<std::string> boards = sim::FarmCatalog().boards;
  if (std::find(boards.begin(), boards.end(), board) == boards.end()) {
    std::string known;
    for (const std::string& b : boards) known += (known.empty() ? "" : ", ") + b;
    throw std::invalid_argument("board: unknown board '" + board + "' (known: " + known + ")");
  }
}

api::EpisodeSpec EnvEpisodeSpec(const std::string& method, const std::string& world,
                                const std::map<std::string, std::string>& world_params, const std::string& board,
                                double timeout_s, std::uint64_t seed) {
  api::EpisodeSpec spec;
  spec.world = world;
  spec.seed = seed;
  spec.world_params = world_params;
  spec.board = board;
  spec.method = method;
  spec.clock = "virtual";
  spec.timeout_s = timeout_s;
  return spec;
}

EnvCore::EnvCore(EnvConfig config) : config_(std::move(config)) {
  CheckBoard(config_.board);
  if (config_.overrides.count("strategy.explore")) {
    throw std::invalid_argument("overrides: strategy.explore is the environment's (its actions are yours)");
  }
}

// The episode goes first (members go in reverse order), before the port and rollout it writes to.
EnvCore::~EnvCore() = default;

int EnvCore::obs_size() const { return navstack::kPolicyStateDim; }
int EnvCore::action_size() const { return navstack::ActionGrid().size(); }

Transition EnvCore::Reset(std::uint64_t seed) {
  episode_.reset();
  finished_ = true;
  api::EpisodeSpec spec =
      EnvEpisodeSpec("enavi", config_.world, config_.world_params, config_.board, config_.timeout_s, seed);
  spec.policy = config_.policy;
  spec.overrides = config_.overrides;
  // Sampled decisions are the ones left to the caller.
  spec.overrides["strategy.explore"] = 1;
  world_ = sim::PrepareSpecWorld(spec);

  decisions_ = std::make_unique<navstack::rl::DecisionPort>();
  rollout_ = std::make_unique<navstack::rl::Rollout>();  // recording makes the controller compute rewards
  sim::EpisodeOptions options;
  options.rollout = rollout_.get();
  options.decisions = decisions_.get();
  episode_ = std::make_unique<sim::Episode>(spec, *world_, options);
  last_obs_ = Eigen::VectorXd::Zero(navstack::kPolicyStateDim);
  finished_ = false;
  Transition first = Advance();
  if (first.terminated || first.truncated) {
    throw std::runtime_error("the episode ended (" + first.end_reason + ") before its first decision");
  }
  first.reward = 0;
  return first;
}

Transition EnvCore::Step(int action) {
  if (finished_) throw std::logic_error("step() before reset() or after the episode ended");
  const std::vector<std::uint8_t>& mask = decisions_->mask();
  if (action < 0 || action >= static_cast<int>(mask.size()) || !mask[static_cast<std::size_t>(action)]) {
    throw std::invalid_argument("action " + std::to_string(action) + " is not feasible (see info['action_mask'])");
  }
  decisions_->Supply(action);
  return Advance();
}

Transition EnvCore::Advance() {
  sim::StepStatus status;
  try {
    while ((status = episode_->Step()) == sim::StepStatus::kRunning) {
    }
  } catch (...) {
    finished_ = true;
    throw;
  }
  Transition t;
  if (status == sim::StepStatus::kAwaitingDecision) {
    // The reward of the previous decision is known once the next one is made (rewards.h).
    const std::vector<navstack::rl::RolloutStep>& steps = episode_->link().rollout()->steps;
    t.obs = last_obs_ = decisions_->observation();
    t.mask = decisions_->mask();
    t.reward = steps.size() >= 2 ? steps[steps.size() - 2].reward : 0.0;
    t.t = static_cast<double>(decisions_->decisions() - 1);
    return t;
  }
  // The end: the last decision's reward, closed by the episode's outcome.
  finished_ = true;
  const api::EpisodeResult r = episode_->Finish();
  t.obs = last_obs_;
  t.reward = rollout_->steps.empty() ? 0.0 : rollout_->steps.back().reward;
  t.terminated = r.success || r.collided;
  t.truncated = !t.terminated;
  t.end_reason = r.end_reason;
  t.t = static_cast<double>(decisions_->decisions());
  t.metrics = {{"success", r.success ? 1.0 : 0.0}, {"collided", r.collided ? 1.0 : 0.0},
               {"flight_time_s", r.flight_time_s}, {"path_length_m", r.path_length_m},
               {"nav_cpu_util_pct", r.nav_cpu_util_pct}};
  return t;
}

}  // namespace enavi::python
