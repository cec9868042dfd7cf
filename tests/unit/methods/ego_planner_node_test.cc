// Ego-Planner's runtime mechanisms one by one, on an empty map (no frames: unknown space is free,
// so every plan goes straight to the local target) with a vehicle that tracks its reference
// exactly, on the virtual clock with a cost model that makes planning take a chosen board time.
#include <cmath>
#include <algorithm>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include "navstack/methods/ego_planner/ego_planner_node.h"
#include "navstack/methods/registry.h"
#include "navstack/runtime/virtual_executor.h"

namespace enavi::navstack {
namespace {

// A job that planned (searched, or optimised) takes `plan_s`; any other 0.5 ms.
class PlanCost final : public CostModel {
 public:
  explicit PlanCost(double plan_s) : plan_s_(plan_s) {}
  double JobSeconds(TaskId, const WorkCounts& w, double) const override {
    const bool planned = w.Get(WorkUnit::kOptimizerEval) > 0 || w.Get(WorkUnit::kPlannerIteration) > 0 ||
                         w.Get(WorkUnit::kAstarExpansion) > 0;
    return planned ? plan_s_ : 0.0005;
  }
  std::string mode() const override { return "model"; }
  bool uses_host_cpu() const override { return false; }

 private:
  double plan_s_;
};

struct Flight {
  std::vector<NavEvent> events;
  std::vector<double> jumps;  ///< how far back along x the reference moved when a replan landed
  std::int64_t plan_failures = 0;
  double final_x = 0;
  double hold_x = -1;  ///< where the first emergency stop held the vehicle (-1: none)
};

// A depth frame of a wall across the whole view at world x = wall_x, seen from p facing +x.
DepthFramePtr WallFrame(const CameraIntrinsics& camera, const Eigen::Vector3d& p, double t, double wall_x) {
  auto f = std::make_shared<DepthFrame>();
  f->t = t;
  f->image = DepthImage(camera.width, camera.height);
  std::fill(f->image.data.begin(), f->image.data.end(), static_cast<float>(wall_x - p.x()));
  Eigen::Matrix3d R_WC;
  R_WC.col(0) = -Eigen::Vector3d::UnitY();  // C: x right, y down, z forward (+x in W)
  R_WC.col(1) = -Eigen::Vector3d::UnitZ();
  R_WC.col(2) = Eigen::Vector3d::UnitX();
  f->X_WC.linear() = R_WC;
  f->X_WC.translation() = p;
  return f;
}

Flight Fly(const CostModel& cost, std::map<std::string, double> params, double duration = 8.0,
           std::optional<double> wall_x = std::nullopt, double half_width = 10.0, int search_iterations = 5000) {
  const MethodInfo& method = *FindMethod("baseline");
  MethodOptions o;
  ConfigureMethod(method, MethodSetup{}, &o);
  for (const auto& [k, v] : params) o.params[k] = v;
  o.goal = Eigen::Vector3d(30, 0, 1.5);
  o.flight_bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-5, -half_width, 0), Eigen::Vector3d(40, half_width, 5));
  o.planner.max_search_iterations = search_iterations;
  VirtualExecutor exec(1, cost, SchedulingPolicy::kFifoNonPreemptive);
  VehicleState s;
  s.p_WB = Eigen::Vector3d(0, 0, 1.5);
  auto nav = method.make(o, &exec, s);
  Flight f;
  double next_frame = 0;
  bool stopping = false;
  for (double t = 0; t <= duration; t += 0.005) {
    if (wall_x && t >= next_frame) {
      next_frame += 1.0 / 30.0;
      nav->OnFrame(WallFrame(o.camera, s.p_WB, t, *wall_x));
    }
    const TrajectorySample before = nav->Reference(t);
    exec.AdvanceTo(t);
    const TrajectorySample after = nav->Reference(t);
    bool landed = false;
    for (NavEvent& e : nav->TakeEvents()) {
      landed = landed || (e.kind == "replan" && e.detail == "distance");
      if (e.kind == "emergency_stop" && f.hold_x < 0) stopping = true;
      f.events.push_back(std::move(e));
    }
    if (stopping && after.v.norm() == 0.0) {
      f.hold_x = after.p.x();
      stopping = false;
    }
    if (landed) f.jumps.push_back(before.p.x() - after.p.x());
    // Perfect tracking.
    s.t = t;
    s.p_WB = after.p;
    s.v_WB = after.v;
    nav->OnState(s);
  }
  f.plan_failures = nav->plan_failures();
  f.final_x = s.p_WB.x();
  return f;
}

int Count(const Flight& f, const std::string& kind, const std::string& detail = "") {
  int n = 0;
  for (const NavEvent& e : f.events) n += e.kind == kind && (detail.empty() || e.detail == detail);
  return n;
}

TEST(EgoPlannerNodeTest, ReplansByDistanceNotByTimer) {
  const Flight f = Fly(PlanCost(0.01), {});
  EXPECT_EQ(Count(f, "replan", "start"), 1);
  // Every thresh_replan (1.5 m) past the local start: at ~2 m/s a few per 8 s, not 20 Hz.
  const int distance = Count(f, "replan", "distance");
  EXPECT_GE(distance, 4);
  EXPECT_LE(distance, 12);
  EXPECT_GT(f.final_x, 10.0) << "it flew";
}

TEST(EgoPlannerNodeTest, ReferenceJumpsBackByTheDistanceFlownWhilePlanning) {
  // Plans take 0.1 s of board time; stamped when planning ends, the new trajectory starts where
  // the reference was when planning began: ~v x 0.1 s behind.
  const Flight stamped = Fly(PlanCost(0.1), {});
  ASSERT_GE(stamped.jumps.size(), 3u);
  double mean = 0;
  for (double j : stamped.jumps) mean += j / static_cast<double>(stamped.jumps.size());
  EXPECT_GT(mean, 0.1) << "cruise 2 m/s x 0.1 s = 0.2 m";
  EXPECT_LT(mean, 0.3);
  // Switched off (stamped at planning start, i.e. latency compensated): no jump.
  const Flight compensated = Fly(PlanCost(0.1), {{"ego.stamp_at_plan_end", 0}});
  ASSERT_GE(compensated.jumps.size(), 3u);
  for (double j : compensated.jumps) EXPECT_NEAR(j, 0.0, 0.02);
  EXPECT_GT(compensated.final_x, stamped.final_x) << "losing 0.2 m per replan flies less far";
}

TEST(EgoPlannerNodeTest, SearchesOverTheirBoardTimeLimitFail) {
  // A wall across the view 4 m ahead: no straight path, plans have to search; at 1 ms of board
  // time per planner state check a search passes the 0.2 s limit and gives up.
  WorkCountCostModel::Coefficients c;
  c.ns_per_unit[static_cast<int>(WorkUnit::kStateCheck)] = 1e6;
  const WorkCountCostModel slow_checks(c);
  auto timeouts = [](const Flight& f) {
    int n = 0;
    for (const NavEvent& e : f.events) n += e.kind == "plan_failed" && e.detail.rfind("search_timeout", 0) == 0;
    return n;
  };
  const Flight limited = Fly(slow_checks, {}, 6.0, 4.0);
  EXPECT_GT(timeouts(limited), 0);
  EXPECT_GT(limited.plan_failures, 0);
  // Without the limit no search times out.
  const Flight unlimited = Fly(slow_checks, {{"ego.search_time_limit", 0}}, 6.0, 4.0);
  EXPECT_EQ(timeouts(unlimited), 0);
}

TEST(EgoPlannerNodeTest, AWallItCannotReplanAroundStopsTheVehicleBeforeIt) {
  // A corridor 1.6 m wide, closed by a wall at x = 4: the safety check finds the wall on the
  // trajectory, no replan gets round it, and once the hit is less than emergency_time (1 s)
  // ahead the node holds the position where it is (EMERGENCY_STOP), short of the wall.
  const PlanCost cheap(0.005);
  // (Hopeless searches are cut at 300 samples to keep the test short.)
  const Flight f = Fly(cheap, {}, 3.0, 4.0, 0.8, 300);
  EXPECT_GT(Count(f, "emergency_stop"), 0);
  ASSERT_GE(f.hold_x, 0.0) << "the stop published a hold";
  EXPECT_LT(f.hold_x, 4.0 - 0.3) << "held short of the wall (robot radius 0.3 m)";
  // Switched off, a hit only ever asks for a replan.
  const Flight no_stop = Fly(cheap, {{"ego.emergency_stop", 0}}, 3.0, 4.0, 0.8, 300);
  EXPECT_EQ(Count(no_stop, "emergency_stop"), 0);
  EXPECT_LT(no_stop.hold_x, 0.0);
}

TEST(EgoPlannerNodeTest, ATrajectoryThatRunsOutShortOfTheGoalLeavesTheNodeWaiting) {
  // With no distance replan (thresh_replan beyond the planning horizon) the first local
  // trajectory ends at its target, 7.5 m along the 30 m line: EXEC_TRAJ goes to WAIT_TARGET and
  // the vehicle hovers there, as Ego-Planner's FSM does (have_target_ = false).
  const Flight f = Fly(PlanCost(0.01), {{"ego.thresh_replan", 20.0}}, 12.0);
  EXPECT_EQ(Count(f, "replan", "distance"), 0);
  ASSERT_EQ(Count(f, "wait_target"), 1);
  EXPECT_NEAR(f.final_x, 7.5, 0.5) << "it stopped at the end of its first local trajectory";
  // With the default threshold it keeps replanning and never waits short of the goal in 12 s.
  const Flight replanning = Fly(PlanCost(0.01), {}, 12.0);
  EXPECT_EQ(Count(replanning, "wait_target"), 0);
  EXPECT_GT(replanning.final_x, 15.0);
}

TEST(GlobalPathTargetTest, LiesThePlanningHorizonAheadOnTheStartGoalLine) {
  GlobalPathTarget target(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(30, 0, 1), 7.5);
  // Walked in steps of horizon / 20 = 0.375 m from the progress point.
  EXPECT_NEAR(target.Next(Eigen::Vector3d(0, 0, 1)).x(), 7.5, 1e-9);
  EXPECT_NEAR(target.Next(Eigen::Vector3d(3, 1, 1)).x(), 3.0 + std::sqrt(7.5 * 7.5 - 1.0), 0.375);
  EXPECT_NEAR(target.Next(Eigen::Vector3d(9, 0, 1)).x(), 16.5, 0.375);
  EXPECT_NEAR(target.Next(Eigen::Vector3d(16, 0, 1)).x(), 23.5, 0.375);
  // Less than the horizon from the goal: the goal.
  EXPECT_EQ(target.Next(Eigen::Vector3d(23, 0, 1)), Eigen::Vector3d(30, 0, 1));
}

TEST(GlobalPathTargetTest, AVehicleDrivenOffThePathKeepsItsPreviousTarget) {
  // ego_replan_fsm.cpp getLocalTarget: when even the last progress point is more than
  // planning_horizon away, it returns before choosing ("last_progress_time_ ERROR"), so the
  // previous target stands; it is not replaced by the progress point behind it.
  GlobalPathTarget target(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(30, 0, 1), 7.5);
  const Eigen::Vector3d before = target.Next(Eigen::Vector3d(2, 0, 1));
  EXPECT_NEAR(before.x(), 9.5, 0.375);
  // 8 m to the side of the progress point (x = 2): the target stays where it was.
  EXPECT_EQ(target.Next(Eigen::Vector3d(2, 8, 1)), before);
  // Back within the horizon, it moves on from the progress point as before.
  EXPECT_NEAR(target.Next(Eigen::Vector3d(4, 2, 1)).x(), 4.0 + std::sqrt(7.5 * 7.5 - 4.0), 0.375);
}

}  // namespace
}  // namespace enavi::navstack
