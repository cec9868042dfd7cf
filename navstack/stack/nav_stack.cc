#include "navstack/stack/nav_stack.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "navstack/methods/method_util.h"
#include "navstack/planning/collision_check.h"
#include "navstack/planning/observed_space.h"

namespace enavi::navstack {

NavStack::NavStack(const NavStackOptions& options, TaskExecutor* executor, const VehicleState& initial)
    : options_(options),
      executor_(executor),
      map_(std::make_unique<OccupancyMap>(options.map)),
      pending_resolution_(options.map.resolution),
      state_(initial) {
  options_.planner.Validate();
  options_.flight_bounds.max().z() = std::min(options_.flight_bounds.max().z(), initial.p_WB.z() + options_.max_climb);
  const Eigen::Vector3d to_goal = options_.goal - initial.p_WB;
  hold_ = HoldAt(initial.p_WB, std::atan2(to_goal.y(), to_goal.x()));
  executor_->Register(TaskId::kPerception, [this] { return PerceptionJob(); });
  executor_->Register(TaskId::kPlanning, [this] { return PlanningJob(); });
  executor_->Register(TaskId::kCollision, [this] { return CollisionJob(); });
  executor_->Register(TaskId::kDifference, [this] { return DifferenceJob(); });
  straight_length_ = to_goal.norm();
  last_p_ = initial.p_WB;
  if (options_.strategy) {
    strategy_ = std::make_unique<StrategyController>(*options_.strategy);
    options_.rates.resolution = strategy_->resolution();
    options_.map.resolution = strategy_->resolution();
    map_ = std::make_unique<OccupancyMap>(options_.map);
    pending_resolution_ = options_.map.resolution;
    executor_->Register(TaskId::kEci, [this] { return EciJob(); });
    executor_->Register(TaskId::kAdapter, [this] { return AdapterJob(); });
    executor_->SetRate(TaskId::kEci, options_.f_sen);
    executor_->SetRate(TaskId::kAdapter, options_.strategy->f_adapt);
  }
  SetRates(options_.rates);
  if (rates_.f_plan == 0) RequestReplan("start");
}

void NavStack::OnState(const VehicleState& state) {
  flown_ += (state.p_WB - last_p_).norm();
  last_p_ = state.p_WB;
  state_ = state;
}

void NavStack::Stop(const char* why) {
  stopped_ = true;
  ++stops_;
  hold_ = HoldAt(state_.p_WB, YawOf(state_.q_WB));
  AddEvent(why);
}

void NavStack::Scan() {
  scanning_ = true;
  scan_t0_ = executor_->now();
  scan_reset_done_ = false;
  ++stops_;
  hold_ = HoldAt(state_.p_WB, YawOf(state_.q_WB));
  AddEvent("scan");
}

bool NavStack::Hovering(double t) const { return stopped_ || scanning_ || !trajectory_ || t >= trajectory_->end_time(); }

void NavStack::SetRates(const TaskRates& rates) {
  rates_ = rates;
  executor_->SetRate(TaskId::kPerception, rates.f_per);
  executor_->SetRate(TaskId::kPlanning, rates.f_plan);
  executor_->SetRate(TaskId::kCollision, rates.collision_on_map_update ? 0.0 : rates.f_col);
  executor_->SetRate(TaskId::kDifference, rates.f_dif);
  if (rates.resolution != pending_resolution_) {
    pending_resolution_ = rates.resolution;
    AddEvent("resolution", std::to_string(rates.resolution));
  }
}

void NavStack::OnFrame(DepthFramePtr frame) {
  latest_frame_ = std::move(frame);
  // Triggered planning also replans ahead of the end of the current trajectory, so the vehicle
  // does not stop at every local goal.
  if (rates_.f_plan == 0 && trajectory_ && !stopped_ && !scanning_) {
    const double left = trajectory_->end_time() - latest_frame_->t;
    const bool ends_at_goal = (trajectory_->end_point() - options_.goal).norm() < 0.1;
    if (left < options_.replan_before_end_s && !ends_at_goal) RequestReplan("trajectory_end");
  }
  // Without a trajectory to follow (stopped, or the last plan failed) triggered planning retries
  // at a bounded rate; a failsafe hover waits for the overload to clear instead.
  if (rates_.f_plan == 0 && !failsafe_ && (stopped_ || scanning_ || !trajectory_) && latest_frame_->t >= next_retry_t_) {
    next_retry_t_ = latest_frame_->t + options_.plan_retry_period_s;
    RequestReplan("retry");
  }
}

TrajectorySample NavStack::Reference(double t) const {
  if (scanning_) {
    TrajectorySample s = hold_;
    s.yaw_rate = options_.scan_yaw_rate;
    s.yaw = WrapAngle(hold_.yaw + s.yaw_rate * (t - scan_t0_));
    return s;
  }
  if (stopped_ || !trajectory_) return hold_;
  // A plan that landed before its own start time hands over at that time.
  if (t < trajectory_->start_time() && previous_trajectory_) return previous_trajectory_->Sample(t);
  return trajectory_->Sample(t);
}

std::vector<NavEvent> NavStack::TakeEvents() { return std::exchange(events_, {}); }

void NavStack::AddEvent(std::string kind, std::string detail) {
  events_.push_back({executor_->now(), std::move(kind), std::move(detail)});
}

void NavStack::RequestReplan(const char* why) {
  // The baseline's 20 Hz timer replans anyway; a trigger would only collide with it.
  if (rates_.f_plan > 0) return;
  // The executor coalesces: a trigger while a job is released releases one more after it, and
  // further ones join that. Each plan is billed to the first trigger it answers.
  std::string& slot = executor_->active(TaskId::kPlanning) ? next_trigger_ : pending_trigger_;
  if (slot.empty()) slot = why;
  executor_->Trigger(TaskId::kPlanning, options_.triggered_plan_deadline_s);
}

void NavStack::PromoteNextTrigger() {
  // A planning job finished: the trigger that asked for the next one now names it.
  if (rates_.f_plan == 0 && pending_trigger_.empty()) pending_trigger_ = std::exchange(next_trigger_, {});
}

JobOutput NavStack::PerceptionJob() {
  JobOutput out;
  const DepthFramePtr frame = latest_frame_;
  const bool reset = map_reset_pending_;
  const bool rebuild = reset || pending_resolution_ != map_->resolution();
  if (!rebuild && (!frame || frame == last_mapped_frame_)) return out;
  map_reset_pending_ = false;
  // A resolution change rebuilds the map from recent frames (paper Sec. V.A); the rebuilt map
  // replaces the current one when this job finishes. A map reset is the same rebuild, carrying
  // only the near cells.
  std::shared_ptr<OccupancyMap> next;
  if (rebuild)
    next = map_->Rebuilt(pending_resolution_, &out.work,
                         reset ? options_.scan_reset_distance : std::numeric_limits<double>::infinity());
  // A coarser map inflates every obstacle by up to a cell: the trajectory being flown, planned on
  // the finer map, can run into it a few tenths of a second ahead, and the check would stop the
  // vehicle for a wall it was clearing (canyon opi5 seed 1 and tx2 seed 2, 0.4 -> 0.5 m). Such a
  // map is not adopted; the Resolution Adapter counts that level as failed.
  double rejected = 0.0;
  const std::shared_ptr<const Trajectory> traj = trajectory_;
  const double now = executor_->now();
  const bool coarser_checked = next && !reset && strategy_ && next->resolution() > map_->resolution() && traj &&
                               !stopped_ && !scanning_ && now < traj->end_time();
  if (coarser_checked && PredictHit(*next, *traj, now, nullptr, &out.work).collides) {
    rejected = next->resolution();
    next.reset();
  }
  // A coarser map adopted after that check holds the trajectory being flown clear: the paper's
  // planning triggers are the collision and change detections (Sec. III), and nothing on the
  // coarser map asks for a new plan. Replanning anyway picked another route at each coarsening
  // (docs/results.md, "Wind, turbulence and movers").
  const std::shared_ptr<const Trajectory> cleared = coarser_checked && next ? traj : nullptr;
  const OccupancyMap& target = next ? *next : *map_;
  std::shared_ptr<const MapUpdate> update;
  if (frame && frame != last_mapped_frame_) {
    update = std::make_shared<const MapUpdate>(
        target.ComputeUpdate(*frame, options_.camera, options_.perception, &out.work));
    // Apply runs at the finish; its updateNode calls are priced here, one per key.
    out.work.Add(WorkUnit::kVoxelUpdate,
                 static_cast<std::int64_t>(update->free_keys.size() + update->occupied_keys.size()));
    last_mapped_frame_ = frame;
  }
  out.commit = [this, next, update, reset, rejected, cleared] {
    if (rejected > 0.0) {
      AddEvent("resolution_kept", std::to_string(map_->resolution()) + " (" + std::to_string(rejected) +
                                      " would put the trajectory in collision)");
      strategy_->OnCoarserMapRejected(rejected);
      if (pending_resolution_ == rejected) pending_resolution_ = map_->resolution();
    }
    if (next) map_ = next;
    if (update) map_->Apply(*update);
    // A refined map is what the Resolution Adapter asked for, a reset map what the scan asked
    // for: plan on it now. A coarsened one that keeps the trajectory clear needs no new plan
    // (unless another plan replaced that trajectory meanwhile, unchecked on this map).
    if (next && (strategy_ || reset) && !(cleared && cleared == trajectory_))
      RequestReplan(reset ? "map_reset" : "resolution");
    if (rates_.collision_on_map_update && trajectory_) executor_->Trigger(TaskId::kCollision, 1.0 / rates_.f_per);
  };
  return out;
}

CollisionCheckResult NavStack::PredictHit(const OccupancyMap& map, const Trajectory& traj, double t,
                                          const ObservedSpaceRule* observed, WorkCounts* work) const {
  const double radius = options_.planner.robot_radius;
  const VoxelGrid grid = map.ExtractGrid(SweptBox(traj, t, traj.end_time(), radius + map.resolution()), work);
  CollisionCheckResult hit = CheckTrajectory(traj, t, traj.end_time(), grid, radius, work, observed);
  // A hit right where the vehicle is means it is already inside inflated space and the plan is
  // escaping from it (the planner relaxes clearance near its start): look further along instead
  // of stopping the escape over and over.
  if (hit.collides && hit.t_hit - t < options_.escape_window_s && t + 2 * options_.escape_window_s < traj.end_time())
    hit = CheckTrajectory(traj, t + 2 * options_.escape_window_s, traj.end_time(), grid, radius, work, observed);
  return hit;
}

JobOutput NavStack::CollisionJob() {
  JobOutput out;
  const std::shared_ptr<const Trajectory> traj = trajectory_;
  const double t = executor_->now();
  if (!traj || stopped_ || scanning_ || t >= traj->end_time()) return out;
  const ObservedSpaceRule observed = ObservedRule(state_.p_WB);
  const CollisionCheckResult hit = PredictHit(*map_, *traj, t, &observed, &out.work);
  if (!hit.collides) return out;
  // As Ego-Planner's safety check (ego_replan_fsm.cpp, checkCollisionCallback): replan at once,
  // inside this job and on the map that found the hit (planFromCurrentTraj); stop only when that
  // fails and the hit is near. A plan made on a map that changed while it was made is replaced
  // here, not answered by a stop (s2 nx on the emulated clock: five stops in 2.2 s).
  std::shared_ptr<const PlanAttempt> attempt = MakePlan(t, &out.work);
  out.commit = [this, traj, hit, attempt] {
    if (trajectory_ != traj) return;  // a newer plan landed meanwhile
    const double now = executor_->now();
    AddEvent("collision_predicted", (hit.unobserved ? "unobserved space in " : "in ") + std::to_string(hit.t_hit - now) + " s");
    if (strategy_) strategy_->OnCollisionTrigger(now);
    if (Land(*attempt, "collision")) return;
    if (hit.t_hit - now < options_.emergency_horizon_s) {
      Stop("emergency_stop");
      emergency_stopped_ = true;
      emergency_stop_t_ = now;
    }
    RequestReplan("collision");
  };
  return out;
}

JobOutput NavStack::DifferenceJob() {
  JobOutput out;
  const DepthFramePtr frame = latest_frame_;
  const DepthFramePtr previous = last_diff_frame_;
  if (!frame || frame == previous) return out;
  last_diff_frame_ = frame;
  if (!previous) return out;
  const DifferenceResult diff =
      DetectDifference(*previous, *frame, options_.camera, options_.difference, &out.work);
  if (diff.trigger) {
    out.commit = [this, diff] {
      AddEvent("difference", std::to_string(diff.changed_fraction));
      RequestReplan("difference");
    };
  }
  return out;
}

JobOutput NavStack::PlanningJob() {
  JobOutput out;
  const double t = executor_->now();
  const std::string trigger = rates_.f_plan > 0 ? "timer" : std::exchange(pending_trigger_, {});
  // Braking after an emergency stop: plan once the vehicle has (nearly) come to rest; the retry
  // while stopped (OnFrame) asks again.
  if (emergency_stopped_ && state_.v_WB.norm() >= options_.stop_speed) {
    out.commit = [this] { PromoteNextTrigger(); };
    return out;
  }
  std::shared_ptr<const PlanAttempt> attempt = MakePlan(t, &out.work);
  out.commit = [this, attempt, trigger] {
    PromoteNextTrigger();
    Land(*attempt, trigger);
  };
  return out;
}

std::shared_ptr<const NavStack::PlanAttempt> NavStack::MakePlan(double t, WorkCounts* work) {
  auto attempt = std::make_shared<PlanAttempt>();
  attempt->t = t;
  // Continue the current reference from where the vehicle will be when this plan lands; start
  // from the measured state when there is no reference to continue or it has drifted away.
  const double t_start = t + plan_latency_estimate_;
  TrajectorySample start = Reference(t_start);
  const bool from_state = !trajectory_ || stopped_ || scanning_ || (Reference(t).p - state_.p_WB).norm() > options_.max_tracking_error;
  if (from_state) start = StartFromState(state_);
  PlanRequest request;
  request.t_start = from_state ? t : t_start;
  request.start = start;
  request.goal_W = options_.goal;
  request.flight_bounds_W = options_.flight_bounds;
  request.seed = PlanSeed(options_.seed, plan_calls_++);
  VoxelGrid grid = map_->ExtractGrid(PlanningVolume(start.p, options_.goal, options_.flight_bounds, options_.planner), work);
  // The Resolution Adapter scores the path against the map's obstacle density (paper Sec. V.A):
  // what was seen, before unobserved space near the vehicle is blocked.
  if (strategy_) {
    for (const CellState c : grid.cells) attempt->score.occupied_cells += c == CellState::kOccupied;
    attempt->score.total_cells = static_cast<double>(grid.cells.size());
    work->Add(WorkUnit::kGridCell, static_cast<std::int64_t>(grid.cells.size()));
  }
  BlockUnobserved(ObservedRule(start.p), &grid, work);
  request.grid = std::make_shared<const VoxelGrid>(std::move(grid));
  // The planner measures clearance to occupied cell centres (minus half a cell); the collision
  // check to whole cells. At a coarse resolution a cell's corner is up to (sqrt(3) - 1) / 2 of a
  // cell nearer than that, so plan with that much more radius, or every plan is "in collision".
  PlannerOptions planner = options_.planner;
  planner.robot_radius += 0.5 * (std::sqrt(3.0) - 1.0) * map_->resolution();
  planner.v_max = std::min(planner.v_max, speed_limit_);  // E-Navi: the reaction constraint's limit
  attempt->v_max = planner.v_max;
  attempt->result = Plan(request, planner);
  *work += attempt->result.work;
  if (strategy_ && attempt->result.ok()) {
    attempt->score.path_length = attempt->result.path_length;
    attempt->score.straight_length = (attempt->result.goal_used_W - start.p).norm();
  }
  return attempt;
}

bool NavStack::Land(const PlanAttempt& attempt, const std::string& trigger) {
  const PlanResult& result = attempt.result;
  if (strategy_) strategy_->OnPlanned(executor_->now(), result.ok(), attempt.score);
  // Latency = board time from start to finish; the next plan aims that far ahead.
  const double latency = executor_->now() - attempt.t;
  plan_latency_estimate_ = std::clamp(0.7 * plan_latency_estimate_ + 0.3 * 1.2 * latency, 0.02, 0.5);
  if (!result.ok()) {
    ++plan_failures_;
    AddEvent("plan_failed", std::string(ToString(result.status)) + ": " + result.message);
    if (++failed_plans_in_row_ >= options_.scan_after_failures && !scanning_ && !failsafe_ &&
        Hovering(executor_->now()))
      Scan();
    // A full turn has shown everything within the mapping range and no plan was found: what
    // blocks the way is beyond it, where the vehicle cannot look again from here.
    const double full_turn_s = 2.0 * std::numbers::pi / options_.scan_yaw_rate;
    if (scanning_ && !scan_reset_done_ && options_.scan_reset_distance > 0 &&
        executor_->now() - scan_t0_ >= full_turn_s) {
      scan_reset_done_ = true;
      map_reset_pending_ = true;
      AddEvent("map_reset", std::to_string(options_.scan_reset_distance));
    }
    return false;
  }
  failed_plans_in_row_ = 0;
  if (failsafe_) return false;  // hovering until the overload clears
  if (emergency_stopped_ && attempt.t < emergency_stop_t_) return false;  // planned from before the stop
  previous_trajectory_ = stopped_ || scanning_ ? nullptr : trajectory_;
  trajectory_ = result.trajectory;
  plan_speed_cap_ = attempt.v_max;
  stopped_ = false;
  emergency_stopped_ = false;
  scanning_ = false;
  last_search_path_ = result.search_path;
  ++replans_;
  AddEvent("replan", trigger);
  return true;
}

TaskWcets NavStack::RecentWcets() const {
  return {executor_->stats(TaskId::kPerception).cost_recent_s, executor_->stats(TaskId::kPlanning).cost_recent_s,
          executor_->stats(TaskId::kCollision).cost_recent_s, executor_->stats(TaskId::kDifference).cost_recent_s};
}

ObservedSpaceRule NavStack::ObservedRule(const Eigen::Vector3d& start) const {
  // Reaction time at the current rates (reaction_constraint.h): frame, map update, check, plan.
  const TaskFrequencies f{rates_.f_per, rates_.collision_on_map_update ? rates_.f_per : rates_.f_col, rates_.f_dif};
  const double speed = std::min(options_.planner.v_max, speed_limit_);
  ObservedSpaceRule rule = ObservedSpaceRule::For(state_.p_WB, start, speed, ReactionTime(f, RecentWcets(), options_.f_sen),
                                                  options_.planner.a_max, options_.planner.robot_radius,
                                                  map_->resolution(), options_.camera);
  // Never ask to have seen beyond what the map is built from.
  rule.reach = std::min(rule.reach, options_.perception.max_range);
  return rule;
}

JobOutput NavStack::EciJob() {
  JobOutput out;
  const DepthFramePtr frame = latest_frame_;
  if (!frame || frame == last_eci_frame_) return out;
  last_eci_frame_ = frame;
  const Eigen::Vector3d v_C = frame->X_WC.linear().transpose() * frame->v_W;
  const EciResult r = ComputeEci(frame->image, options_.camera, v_C, options_.eci, &out.work);
  out.commit = [this, eci = r.eci, d_ahead = r.d_ahead] {
    d_eci_ = eci_tracker_.Update(eci);
    eci_ = eci;
    d_ahead_ = d_ahead;
    strategy_->ObserveEci(executor_->now(), eci);
  };
  return out;
}

StrategyInputs NavStack::GatherStrategyInputs(double t) {
  StrategyInputs in;
  in.t = t;
  in.f_sen = options_.f_sen;
  in.cores = executor_->cores();
  // System monitor: navigation utilisation over the epoch since the last decision, in cores.
  double busy = 0;
  for (int i = 0; i < kTaskCount; ++i)
    if (IsNavigationTask(static_cast<TaskId>(i))) busy += executor_->stats(static_cast<TaskId>(i)).busy_s;
  in.u_cur = t > last_adapt_t_ ? (busy - last_adapt_busy_) / (t - last_adapt_t_) : 0.0;
  last_adapt_t_ = t;
  last_adapt_busy_ = busy;
  in.wcet = RecentWcets();
  in.trajectory_duration = trajectory_ ? trajectory_->duration() : std::numeric_limits<double>::infinity();
  in.current = {rates_.f_per, rates_.f_col, rates_.f_dif};
  in.d_ahead = d_ahead_;
  in.a_brake = options_.planner.a_max;
  in.robot_radius = options_.planner.robot_radius;
  in.flight.eci = eci_;
  in.flight.d_eci = d_eci_;
  in.flight.resolution = map_->resolution();
  in.flight.p_WB = state_.p_WB;
  in.flight.v_WB = state_.v_WB;
  in.flight.q_WB = state_.q_WB;
  in.flight.p_goal_W = options_.goal;
  in.distance_to_goal = (options_.goal - state_.p_WB).norm();
  in.straight_length = straight_length_;
  // |L_e|: flown so far + what the current plan still covers + straight on to the goal.
  double planned = 0;
  Eigen::Vector3d end = state_.p_WB;
  if (trajectory_ && !stopped_ && t < trajectory_->end_time()) {
    Eigen::Vector3d p = trajectory_->Sample(t).p;
    for (double s = t + 0.2; s < trajectory_->end_time() + 0.2; s += 0.2) {
      const Eigen::Vector3d q = trajectory_->Sample(s).p;
      planned += (q - p).norm();
      p = q;
    }
    end = p;
  }
  in.expected_path = flown_ + planned + (options_.goal - end).norm();
  in.stops = stops_;
  return in;
}

JobOutput NavStack::AdapterJob() {
  JobOutput out;
  const StrategyInputs in = GatherStrategyInputs(executor_->now());
  auto decision = std::make_shared<StrategyDecision>(strategy_->Decide(in, options_.goal));
  out.work = decision->work;
  out.awaits_decision = decision->pending;
  out.commit = [this, decision] {
    strategy_->Resolve(decision.get());
    TaskRates r = rates_;
    r.f_per = decision->f.f_per;
    r.f_col = decision->f.f_col;
    r.f_dif = decision->f.f_dif;
    r.resolution = decision->resolution;
    SetRates(r);
    // The limit binds plans made from now on. A plan made for more speed is replaced at once, or
    // the vehicle flies it on at its old speed towards the obstacle that set the limit; and a plan
    // made under a limit is replaced once there is none, or the vehicle crawls on at the old
    // limit until something else triggers a plan (6 s at 0.5 m/s, s4 seed 1 on opi5).
    speed_limit_ = decision->v_limit;
    if (trajectory_ && !stopped_ && !scanning_) {
      if (plan_speed_cap_ > speed_limit_ && state_.v_WB.norm() > speed_limit_) RequestReplan("speed_limit");
      else if (std::isinf(speed_limit_) && plan_speed_cap_ < options_.planner.v_max) RequestReplan("speed_limit_lifted");
    }
    if (decision->fallback) AddEvent("constraint_fallback");
    if (decision->scaled) AddEvent("period_scaling");
    if (decision->failsafe && !failsafe_) {
      failsafe_ = true;
      Stop("failsafe");
    }
    if (decision->recovered && failsafe_) {
      failsafe_ = false;
      AddEvent("failsafe_recovered");
      RequestReplan("recovered");
    }
  };
  return out;
}

void NavStack::FinishEpisode(bool collided, bool reached_goal) {
  if (strategy_) strategy_->Finish(GatherStrategyInputs(executor_->now()), collided, reached_goal);
}

const rl::Rollout* NavStack::rollout() const {
  return strategy_ && strategy_->options().record ? &strategy_->rollout() : nullptr;
}

}  // namespace enavi::navstack
