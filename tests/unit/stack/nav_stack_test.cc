// NavStack (methods `fixed` and `enavi`) on a scripted executor: the test decides when each job's
// code runs and when its commit lands, and sees every rate and trigger the stack asks for. What
// the stack decides is checked without a simulator or a clock.
#include "navstack/stack/nav_stack.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "navstack/adapt/action_grid.h"
#include "navstack/rl/policy_io.h"

namespace enavi::navstack {
namespace {

// Records what the stack asks of its board; runs a job only when the test says so.
class ScriptedExecutor final : public TaskExecutor {
 public:
  void Register(TaskId task, JobFn fn) override { fns_[Index(task)] = std::move(fn); }
  void SetRate(TaskId task, double hz) override { rates_[Index(task)] = hz; }
  double rate(TaskId task) const override { return rates_[Index(task)]; }
  void Trigger(TaskId task, double relative_deadline) override { triggers.push_back({task, relative_deadline}); }
  void AdvanceTo(double t) override { now_ = t; }
  double now() const override { return now_; }
  int cores() const override { return 4; }
  const TaskStats& stats(TaskId task) const override { return stats_[Index(task)]; }
  bool active(TaskId task) const override { return false; }
  double JobElapsed(TaskId, const WorkCounts&, double) const override { return 0; }

  bool registered(TaskId task) const { return static_cast<bool>(fns_[Index(task)]); }
  /// Runs the job's code now; the returned commit is the test's to apply.
  JobOutput Start(TaskId task) { return fns_[Index(task)](); }
  /// Code and commit at once.
  void Run(TaskId task) {
    JobOutput out = Start(task);
    if (out.commit) out.commit();
  }
  int Triggered(TaskId task) const {
    int n = 0;
    for (const auto& [t, deadline] : triggers) n += t == task;
    return n;
  }

  std::vector<std::pair<TaskId, double>> triggers;

 private:
  static int Index(TaskId t) { return static_cast<int>(t); }
  std::array<JobFn, kTaskCount> fns_{};
  std::array<double, kTaskCount> rates_{};
  std::array<TaskStats, kTaskCount> stats_{};
  double now_ = 0;
};

// An open 20 x 10 x 4 m volume, start at the origin at 1.5 m, goal 10 m ahead.
NavStackOptions OpenVolume() {
  NavStackOptions o;
  o.goal = Eigen::Vector3d(10, 0, 1.5);
  o.flight_bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-5, -5, 0), Eigen::Vector3d(15, 5, 4));
  return o;
}

VehicleState Hovering() {
  VehicleState s;
  s.p_WB = Eigen::Vector3d(0, 0, 1.5);
  return s;
}

// A frame from a level camera at p_W looking along yaw (camera z forward, x right, y down), every
// pixel at `depth` m (0: nothing in view, so the stack maps the view cone free up to its mapping
// range), taken at velocity v_W.
DepthFramePtr ViewFrom(const NavStackOptions& o, double t, const Eigen::Vector3d& p_W, double yaw = 0.0,
                       float depth = 0.0f, const Eigen::Vector3d& v_W = Eigen::Vector3d::Zero()) {
  auto frame = std::make_shared<DepthFrame>();
  frame->t = t;
  frame->v_W = v_W;
  frame->image = DepthImage(o.camera.width, o.camera.height);
  std::fill(frame->image.data.begin(), frame->image.data.end(), depth);
  const Eigen::Vector3d forward(std::cos(yaw), std::sin(yaw), 0.0);
  Eigen::Matrix3d R_WC;
  R_WC.col(2) = forward;
  R_WC.col(1) = -Eigen::Vector3d::UnitZ();
  R_WC.col(0) = R_WC.col(1).cross(R_WC.col(2));
  frame->X_WC.linear() = R_WC;
  frame->X_WC.translation() = p_W;
  return frame;
}

DepthFramePtr OpenViewAhead(const NavStackOptions& o, double t) { return ViewFrom(o, t, Hovering().p_WB); }

// The stack plans only into space it has seen near the vehicle (observed_space.h): show it the
// way ahead first.
void LookAhead(NavStack* stack, ScriptedExecutor* ex, const NavStackOptions& o) {
  stack->OnFrame(OpenViewAhead(o, ex->now()));
  ex->Run(TaskId::kPerception);
  ex->triggers.clear();
}

bool HasEvent(const std::vector<NavEvent>& events, const std::string& kind, const std::string& detail = {}) {
  for (const NavEvent& e : events)
    if (e.kind == kind && (detail.empty() || e.detail == detail)) return true;
  return false;
}

// Triggered planning (as E-Navi plans) in the open volume, having looked ahead and planned once.
// Members in this order: the tests bind them as `auto& [ex, o, stack] = f`.
struct FlyingStack {
  FlyingStack() {
    LookAhead(&stack, &ex, o);
    ex.Run(TaskId::kPlanning);
  }
  ScriptedExecutor ex;
  NavStackOptions o = [] {
    NavStackOptions triggered = OpenVolume();
    triggered.rates.f_plan = 0;
    return triggered;
  }();
  NavStack stack{o, &ex, Hovering()};
};

TEST(NavStackTest, StartsItsRatesAndHoldsAtTheStartUntilAPlanLands) {
  ScriptedExecutor ex;
  NavStackOptions o = OpenVolume();
  o.rates = TaskRates{};  // fixed: 30 Hz perception, 20 Hz planning, collision after map updates
  NavStack stack(o, &ex, Hovering());
  for (TaskId t : {TaskId::kPerception, TaskId::kPlanning, TaskId::kCollision, TaskId::kDifference})
    EXPECT_TRUE(ex.registered(t)) << TaskName(t);
  EXPECT_FALSE(ex.registered(TaskId::kAdapter)) << "no strategy controller without E-Navi";
  EXPECT_EQ(ex.rate(TaskId::kPerception), 30.0);
  EXPECT_EQ(ex.rate(TaskId::kPlanning), 20.0);
  EXPECT_EQ(ex.rate(TaskId::kCollision), 0.0) << "runs after every map update instead";
  EXPECT_EQ(ex.rate(TaskId::kDifference), 0.0);
  EXPECT_TRUE(ex.triggers.empty()) << "a timer-planned stack asks for no plan of its own";
  const TrajectorySample ref = stack.Reference(1.0);
  EXPECT_TRUE(ref.p.isApprox(Hovering().p_WB)) << ref.p.transpose();
  EXPECT_EQ(ref.v.norm(), 0.0);
  EXPECT_EQ(stack.trajectory(), nullptr);
}

TEST(NavStackTest, TriggeredPlanningAsksForAPlanAtTheStart) {
  ScriptedExecutor ex;
  NavStackOptions o = OpenVolume();
  o.rates.f_plan = 0;
  NavStack stack(o, &ex, Hovering());
  ASSERT_EQ(ex.Triggered(TaskId::kPlanning), 1);
  EXPECT_EQ(ex.triggers[0].second, o.triggered_plan_deadline_s);
}

TEST(NavStackTest, APlanTakesEffectAtItsCommitNotWhenItsCodeRuns) {
  ScriptedExecutor ex;
  NavStackOptions o = OpenVolume();
  o.rates.f_plan = 0;
  NavStack stack(o, &ex, Hovering());
  LookAhead(&stack, &ex, o);
  JobOutput plan = ex.Start(TaskId::kPlanning);
  EXPECT_EQ(stack.trajectory(), nullptr) << "computed, not yet finished on the board";
  EXPECT_FALSE(HasEvent(stack.TakeEvents(), "replan"));
  ex.AdvanceTo(0.05);
  ASSERT_TRUE(plan.commit);
  plan.commit();
  const std::vector<NavEvent> events = stack.TakeEvents();
  ASSERT_NE(stack.trajectory(), nullptr) << (HasEvent(events, "plan_failed") ? "the plan failed" : "no plan");
  EXPECT_EQ(stack.replans(), 1);
  EXPECT_TRUE(HasEvent(events, "replan", "start")) << "billed to the trigger it answers";
  const TrajectorySample later = stack.Reference(stack.trajectory()->start_time() + 2.0);
  EXPECT_GT(later.p.x(), Hovering().p_WB.x() + 0.1) << "the reference now moves towards the goal";
}

TEST(NavStackTest, ItDoesNotPlanIntoSpaceItHasNotSeen) {
  // Nothing mapped yet: everything within stopping reach is unobserved, so no plan may leave the
  // vehicle's own bubble; once it has looked ahead, the same request plans.
  ScriptedExecutor ex;
  NavStackOptions o = OpenVolume();
  o.rates.f_plan = 0;
  NavStack stack(o, &ex, Hovering());
  ex.Run(TaskId::kPlanning);
  EXPECT_EQ(stack.trajectory(), nullptr);
  EXPECT_TRUE(HasEvent(stack.TakeEvents(), "plan_failed"));
  LookAhead(&stack, &ex, o);
  ex.Run(TaskId::kPlanning);
  EXPECT_NE(stack.trajectory(), nullptr);
}

TEST(NavStackTest, AHoveringStackWhosePlansKeepFailingTurnsOnTheSpotUntilOneLands) {
  // Nothing seen: every plan fails (as above). After scan_after_failures of them in a row the
  // vehicle turns where it is, so the camera sees what boxes it in, and retries at the bounded
  // rate; the first plan that lands ends the turn.
  ScriptedExecutor ex;
  NavStackOptions o = OpenVolume();
  o.rates.f_plan = 0;
  NavStack stack(o, &ex, Hovering());
  for (int i = 1; i < o.scan_after_failures; ++i) ex.Run(TaskId::kPlanning);
  EXPECT_FALSE(HasEvent(stack.TakeEvents(), "scan"));
  EXPECT_EQ(stack.Reference(1.0).yaw, 0.0) << "holds its heading";
  ex.AdvanceTo(1.0);
  ex.Run(TaskId::kPlanning);
  EXPECT_TRUE(HasEvent(stack.TakeEvents(), "scan"));
  const TrajectorySample turning = stack.Reference(1.5);
  EXPECT_NEAR(turning.yaw, 0.5 * o.scan_yaw_rate, 1e-12);
  EXPECT_EQ(turning.yaw_rate, o.scan_yaw_rate);
  EXPECT_TRUE(turning.p.isApprox(Hovering().p_WB)) << "on the spot";
  EXPECT_NEAR(stack.Reference(1.0 + 4.0 / o.scan_yaw_rate).yaw, 4.0 - 2.0 * 3.14159265358979323846, 1e-9)
      << "wrapped to (-pi, pi]";
  ex.triggers.clear();
  stack.OnFrame(OpenViewAhead(o, 1.5));
  EXPECT_EQ(ex.Triggered(TaskId::kPlanning), 1) << "retries while it turns";
  ex.Run(TaskId::kPerception);
  ex.Run(TaskId::kPlanning);
  ASSERT_NE(stack.trajectory(), nullptr);
  EXPECT_EQ(stack.Reference(1.5).yaw_rate, stack.trajectory()->Sample(1.5).yaw_rate) << "the plan ends the turn";
}

TEST(NavStackTest, AScanThatTurnsAFullCircleWithoutAPlanForgetsTheFarMap) {
  // A wall 4.5 m ahead is mapped from a camera 1.5 m ahead of the vehicle, so the vehicle's own
  // surroundings stay unobserved and every plan fails (as above).
  // The vehicle scans; once it has turned a full circle without a plan, the next perception job
  // rebuilds the map keeping only cells within scan_reset_distance (3 m): the wall, which the
  // vehicle can no longer see from where it hovers, is forgotten, and a plan is asked for on the
  // new map. One reset per scan.
  ScriptedExecutor ex;
  NavStackOptions o = OpenVolume();
  o.rates.f_plan = 0;
  o.map.rebuild_frames = 1;
  NavStack stack(o, &ex, Hovering());
  const Eigen::Vector3d wall(4.55, 0, 1.5);
  stack.OnFrame(ViewFrom(o, 0.0, Hovering().p_WB + Eigen::Vector3d(1.5, 0, 0), 0.0, 3.0f));
  ex.Run(TaskId::kPerception);
  ASSERT_EQ(stack.map().Query(wall), CellState::kOccupied);
  for (int i = 0; i < o.scan_after_failures; ++i) ex.Run(TaskId::kPlanning);
  ASSERT_TRUE(HasEvent(stack.TakeEvents(), "scan"));

  // Looking the other way now, at a wall 1.05 m behind; just short of a full turn: no reset.
  const double full_turn = 2.0 * 3.14159265358979323846 / o.scan_yaw_rate;
  ex.AdvanceTo(full_turn - 0.1);
  stack.OnFrame(ViewFrom(o, ex.now(), Hovering().p_WB, 3.14159265358979323846, 1.05f));
  ex.Run(TaskId::kPlanning);
  EXPECT_FALSE(HasEvent(stack.TakeEvents(), "map_reset"));
  ex.Run(TaskId::kPerception);
  EXPECT_EQ(stack.map().Query(wall), CellState::kOccupied) << "an ordinary map update keeps it";

  ex.AdvanceTo(full_turn + 0.1);
  ex.Run(TaskId::kPlanning);
  EXPECT_TRUE(HasEvent(stack.TakeEvents(), "map_reset"));
  EXPECT_EQ(stack.map().Query(wall), CellState::kOccupied) << "the reset is the next perception job's";
  ex.triggers.clear();
  ex.Run(TaskId::kPerception);
  EXPECT_EQ(stack.map().Query(wall), CellState::kUnknown);
  EXPECT_EQ(stack.map().Query(Eigen::Vector3d(-1.05, 0, 1.5)), CellState::kOccupied) << "near cells stay";
  EXPECT_EQ(stack.map().Query(Eigen::Vector3d(-0.5, 0, 1.5)), CellState::kFree) << "the newest frame's view stays";
  EXPECT_EQ(ex.Triggered(TaskId::kPlanning), 1) << "plans on the reset map at once";

  ex.AdvanceTo(2 * full_turn + 0.2);
  ex.Run(TaskId::kPlanning);
  EXPECT_FALSE(HasEvent(stack.TakeEvents(), "map_reset")) << "once per scan";
}

TEST(NavStackTest, AScanResetDistanceOfZeroKeepsTheMap) {
  ScriptedExecutor ex;
  NavStackOptions o = OpenVolume();
  o.rates.f_plan = 0;
  o.scan_reset_distance = 0;
  NavStack stack(o, &ex, Hovering());
  stack.OnFrame(ViewFrom(o, 0.0, Hovering().p_WB + Eigen::Vector3d(1.5, 0, 0), 0.0, 3.0f));
  ex.Run(TaskId::kPerception);
  for (int i = 0; i < o.scan_after_failures; ++i) ex.Run(TaskId::kPlanning);
  ex.AdvanceTo(20.0);
  ex.Run(TaskId::kPlanning);
  const std::vector<NavEvent> events = stack.TakeEvents();
  EXPECT_TRUE(HasEvent(events, "scan"));
  EXPECT_FALSE(HasEvent(events, "map_reset"));
}

TEST(NavStackTest, AMapUpdateChecksTheTrajectoryAgainstTheNewMap) {
  FlyingStack f;
  auto& [ex, o, stack] = f;
  ASSERT_NE(stack.trajectory(), nullptr);
  ex.triggers.clear();
  auto frame = std::make_shared<DepthFrame>();
  frame->t = 0.1;
  frame->image = DepthImage(o.camera.width, o.camera.height);  // nothing in view
  stack.OnFrame(frame);
  ex.Run(TaskId::kPerception);
  ASSERT_EQ(ex.Triggered(TaskId::kCollision), 1) << "collision check after every map update";
  for (const auto& [task, deadline] : ex.triggers) {
    if (task == TaskId::kCollision) {
      EXPECT_DOUBLE_EQ(deadline, 1.0 / o.rates.f_per) << "before the next update";
    }
  }
  ex.Run(TaskId::kPerception);
  EXPECT_EQ(ex.Triggered(TaskId::kCollision), 1) << "the same frame is mapped once";
}

// Flying the planned trajectory at time t, a wall fills the view 1 m ahead: the collision check
// stops the vehicle (emergency_stop). Returns the state it was in.
VehicleState StopInFrontOfAWall(NavStack* stack, ScriptedExecutor* ex, const NavStackOptions& o, double t) {
  ex->AdvanceTo(t);
  const TrajectorySample on = stack->trajectory()->Sample(t);
  VehicleState moving;
  moving.p_WB = on.p;
  moving.v_WB = on.v;
  stack->OnState(moving);
  stack->OnFrame(ViewFrom(o, t, on.p, 0.0, 1.0f));
  ex->Run(TaskId::kPerception);
  ex->Run(TaskId::kCollision);
  return moving;
}

TEST(NavStackTest, AfterAnEmergencyStopItPlansOnlyOnceTheVehicleHasSlowedDown) {
  // Ego-Planner's EMERGENCY_STOP: no new trajectory until odom speed < 0.1 m/s. A plan started
  // from the braking vehicle's velocity would carry it on towards the wall (a sampled training
  // flight in the canyon stopped five times in 0.3 s that way and hit the wall).
  FlyingStack f;
  auto& [ex, o, stack] = f;
  ASSERT_NE(stack.trajectory(), nullptr);
  stack.TakeEvents();
  VehicleState braking = StopInFrontOfAWall(&stack, &ex, o, 1.0);
  ASSERT_GT(braking.v_WB.norm(), 1.0);
  ASSERT_TRUE(HasEvent(stack.TakeEvents(), "emergency_stop"));
  const TrajectorySample hold = stack.Reference(1.1);
  EXPECT_TRUE(hold.p.isApprox(braking.p_WB));

  braking.v_WB = braking.v_WB.normalized() * 0.5;
  stack.OnState(braking);
  ex.Run(TaskId::kPlanning);
  std::vector<NavEvent> events = stack.TakeEvents();
  EXPECT_FALSE(HasEvent(events, "replan")) << "no plan while braking";
  EXPECT_FALSE(HasEvent(events, "plan_failed")) << "not even tried";
  EXPECT_TRUE(stack.Reference(1.2).p.isApprox(hold.p)) << "still holding where it stopped";

  braking.v_WB = braking.v_WB.normalized() * 0.05;
  stack.OnState(braking);
  ex.Run(TaskId::kPlanning);
  events = stack.TakeEvents();
  EXPECT_TRUE(HasEvent(events, "replan") || HasEvent(events, "plan_failed")) << "slow: plans again";
}

TEST(NavStackTest, APlanStartedBeforeAnEmergencyStopIsNotAdoptedAfterIt) {
  FlyingStack f;
  auto& [ex, o, stack] = f;
  ASSERT_NE(stack.trajectory(), nullptr);
  ex.AdvanceTo(0.9);
  JobOutput before = ex.Start(TaskId::kPlanning);  // planned on the map without the wall
  ASSERT_TRUE(before.commit);
  StopInFrontOfAWall(&stack, &ex, o, 1.0);
  stack.TakeEvents();
  const auto stopped_on = stack.trajectory();
  before.commit();
  EXPECT_TRUE(stack.trajectory() == stopped_on) << "the old plan does not end the stop";
  EXPECT_FALSE(HasEvent(stack.TakeEvents(), "replan"));
}

TEST(NavStackTest, AHitTheCheckCanPlanAroundIsReplannedInsideTheCheckWithoutAStop) {
  // Ego-Planner's safety check replans inside its callback and stops only when that fails: a
  // plan made on a map that changed while it was made is replaced, not answered by a stop.
  FlyingStack f;
  auto& [ex, o, stack] = f;
  ASSERT_NE(stack.trajectory(), nullptr);
  const double t = 1.0;
  ex.AdvanceTo(t);
  const TrajectorySample on = stack.trajectory()->Sample(t);
  VehicleState moving;
  moving.p_WB = on.p;
  moving.v_WB = on.v;
  stack.OnState(moving);
  // A post in the middle of the view, 1.3 m ahead; the rest of the view is open.
  DepthFramePtr frame = ViewFrom(o, t, on.p);
  DepthImage& image = std::const_pointer_cast<DepthFrame>(frame)->image;
  for (int v = 0; v < image.height; ++v)
    for (int u = 2 * image.width / 5; u < 3 * image.width / 5; ++u) image.data[v * image.width + u] = 1.3f;
  stack.OnFrame(frame);
  ex.Run(TaskId::kPerception);
  const auto flown = stack.trajectory();
  const VoxelGrid near = stack.map().ExtractGrid(
      Eigen::AlignedBox3d(on.p - Eigen::Vector3d(1, 3, 1), on.p + Eigen::Vector3d(6, 3, 1)), nullptr);
  const CollisionCheckResult before = CheckTrajectory(*flown, t, flown->end_time(), near, o.planner.robot_radius, nullptr);
  ASSERT_TRUE(before.collides) << "the post is on the flown trajectory";
  ASSERT_LT(before.t_hit - t, o.emergency_horizon_s) << "near enough that the check used to stop";
  stack.TakeEvents();
  ex.triggers.clear();
  ex.Run(TaskId::kCollision);
  const std::vector<NavEvent> events = stack.TakeEvents();
  EXPECT_TRUE(HasEvent(events, "collision_predicted"));
  EXPECT_TRUE(HasEvent(events, "replan", "collision")) << "planned inside the check";
  EXPECT_FALSE(HasEvent(events, "emergency_stop"));
  EXPECT_EQ(ex.Triggered(TaskId::kPlanning), 0) << "no planning job needed";
  ASSERT_NE(stack.trajectory(), flown);
  EXPECT_GT(stack.Reference(t + 0.1).v.norm(), 0.5) << "flying on, not holding";
  const auto around = stack.trajectory();
  EXPECT_FALSE(CheckTrajectory(*around, t, around->end_time(), near, o.planner.robot_radius, nullptr).collides)
      << "round the post";
}

double MaxSpeedBetween(const Trajectory& trajectory, double t0, double t1) {
  double v = 0;
  for (double t = t0; t <= t1; t += 0.01) v = std::max(v, trajectory.Sample(t).v.norm());
  return v;
}

TEST(NavStackTest, ASpeedLimitReplacesAFasterPlanAndItsLiftingThePlanMadeUnderIt) {
  // E-Navi (an untrained policy: the limit does not depend on the choice) flying its first plan
  // sees a wall 0.6 m ahead, nearer than it can brake from its speed at any rate: the strategy
  // limits the speed of new plans. The plan being flown was made for more speed, so the stack
  // replans at once rather than flying it on towards the wall.
  ScriptedExecutor ex;
  NavStackOptions o = OpenVolume();
  o.rates.f_plan = 0;
  StrategyOptions strategy;
  strategy.policy = std::make_shared<const rl::PolicyFile>(rl::MakeFrequencyPolicy(ActionGrid(), 7));
  o.strategy = strategy;
  NavStack stack(o, &ex, Hovering());
  LookAhead(&stack, &ex, o);
  ex.Run(TaskId::kPlanning);
  ASSERT_NE(stack.trajectory(), nullptr);
  const auto first = stack.trajectory();
  const double t = 1.5;
  ex.AdvanceTo(t);
  const TrajectorySample on = first->Sample(t);
  ASSERT_GT(on.v.norm(), 1.0) << "the test needs a vehicle that cannot stop within 0.6 m";
  VehicleState moving;
  moving.p_WB = on.p;
  moving.v_WB = on.v;
  stack.OnState(moving);
  ex.Run(TaskId::kAdapter);  // the wall is not in view yet: no limit
  ex.triggers.clear();
  stack.TakeEvents();
  ex.Run(TaskId::kPlanning);  // a plan at the options' speed
  ASSERT_TRUE(HasEvent(stack.TakeEvents(), "replan"));
  ex.Run(TaskId::kAdapter);
  EXPECT_EQ(ex.Triggered(TaskId::kPlanning), 0) << "without a limit the plan stays";

  stack.OnFrame(ViewFrom(o, t, on.p, 0.0, 0.6f, on.v));
  ex.Run(TaskId::kEci);  // only the eci job: the map stays open, so planning can succeed
  ex.Run(TaskId::kAdapter);
  ASSERT_EQ(ex.Triggered(TaskId::kPlanning), 1) << "a limit below the plan's speed asks for a plan";
  ex.Run(TaskId::kPlanning);
  const std::vector<NavEvent> events = stack.TakeEvents();
  ASSERT_TRUE(HasEvent(events, "replan", "speed_limit"));
  const double v_planned = MaxSpeedBetween(*first, t, t + 3.0);
  // The new plan brakes from the flown speed (about 1.9 m/s) at 0.8 a_max, in about 0.7 s, and
  // never turns back along its way (bspline.cc, BsplineFromPath brakes to the limit first).
  const Trajectory& limited = *stack.trajectory();
  const double v_limited = MaxSpeedBetween(limited, t + 1.0, t + 4.0);
  EXPECT_GT(v_planned, 1.0);
  EXPECT_LT(v_limited, 0.5) << "once braked, the new plan flies at the limit (at least 0.3 m/s)";
  double least_forward = 1e9;
  for (double tau = t; tau <= t + 4.0; tau += 0.01)
    least_forward = std::min(least_forward, limited.Sample(tau).v.dot(on.v.normalized()));
  EXPECT_GT(least_forward, -0.05) << "the braking plan flies back";

  ex.triggers.clear();
  ex.Run(TaskId::kAdapter);
  EXPECT_EQ(ex.Triggered(TaskId::kPlanning), 0) << "a plan made within the limit is kept";

  // The wall goes out of view: the limit is lifted, and the plan made under it is replaced by
  // one at the options' speed rather than crawled along until something else asks for a plan.
  ex.AdvanceTo(t + 0.2);
  stack.OnFrame(ViewFrom(o, t + 0.2, on.p, 0.0, 0.0f, on.v));
  ex.Run(TaskId::kEci);
  ex.Run(TaskId::kAdapter);
  ASSERT_EQ(ex.Triggered(TaskId::kPlanning), 1) << "no limit any more: a plan at full speed";
  ex.Run(TaskId::kPlanning);
  ASSERT_TRUE(HasEvent(stack.TakeEvents(), "replan", "speed_limit_lifted"));
  EXPECT_GT(MaxSpeedBetween(*stack.trajectory(), t + 0.2, t + 4.0), 1.0);
  ex.triggers.clear();
  ex.Run(TaskId::kAdapter);
  EXPECT_EQ(ex.Triggered(TaskId::kPlanning), 0) << "and that plan is kept";
}

TEST(NavStackTest, RatesFromTheStrategyReachTheExecutor) {
  ScriptedExecutor ex;
  NavStack stack(OpenVolume(), &ex, Hovering());
  TaskRates r;
  r.f_per = 10;
  r.f_plan = 0;
  r.f_col = 5;
  r.collision_on_map_update = false;
  r.f_dif = 2;
  r.resolution = 0.3;
  stack.SetRates(r);
  EXPECT_EQ(ex.rate(TaskId::kPerception), 10.0);
  EXPECT_EQ(ex.rate(TaskId::kPlanning), 0.0);
  EXPECT_EQ(ex.rate(TaskId::kCollision), 5.0);
  EXPECT_EQ(ex.rate(TaskId::kDifference), 2.0);
  EXPECT_TRUE(HasEvent(stack.TakeEvents(), "resolution")) << "a new resolution is announced";
  EXPECT_DOUBLE_EQ(stack.map_resolution(), 0.1) << "the map is rebuilt by the next perception job, not before";
  ex.Run(TaskId::kPerception);
  EXPECT_DOUBLE_EQ(stack.map_resolution(), 0.3);
}

}  // namespace
}  // namespace enavi::navstack
