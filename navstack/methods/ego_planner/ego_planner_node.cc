#include "navstack/methods/ego_planner/ego_planner_node.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "navstack/methods/method_util.h"
#include "navstack/planning/collision_check.h"
#include "navstack/planning/path_search.h"

namespace enavi::navstack {

/// One callReboundReplan: its result and when planning began.
struct EgoPlannerNode::Attempt {
  std::shared_ptr<const PlanResult> result;
  double t_begin = 0;
  Eigen::Vector3d start_p = Eigen::Vector3d::Zero();
  int tries = 0;          ///< planning calls made (planFromCurrentTraj makes up to three)
  int failed_tries = 0;
};

EgoPlannerNode::EgoPlannerNode(const MethodOptions& options, const EgoPlannerOptions& ego, TaskExecutor* executor,
                               const VehicleState& initial)
    : options_(options),
      ego_(ego),
      executor_(executor),
      state_(initial),
      local_target_(initial.p_WB, options.goal, ego.planning_horizon) {
  options_.planner.Validate();
  options_.flight_bounds.max().z() = std::min(options_.flight_bounds.max().z(), initial.p_WB.z() + ego_.max_climb);
  map_ = std::make_shared<OccupancyMap>(ego_.map);
  // skip_pixel counts pixels of the full sensor frame; the stream may be decimated.
  perception_ = ego_.perception;
  const int decimation = std::max(1, CameraIntrinsics::Default().width / std::max(1, options_.camera.width));
  perception_.stride = std::max(1, ego_.skip_pixel / decimation);
  const Eigen::Vector3d to_goal = options_.goal - initial.p_WB;
  hold_ = HoldAt(initial.p_WB, std::atan2(to_goal.y(), to_goal.x()));
  holding_ = true;
  executor_->Register(TaskId::kPerception, [this] { return OccupancyJob(); });
  executor_->Register(TaskId::kPlanning, [this] { return FsmJob(); });
  executor_->Register(TaskId::kCollision, [this] { return SafetyJob(); });
  executor_->SetRate(TaskId::kPerception, ego_.occupancy_hz);
  executor_->SetRate(TaskId::kPlanning, ego_.fsm_hz);
  executor_->SetRate(TaskId::kCollision, ego_.safety_hz);
}

TaskRates EgoPlannerNode::rates() const {
  TaskRates r;
  r.f_per = ego_.occupancy_hz;
  r.f_plan = ego_.fsm_hz;
  r.f_col = ego_.safety_hz;
  r.collision_on_map_update = false;
  r.f_dif = 0;
  r.resolution = map_->resolution();
  return r;
}

void EgoPlannerNode::OnFrame(DepthFramePtr frame) {
  if (!ego_.newest_frame_only) unmapped_frames_.push_back(frame);
  latest_frame_ = std::move(frame);
}

TrajectorySample EgoPlannerNode::Reference(double t) const {
  if (holding_ || !trajectory_) return hold_;
  return trajectory_->Sample(t);  // after its end: the end point at rest (traj_server.cpp)
}

std::vector<NavEvent> EgoPlannerNode::TakeEvents() { return std::exchange(events_, {}); }

void EgoPlannerNode::AddEvent(std::string kind, std::string detail) {
  events_.push_back({executor_->now(), std::move(kind), std::move(detail)});
}

JobOutput EgoPlannerNode::OccupancyJob() {
  JobOutput out;
  // updateOccupancyCallback: nothing to do unless a depth callback came since the last update.
  std::vector<DepthFramePtr> frames;
  if (ego_.newest_frame_only) {
    if (!latest_frame_ || latest_frame_ == last_mapped_frame_) return out;
    frames = {latest_frame_};
  } else {
    frames = std::exchange(unmapped_frames_, {});
    if (frames.empty()) return out;
  }
  last_mapped_frame_ = frames.back();
  auto updates = std::make_shared<std::vector<MapUpdate>>();
  for (const DepthFramePtr& f : frames) {
    updates->push_back(map_->ComputeUpdate(*f, options_.camera, perception_, &out.work));
    out.work.Add(WorkUnit::kVoxelUpdate,
                 static_cast<std::int64_t>(updates->back().free_keys.size() + updates->back().occupied_keys.size()));
  }
  out.commit = [this, updates] {
    for (const MapUpdate& u : *updates) map_->Apply(u);
  };
  return out;
}

GlobalPathTarget::GlobalPathTarget(const Eigen::Vector3d& start, const Eigen::Vector3d& goal, double horizon)
    : start_(start), goal_(goal), horizon_(horizon), target_(goal) {}

Eigen::Vector3d GlobalPathTarget::Next(const Eigen::Vector3d& from) {
  const Eigen::Vector3d line = goal_ - start_;
  const double length = line.norm();
  if (length < 1e-9) return target_ = goal_;
  const Eigen::Vector3d dir = line / length;
  const double step = horizon_ / 20.0;
  double nearest = 1e300, nearest_s = progress_;
  for (double s = progress_; s < length; s += step) {
    const Eigen::Vector3d p = start_ + s * dir;
    const double d = (p - from).norm();
    // ego_replan_fsm.cpp getLocalTarget: already the progress point too far: return, the old
    // target stands (not the progress point itself, which lies behind it).
    if (s == progress_ && d > horizon_) return target_;
    if (d < nearest) {
      nearest = d;
      nearest_s = s;
    }
    if (d >= horizon_) {
      progress_ = nearest_s;
      return target_ = p;
    }
  }
  return target_ = goal_;
}

std::shared_ptr<const EgoPlannerNode::Attempt> EgoPlannerNode::PlanOnce(TaskId task, const TrajectorySample& start,
                                                                        double t_begin, WorkCounts* work) {
  auto attempt = std::make_shared<Attempt>();
  attempt->t_begin = t_begin;
  attempt->start_p = start.p;
  const Eigen::Vector3d target = local_target_.Next(start.p);
  PlanRequest request;
  request.t_start = t_begin;
  request.start = start;
  request.goal_W = target;
  request.flight_bounds_W = options_.flight_bounds;
  request.seed = PlanSeed(options_.seed, plan_calls_++);
  request.grid = std::make_shared<const VoxelGrid>(
      map_->ExtractGrid(PlanningVolume(start.p, target, options_.flight_bounds, options_.planner), work));
  // dyn_a_star.cpp: a search gives up after 0.2 s, measured from the start of this planning call.
  if (ego_.search_time_limit > 0) {
    const WorkCounts before = *work;
    const double limit = ego_.search_time_limit;
    request.over_budget = [this, task, before, t_begin, limit, call_start = executor_->JobElapsed(task, before, t_begin)](
                              const WorkCounts& plan_work) {
      WorkCounts so_far = before;
      so_far += plan_work;
      return executor_->JobElapsed(task, so_far, t_begin) - call_start > limit;
    };
  }
  PlannerOptions planner = options_.planner;
  planner.robot_radius += 0.5 * (std::sqrt(3.0) - 1.0) * map_->resolution();
  auto result = std::make_shared<PlanResult>(Plan(request, planner));
  *work += result->work;
  attempt->result = std::move(result);
  attempt->tries = 1;
  attempt->failed_tries = attempt->result->ok() ? 0 : 1;
  return attempt;
}

std::shared_ptr<const EgoPlannerNode::Attempt> EgoPlannerNode::PlanFromCurrentTrajectory(TaskId task, double t_begin,
                                                                                         WorkCounts* work) {
  // planFromCurrentTraj: start where the current reference is now, with its velocity and
  // acceleration; three initialisations (previous trajectory, polynomial, random polynomial),
  // here three search seeds.
  TrajectorySample start = Reference(t_begin);
  int tries = 0, failed = 0;
  std::shared_ptr<const Attempt> last;
  for (int i = 0; i < 3; ++i) {
    last = PlanOnce(task, start, t_begin, work);
    ++tries;
    if (last->result->ok()) break;
    ++failed;
  }
  auto out = std::make_shared<Attempt>(*last);
  out->tries = tries;
  out->failed_tries = failed;
  return out;
}

bool EgoPlannerNode::Land(const Attempt& attempt, const std::string& trigger) {
  plan_failures_ += attempt.failed_tries;
  if (!attempt.result->ok()) {
    AddEvent("plan_failed", std::string(ToString(attempt.result->status)) + ": " + attempt.result->message);
    return false;
  }
  // updateTrajInfo(pos, ros::Time::now()): the trajectory starts now, from the state it was
  // planned from when planning began.
  const double t0 = ego_.stamp_at_plan_end ? executor_->now() : attempt.t_begin;
  const Trajectory& planned = *attempt.result->trajectory;
  trajectory_ = t0 == planned.start_time()
                    ? attempt.result->trajectory
                    : std::make_shared<const Trajectory>(planned.spline(), t0, planned.Sample(planned.start_time()).yaw,
                                                         options_.planner, planned.start_yaw_rate());
  local_start_ = attempt.start_p;
  holding_ = false;
  AddEvent("replan", trigger);
  return true;
}

JobOutput EgoPlannerNode::FsmJob() {
  JobOutput out;
  const double t = executor_->now();
  switch (fsm_) {
    case State::kGenNewTraj: {
      // From odometry, zero acceleration; random initialisation when called again in a row.
      const TrajectorySample start = StartFromState(state_);
      auto attempt = PlanOnce(TaskId::kPlanning, start, t, &out.work);
      out.commit = [this, attempt] {
        if (Land(*attempt, consecutive_gen_calls_ == 0 ? "start" : "retry")) {
          fsm_ = State::kExecTraj;
          escape_emergency_ = true;
          consecutive_gen_calls_ = 0;
        } else {
          ++consecutive_gen_calls_;
        }
      };
      return out;
    }
    case State::kReplanTraj: {
      auto attempt = PlanFromCurrentTrajectory(TaskId::kPlanning, t, &out.work);
      out.commit = [this, attempt] {
        if (Land(*attempt, "distance")) fsm_ = State::kExecTraj;
      };
      return out;
    }
    case State::kExecTraj: {
      const Trajectory& traj = *trajectory_;
      const double t_cur = std::min(traj.duration(), t - traj.start_time());
      const Eigen::Vector3d p = traj.Sample(traj.start_time() + t_cur).p;
      State next = fsm_;
      if (t_cur > traj.duration() - 1e-2) {
        next = State::kWaitTarget;  // the trajectory ran out: the node waits for a new target
      } else if ((options_.goal - p).norm() < ego_.thresh_no_replan) {
        next = State::kExecTraj;
      } else if ((local_start_ - p).norm() < ego_.thresh_replan) {
        next = State::kExecTraj;
      } else {
        next = State::kReplanTraj;
      }
      if (next == State::kWaitTarget) {
        // ego_replan_fsm.cpp sets have_target_ = false here: the node waits for a new goal, and
        // the vehicle hovers at the trajectory's end even when that is short of the goal.
        const double to_goal = (options_.goal - p).norm();
        out.commit = [this, to_goal] {
          fsm_ = State::kWaitTarget;
          AddEvent("wait_target", "trajectory ended " + std::to_string(to_goal) + " m from the goal");
        };
      } else if (next != fsm_) {
        out.commit = [this, next] { fsm_ = next; };
      }
      return out;
    }
    case State::kEmergencyStop: {
      const bool publish_hold = escape_emergency_;
      const bool slow = state_.v_WB.norm() < ego_.stop_speed;
      const Eigen::Vector3d p = state_.p_WB;
      const double yaw = YawOf(state_.q_WB);
      out.commit = [this, publish_hold, slow, p, yaw] {
        if (publish_hold) {
          // EmergencyStop(odom_pos): a trajectory that holds the current position.
          holding_ = true;
          hold_ = HoldAt(p, yaw);
        } else if (slow) {
          fsm_ = State::kGenNewTraj;
          consecutive_gen_calls_ = 0;
        }
        escape_emergency_ = false;
      };
      return out;
    }
    case State::kWaitTarget:
      return out;
  }
  return out;
}

JobOutput EgoPlannerNode::SafetyJob() {
  JobOutput out;
  const std::shared_ptr<const Trajectory> traj = trajectory_;
  if (fsm_ == State::kWaitTarget || !traj || holding_) return out;
  const double t = executor_->now();
  const double t_cur = t - traj->start_time();
  if (t_cur >= traj->duration()) return out;
  // Only the first 2/3 of the trajectory while t_cur < 2/3 of its duration.
  const double t_2_3 = traj->duration() * 2.0 / 3.0;
  const double t_to = traj->start_time() + (ego_.check_two_thirds && t_cur < t_2_3 ? t_2_3 : traj->duration());
  const double radius = options_.planner.robot_radius;
  const VoxelGrid grid = map_->ExtractGrid(SweptBox(*traj, t, t_to, radius + map_->resolution()), &out.work);
  const CollisionCheckResult hit = CheckTrajectory(*traj, t, t_to, grid, radius, &out.work);
  if (!hit.collides) return out;
  const double ahead = hit.t_hit - t;
  std::shared_ptr<const Attempt> attempt;
  if (ego_.safety_replan_inline) attempt = PlanFromCurrentTrajectory(TaskId::kCollision, t, &out.work);
  out.commit = [this, traj, attempt, ahead] {
    if (trajectory_ != traj) return;  // a newer plan landed meanwhile (several threads only)
    AddEvent("collision_predicted", "in " + std::to_string(ahead) + " s");
    if (attempt && Land(*attempt, "safety")) {
      fsm_ = State::kExecTraj;
      return;
    }
    if (ego_.emergency_stop && ahead < ego_.emergency_time) {
      AddEvent("emergency_stop");
      fsm_ = State::kEmergencyStop;
    } else {
      fsm_ = State::kReplanTraj;
    }
  };
  return out;
}

}  // namespace enavi::navstack
