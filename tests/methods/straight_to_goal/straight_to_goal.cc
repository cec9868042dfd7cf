#include "tests/methods/straight_to_goal/straight_to_goal.h"

#include <memory>
#include <utility>
#include <vector>

#include "navstack/planning/planner.h"
#include "navstack/runtime/executor.h"

namespace enavi::navstack {
namespace {

// Plans once from the start to the goal on an empty map and follows that.
class StraightToGoal final : public Navigator {
 public:
  StraightToGoal(const MethodOptions& o, TaskExecutor* exec, const VehicleState& s0)
      : options_(o), exec_(exec), start_(s0) {
    exec_->Register(TaskId::kPlanning, [this] { return Plan(); });
    exec_->SetRate(TaskId::kPlanning, 1.0);
  }
  void OnFrame(DepthFramePtr) override {}
  void OnState(const VehicleState&) override {}
  TrajectorySample Reference(double t) const override {
    if (traj_) return traj_->Sample(t);
    TrajectorySample hold;
    hold.p = start_.p_WB;
    return hold;
  }
  std::vector<NavEvent> TakeEvents() override { return std::exchange(events_, {}); }
  TaskRates rates() const override { return {}; }
  double map_resolution() const override { return 0.1; }
  std::shared_ptr<const Trajectory> trajectory() const override { return traj_; }
  std::int64_t plan_failures() const override { return 0; }

 private:
  JobOutput Plan() {
    JobOutput out;
    if (traj_) return out;
    PlanRequest request;
    request.t_start = exec_->now();
    request.start.p = start_.p_WB;
    request.goal_W = options_.goal;
    request.flight_bounds_W = options_.flight_bounds;
    const double res = 0.5;
    const Eigen::Vector3i dims = (options_.flight_bounds.sizes() / res).array().ceil().cast<int>();
    request.grid = std::make_shared<const VoxelGrid>(options_.flight_bounds.min(), res, dims, CellState::kFree);
    auto result = std::make_shared<PlanResult>(navstack::Plan(request, options_.planner));
    out.work = result->work;
    out.commit = [this, result] {
      if (!result->ok()) return;
      traj_ = result->trajectory;
      events_.push_back({exec_->now(), "replan", "start"});
    };
    return out;
  }
  MethodOptions options_;
  TaskExecutor* exec_;
  VehicleState start_;
  std::shared_ptr<const Trajectory> traj_;
  std::vector<NavEvent> events_;
};

}  // namespace

MethodInfo StraightToGoalMethod() {
  MethodInfo m;
  m.name = "straight_to_goal";
  m.summary = "one plan on an empty map (test)";
  m.scheduler = {SchedulingPolicy::kGlobalEdf, 0};
  m.cost_family = "navstack";
  // Its one task is no stack's planning: results name its CPU for what it is.
  m.task_keys[static_cast<int>(TaskId::kPlanning)] = "one_plan";
  m.task_labels[static_cast<int>(TaskId::kPlanning)] = "the one plan";
  m.tunables = {{"straight.unused", 0, 1, 0, true, "a tunable of its own"}};
  m.make = [](const MethodOptions& o, TaskExecutor* e, const VehicleState& s) {
    return std::unique_ptr<Navigator>(std::make_unique<StraightToGoal>(o, e, s));
  };
  return m;
}

}  // namespace enavi::navstack
