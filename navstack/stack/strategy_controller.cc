#include "navstack/stack/strategy_controller.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>


namespace enavi::navstack {
namespace {

// Plans never go slower than this, m/s (planner.v_max's range starts at 0.2): at the limit's
// zero, the vehicle is already as near as the margin, and a crawl still lets the planner back off.
constexpr double kMinSpeedLimit = 0.3;

// The body's radius, plus half a cell: a coarse map may put an obstacle that much nearer.
double ReactionMargin(const StrategyInputs& in) { return in.robot_radius + 0.5 * in.flight.resolution; }

ConstraintInputs ToConstraints(const StrategyInputs& in) {
  ConstraintInputs c;
  c.f_sen = in.f_sen;
  c.trajectory_duration = in.trajectory_duration > 0 ? in.trajectory_duration : std::numeric_limits<double>::infinity();
  c.wcet = in.wcet;
  c.num_cores = in.cores;
  c.u_cur = in.u_cur;
  c.current = in.current;
  c.reaction.d0 = in.d_ahead;
  c.reaction.speed = in.flight.v_WB.norm();
  c.reaction.a_brake = in.a_brake;
  c.reaction.margin = ReactionMargin(in);
  return c;
}

rl::PolicyFile RequirePolicy(const StrategyOptions& o) {
  if (!o.policy) throw std::invalid_argument("strategy: E-Navi needs a frequency-adapter policy");
  if (o.record && o.choice == rl::ActionChoice::kLeastLoad) {
    throw std::invalid_argument(
        "strategy.least_load: the rule's decisions are not the policy's; a rollout for training "
        "cannot be recorded with it");
  }
  return *o.policy;
}

}  // namespace

StrategyController::StrategyController(const StrategyOptions& options)
    : options_(options),
      adapter_(RequirePolicy(options), options.constraints, {}, options.choice, options.decisions),
      resolution_(options.resolution),
      overload_(options.overload),
      rng_(options.seed) {}

double StrategyController::Reward(const StrategyInputs& in, bool collided, bool reached_goal) const {
  rl::RewardInputs r;
  r.dt = previous_ ? in.t - previous_->t : 0.0;
  r.u_nav = in.u_cur;
  r.u_total = in.cores;
  r.dist_prev = previous_ ? previous_->distance_to_goal : in.distance_to_goal;
  r.dist = in.distance_to_goal;
  r.straight_length = std::max(in.straight_length, 1e-3);
  r.path_prev = previous_ ? previous_->expected_path : 0.0;
  r.path = in.expected_path;
  r.stops = in.stops - (previous_ ? previous_->stops : 0);
  r.collided = collided;
  r.reached_goal = reached_goal;
  return rl::ComputeReward(r, options_.rewards).total;
}

StrategyDecision StrategyController::Decide(const StrategyInputs& in, const Eigen::Vector3d& goal_W) {
  StrategyDecision d;
  // The previous action's reward is known now: what its epoch cost and achieved.
  if (options_.record && !rollout_.steps.empty()) rollout_.steps.back().reward = Reward(in, false, false);

  rl::RolloutStep step;
  const rl::FrequencyDecision f = adapter_.Decide(ToConstraints(in), in.flight, options_.mode, &rng_, &d.work,
                                                  options_.record ? &step : nullptr);
  d.fallback = f.fallback_used;
  d.reaction_infeasible = f.reaction_infeasible;
  if (options_.record) rollout_.steps.push_back(std::move(step));
  d.pending = f.pending;
  if (f.pending) pending_.emplace(f, in);
  else ApplyFrequencies(f, in, &d);

  // Paper Sec. V.D: overload that persists sends the vehicle into a hover.
  const OverloadMonitor::Update overload = overload_.Observe(in.t, in.u_cur, in.cores);
  failsafe_ = overload.mode == OverloadMonitor::Mode::kFailSafe;
  d.failsafe = failsafe_;
  d.recovered = overload.recovered;

  d.resolution = resolution_.Select(in.flight.p_WB, goal_W).resolution;
  previous_ = in;
  return d;
}

void StrategyController::ApplyFrequencies(const rl::FrequencyDecision& f, const StrategyInputs& in,
                                          StrategyDecision* d) const {
  d->f = f.f;
  // Paper Sec. V.D: over capacity, periods are scaled down proportionally.
  if (in.u_cur > in.cores * options_.constraints.capacity_fraction) {
    const ScaledFrequencies scaled = ScaleToCapacity(ToConstraints(in), options_.constraints);
    d->f = scaled.f;
    d->scaled = scaled.scaled;
  }
  // When even the quickest rates cannot stop in time, new plans fly no faster than the chosen
  // rates (possibly scaled above) can stop from. Otherwise the rates carry it: limiting every plan
  // by the nearest obstacle ahead held the vehicle back round every corner (canyon seed 1 on
  // three boards: 4-8 % longer flights) for walls the chosen rates would have caught anyway.
  if (d->reaction_infeasible) {
    d->v_limit = std::max(kMinSpeedLimit, SafeSpeed(in.d_ahead, ReactionMargin(in), in.a_brake,
                                                    ReactionTime(d->f, in.wcet, in.f_sen)));
  }
}

void StrategyController::Resolve(StrategyDecision* decision) {
  if (!decision->pending) return;
  if (!pending_) throw std::logic_error("strategy: no decision of this controller is pending");
  auto& [f, in] = *pending_;
  adapter_.Resolve(&f, options_.record ? &rollout_.steps.back() : nullptr);
  ApplyFrequencies(f, in, decision);
  decision->pending = false;
  pending_.reset();
}

void StrategyController::OnCoarserMapRejected(double resolution) {
  const std::vector<double>& ladder = resolution_.options().ladder;
  const auto it = std::find(ladder.begin(), ladder.end(), resolution);
  if (it != ladder.end()) resolution_.ReportPlanningOutcome(static_cast<int>(it - ladder.begin()), false);
}

void StrategyController::OnPlanned(double t, bool found, const PathScoreInputs& path) {
  resolution_.ReportPlanningOutcome(resolution_.level(), found);
  if (found) resolution_.OnPathPlanned(t, path);
}

void StrategyController::Finish(const StrategyInputs& last, bool collided, bool reached_goal) {
  // A decision whose action came but whose job did not finish before the episode ended: the
  // rollout records the action taken.
  if (pending_) {
    adapter_.Resolve(&pending_->first, options_.record ? &rollout_.steps.back() : nullptr);
    pending_.reset();
  }
  if (!options_.record || rollout_.steps.empty()) return;
  rl::RolloutStep& tail = rollout_.steps.back();
  tail.reward = Reward(last, collided, reached_goal);
  tail.done = collided || reached_goal;
  if (!tail.done) {
    // Time-out: not a terminal; bootstrap from the critic's value of the final state.
    rl::RolloutStep probe;
    adapter_.Decide(ToConstraints(last), last.flight, rl::ActMode::kGreedy, nullptr, nullptr, &probe);
    rollout_.bootstrap_value = probe.value;
  }
}

}  // namespace enavi::navstack
