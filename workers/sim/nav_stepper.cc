#include "workers/sim/nav_stepper.h"

#include <stdexcept>

namespace enavi::sim {
namespace {

constexpr int kN = navstack::rl::kNavStateSize;

}  // namespace

NavStepper::NavStepper(const api::EpisodeSpec& spec, const PreparedWorld& world, EpisodeOptions options)
    : world_(world), decisions_(std::make_unique<navstack::rl::DecisionPort>()) {
  options.decisions = decisions_.get();
  episode_ = std::make_unique<Episode>(spec, world_, options);
  last_distance_ = (world_.world.goal - world_.world.start).norm();
  last_action_ = Eigen::VectorXd::Zero(navstack::rl::kNavActionSize);
}

NavStepper::~NavStepper() = default;

NavTransition NavStepper::First() {
  if (started_) throw std::logic_error("First: called twice");
  started_ = true;
  NavTransition first = Advance();
  if (first.terminated || first.truncated)
    throw std::runtime_error("the episode ended (" + first.end_reason + ") before its first observation");
  first.reward = 0;
  return first;
}

NavTransition NavStepper::Step(const Eigen::VectorXd& action) {
  if (!started_ || finished_) throw std::logic_error("step() before reset() or after the episode ended");
  decisions_->Supply(action);
  const Eigen::VectorXd a = action.cwiseMax(-1.0).cwiseMin(1.0);
  NavTransition t = Advance();
  t.reward += -kSmoothnessWeight * (a - last_action_).squaredNorm();
  last_action_ = a;
  return t;
}

NavTransition NavStepper::Advance() {
  const Eigen::AlignedBox3d& bounds = world_.world.bounds;
  StepStatus status;
  bool left_bounds = false;
  try {
    while ((status = episode_->Step()) == StepStatus::kRunning) {
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
  const double distance = (world_.world.goal - episode_->vehicle().p_WB).norm();
  t.reward = last_distance_ - distance;
  last_distance_ = distance;
  t.t = episode_->vehicle().t;
  if (!left_bounds && status == StepStatus::kAwaitingDecision) {
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
  if (left_bounds) episode_->Stop(EpisodeEnd{.reason = "left_bounds"});
  result_ = episode_->Finish();
  const api::EpisodeResult& r = *result_;
  t.terminated = r.success || r.collided || left_bounds;
  t.truncated = !t.terminated;
  if (r.success) t.reward += kGoalReward;
  if (r.collided || left_bounds) t.reward -= kCrashPenalty;
  t.end_reason = r.end_reason;
  t.metrics = {{"success", r.success ? 1.0 : 0.0}, {"collided", r.collided ? 1.0 : 0.0},
               {"flight_time_s", r.flight_time_s}, {"path_length_m", r.path_length_m},
               {"nav_cpu_util_pct", r.nav_cpu_util_pct}};
  return t;
}

}  // namespace enavi::sim
