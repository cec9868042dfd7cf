#include "python/env_core.h"

#include <algorithm>
#include <stdexcept>

#include "api/job_spec.h"
#include "navstack/adapt/action_grid.h"
#include "navstack/adapt/policy_state.h"
#include "navstack/rl/decision_hook.h"
#include "navstack/rl/rollout.h"
#include "workers/sim/episode.h"
#include "workers/sim/episode_config.h"
#include "worlds/resolve.h"

namespace enavi::python {
namespace {

// Unwinds the episode thread when the environment is reset or destroyed mid-episode.
struct Abandoned {};

}  // namespace

// The rendezvous between the episode thread and the caller.
class EnvCore::Hook : public navstack::rl::DecisionHook {
 public:
  int Choose(const Eigen::VectorXd& obs, std::span<const std::uint8_t> mask) override {
    std::unique_lock lock(mutex_);
    Transition t;
    t.obs = obs;
    t.mask.assign(mask.begin(), mask.end());
    t.reward = pending_reward_;
    t.t = decisions_++;
    pending_reward_ = 0;
    last_obs_ = obs;
    event_ = std::move(t);
    cv_.notify_all();
    cv_.wait(lock, [&] { return action_.has_value() || abort_; });
    if (abort_) throw Abandoned{};
    const int a = *action_;
    action_.reset();
    return a;
  }
  void Reward(double reward) override {
    std::lock_guard lock(mutex_);
    pending_reward_ += reward;
  }

  // Episode thread: the end (or an error) of the episode.
  void End(const api::EpisodeResult& r) {
    std::lock_guard lock(mutex_);
    Transition t;
    t.obs = last_obs_;
    t.reward = pending_reward_;
    t.terminated = r.success || r.collided;
    t.truncated = !t.terminated;
    t.end_reason = r.end_reason;
    t.t = decisions_;
    t.metrics = {{"success", r.success ? 1.0 : 0.0}, {"collided", r.collided ? 1.0 : 0.0},
                 {"flight_time_s", r.flight_time_s}, {"path_length_m", r.path_length_m},
                 {"nav_cpu_util_pct", r.nav_cpu_util_pct}};
    event_ = std::move(t);
    cv_.notify_all();
  }
  void Fail(const std::string& what) {
    std::lock_guard lock(mutex_);
    error_ = what;
    cv_.notify_all();
  }

  // Caller: waits for the next decision or the end.
  Transition Next() {
    std::unique_lock lock(mutex_);
    cv_.wait(lock, [&] { return event_.has_value() || !error_.empty(); });
    if (!error_.empty()) {
      finished_ = true;
      throw std::runtime_error("episode failed: " + error_);
    }
    Transition t = std::move(*event_);
    event_.reset();
    if (t.terminated || t.truncated) finished_ = true;
    mask_ = t.mask;
    return t;
  }
  void Act(int action) {
    std::lock_guard lock(mutex_);
    action_ = action;
    cv_.notify_all();
  }
  void Abort() {
    std::lock_guard lock(mutex_);
    abort_ = true;
    cv_.notify_all();
  }
  bool finished() {
    std::lock_guard lock(mutex_);
    return finished_;
  }
  std::vector<std::uint8_t> mask() {
    std::lock_guard lock(mutex_);
    return mask_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::optional<Transition> event_;
  std::optional<int> action_;
  std::vector<std::uint8_t> mask_;
  Eigen::VectorXd last_obs_ = Eigen::VectorXd::Zero(navstack::kPolicyStateDim);
  double pending_reward_ = 0;
  std::int64_t decisions_ = 0;
  bool abort_ = false, finished_ = false;
  std::string error_;
};

EnvCore::EnvCore(EnvConfig config) : config_(std::move(config)) {
  const std::vector<std::string> boards = sim::FarmCatalog().boards;
  if (std::find(boards.begin(), boards.end(), config_.board) == boards.end()) {
    std::string known;
    for (const std::string& b : boards) known += (known.empty() ? "" : ", ") + b;
    throw std::invalid_argument("board: unknown board '" + config_.board + "' (known: " + known + ")");
  }
  if (config_.overrides.count("strategy.explore")) {
    throw std::invalid_argument("overrides: strategy.explore is the environment's (its actions are yours)");
  }
}

EnvCore::~EnvCore() { Abort(); }

int EnvCore::obs_size() const { return navstack::kPolicyStateDim; }
int EnvCore::action_size() const { return navstack::ActionGrid().size(); }

void EnvCore::Abort() {
  if (hook_) hook_->Abort();
  if (episode_.joinable()) episode_.join();
  hook_.reset();
}

Transition EnvCore::Reset(std::uint64_t seed) {
  Abort();
  api::EpisodeSpec spec;
  spec.world = config_.world;
  spec.seed = seed;
  spec.world_params = config_.world_params;
  spec.board = config_.board;
  spec.method = "enavi";
  spec.clock = "virtual";
  spec.timeout_s = config_.timeout_s;
  spec.policy = config_.policy;
  spec.overrides = config_.overrides;
  // Sampled decisions are the ones the hook takes.
  spec.overrides["strategy.explore"] = 1;
  worlds::WorldRequest request;
  request.world = spec.world;
  request.seed = spec.seed;
  request.params = spec.world_params;
  std::shared_ptr<const sim::PreparedWorld> world = sim::PrepareWorld(worlds::ResolveWorld(request));

  hook_ = std::make_unique<Hook>();
  Hook* hook = hook_.get();
  episode_ = std::thread([hook, spec, world] {
    try {
      navstack::rl::ScopedDecisionHook scoped(hook);
      navstack::rl::Rollout rollout;  // recording makes the controller compute rewards
      sim::EpisodeOptions options;
      options.rollout = &rollout;
      hook->End(sim::RunEpisode(spec, *world, options));
    } catch (const Abandoned&) {
    } catch (const std::exception& e) {
      hook->Fail(e.what());
    }
  });
  Transition first = hook_->Next();
  if (first.terminated || first.truncated) {
    throw std::runtime_error("the episode ended (" + first.end_reason + ") before its first decision");
  }
  first.reward = 0;
  return first;
}

Transition EnvCore::Step(int action) {
  if (!hook_ || hook_->finished()) throw std::logic_error("step() before reset() or after the episode ended");
  const std::vector<std::uint8_t> mask = hook_->mask();
  if (action < 0 || action >= static_cast<int>(mask.size()) || !mask[static_cast<std::size_t>(action)]) {
    throw std::invalid_argument("action " + std::to_string(action) + " is not feasible (see info['action_mask'])");
  }
  hook_->Act(action);
  return hook_->Next();
}

}  // namespace enavi::python
