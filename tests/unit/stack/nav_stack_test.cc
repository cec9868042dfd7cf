// NavStack (methods `fixed` and `enavi`) on a scripted executor: the test decides when each job's
// code runs and when its commit lands, and sees every rate and trigger the stack asks for. What
// the stack decides is checked without a simulator or a clock.
#include "navstack/stack/nav_stack.h"

#include <array>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

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

// A frame with nothing in view, from a camera at the hovering vehicle looking along +x (camera
// z forward, x right, y down): the stack maps the view cone free up to its mapping range.
DepthFramePtr OpenViewAhead(const NavStackOptions& o, double t) {
  auto frame = std::make_shared<DepthFrame>();
  frame->t = t;
  frame->image = DepthImage(o.camera.width, o.camera.height);
  Eigen::Matrix3d R_WC;
  R_WC.col(0) = -Eigen::Vector3d::UnitY();
  R_WC.col(1) = -Eigen::Vector3d::UnitZ();
  R_WC.col(2) = Eigen::Vector3d::UnitX();
  frame->X_WC.linear() = R_WC;
  frame->X_WC.translation() = Hovering().p_WB;
  return frame;
}

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

TEST(NavStackTest, AMapUpdateChecksTheTrajectoryAgainstTheNewMap) {
  ScriptedExecutor ex;
  NavStackOptions o = OpenVolume();
  o.rates.f_plan = 0;
  NavStack stack(o, &ex, Hovering());
  LookAhead(&stack, &ex, o);
  ex.Run(TaskId::kPlanning);
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
