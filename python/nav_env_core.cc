#include "python/nav_env_core.h"

#include <stdexcept>

#include "python/env_core.h"

namespace enavi::python {
namespace {

constexpr int kN = navstack::rl::kNavStateSize;

}  // namespace

NavEnvCore::NavEnvCore(NavEnvConfig config) : config_(std::move(config)) {
  CheckBoard(config_.board);
  if (config_.decimation < 1 || config_.decimation > 10 || 640 % config_.decimation || 480 % config_.decimation)
    throw std::invalid_argument("image: the 640x480 sensor decimated by a whole n in [1, 10] (64x48 at n = 10), got n = " +
                                std::to_string(config_.decimation));
  for (const auto& [name, value] : config_.overrides)
    if (name.rfind("learned.", 0) == 0 || name == "camera.decimation")
      throw std::invalid_argument("overrides: " + name + " is the environment's (image, latency, multiply_adds)");
  width_ = 640 / config_.decimation;
  height_ = 480 / config_.decimation;
  multiply_adds_ = config_.multiply_adds > 0 ? config_.multiply_adds
                                             : navstack::rl::DefaultNavArchitecture(width_, height_).multiply_adds();
}

// The episode goes first (members go in reverse order), before the port it writes to.
NavEnvCore::~NavEnvCore() = default;

NavTransition NavEnvCore::Reset(std::uint64_t seed) {
  episode_.reset();
  finished_ = true;
  api::EpisodeSpec spec =
      EnvEpisodeSpec("learned", config_.world, config_.world_params, config_.board, config_.timeout_s, seed);
  spec.overrides = config_.overrides;
  spec.overrides["camera.decimation"] = config_.decimation;
  spec.overrides["learned.zero_latency"] = config_.zero_latency ? 1 : 0;
  spec.overrides["learned.multiply_adds"] = config_.zero_latency ? 0 : static_cast<double>(multiply_adds_);
  world_ = PrepareSpecWorld(spec);

  decisions_ = std::make_unique<navstack::rl::DecisionPort>();
  sim::EpisodeOptions options;
  options.decisions = decisions_.get();
  episode_ = std::make_unique<sim::Episode>(spec, *world_, options);
  last_distance_ = (world_->world.goal - world_->world.start).norm();
  last_action_ = Eigen::VectorXd::Zero(navstack::rl::kNavActionSize);
  finished_ = false;
  NavTransition first = Advance();
  if (first.terminated || first.truncated)
    throw std::runtime_error("the episode ended (" + first.end_reason + ") before its first observation");
  first.reward = 0;
  return first;
}

NavTransition NavEnvCore::Step(const Eigen::VectorXd& action) {
  if (finished_) throw std::logic_error("step() before reset() or after the episode ended");
  decisions_->Supply(action);
  const Eigen::VectorXd a = action.cwiseMax(-1.0).cwiseMin(1.0);
  NavTransition t = Advance();
  t.reward += -kSmoothnessWeight * (a - last_action_).squaredNorm();
  last_action_ = a;
  return t;
}

NavTransition NavEnvCore::Advance() {
  const Eigen::AlignedBox3d& bounds = world_->world.bounds;
  sim::StepStatus status;
  bool left_bounds = false;
  try {
    while ((status = episode_->Step()) == sim::StepStatus::kRunning) {
      if (!bounds.contains(episode_->vehicle().p_WB)) {
        left_bounds = true;
        break;
      }
    }
  } catch (...) {
    finished_ = true;
    throw;
  }
  NavTransition t;
  const double distance = (world_->world.goal - episode_->vehicle().p_WB).norm();
  t.reward = last_distance_ - distance;
  last_distance_ = distance;
  t.t = episode_->vehicle().t;
  if (!left_bounds && status == sim::StepStatus::kAwaitingDecision) {
    const Eigen::VectorXd& obs = decisions_->observation();
    t.depth.assign(obs.data(), obs.data() + (obs.size() - kN));
    t.state = obs.tail<kN>();
    last_ = t;
    return t;
  }
  // The end: the last observation again, closed by the outcome.
  finished_ = true;
  t.depth = last_.depth;
  t.state = last_.state;
  if (left_bounds) {
    t.terminated = true;
    t.reward -= kCrashPenalty;
    t.end_reason = "left_bounds";
    t.metrics = {{"success", 0.0}, {"collided", 0.0}, {"flight_time_s", t.t}};
    return t;
  }
  const api::EpisodeResult r = episode_->Finish();
  t.terminated = r.success || r.collided;
  t.truncated = !t.terminated;
  if (r.success) t.reward += kGoalReward;
  if (r.collided) t.reward -= kCrashPenalty;
  t.end_reason = r.end_reason;
  t.metrics = {{"success", r.success ? 1.0 : 0.0}, {"collided", r.collided ? 1.0 : 0.0},
               {"flight_time_s", r.flight_time_s}, {"path_length_m", r.path_length_m},
               {"nav_cpu_util_pct", r.nav_cpu_util_pct}};
  return t;
}

}  // namespace enavi::python
