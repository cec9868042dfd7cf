#include "navstack/planning/planner.h"

#include <cmath>
#include <memory>
#include <stdexcept>

#include <gtest/gtest.h>

#include "navstack/planning/distance_field.h"
#include "tests/unit/planning/planning_test_worlds.h"

namespace enavi::navstack {
namespace {

using testing::AsciiWorld;
using testing::WorldFromAscii;

// One character = 0.5 m; grid at 0.1 m, 3 m tall; S and G at z = 1.5 m.
AsciiWorld Ascii(const std::string& plan) { return WorldFromAscii(plan, 0.5, 0.1, 3.0, 1.5); }

// 8 x 4 m, a 1 x 1 m pillar on the straight line from S to G.
AsciiWorld PillarWorld() {
  return Ascii(R"(
    ................
    ................
    ................
    .S.....##.....G.
    .......##.......
    ................
    ................
    ................)");
}

// 10 x 6 m, a wall across with a 1.5 m gap well off the straight line from S to G.
AsciiWorld GapWorld() {
  return Ascii(R"(
    ..........#.........
    ..........#.........
    ..........#.........
    ....................
    ....................
    ....................
    ..........#.........
    ..........#.........
    ..........#.........
    ...S......#.....G...
    ..........#.........
    ..........#.........)");
}

PlanRequest RequestFor(const AsciiWorld& world, std::uint32_t seed = 1) {
  PlanRequest r;
  r.t_start = 3.0;
  r.start.p = world.start;
  r.goal_W = world.goal;
  r.flight_bounds_W = world.grid.Box();
  r.grid = std::make_shared<const VoxelGrid>(world.grid);
  r.seed = seed;
  return r;
}

// The contract every optimiser passes (kEsdf and kRebound). Fails the test on any OMPL warning
// or error (MuJoCo-style fixture).
class PlannerContractTest : public ::testing::TestWithParam<PlannerOptimizer> {
 protected:
  void SetUp() override {
    RouteOmplLog([](OmplLogLevel, const std::string& m) { ADD_FAILURE() << "OMPL: " << m; },
                 OmplLogLevel::kWarn);
  }
  static PlannerOptions Options() {
    PlannerOptions o;
    o.optimizer = GetParam();
    return o;
  }
  static bool Esdf() { return GetParam() == PlannerOptimizer::kEsdf; }
};

// Samples the trajectory densely and checks the limits and the clearance from the grid.
void ExpectFeasibleAndClear(const PlanResult& r, const VoxelGrid& grid, const PlannerOptions& o,
                            const std::string& what) {
  ASSERT_TRUE(r.ok()) << what << ": " << r.message;
  const DistanceField field(grid);
  const Trajectory& traj = *r.trajectory;
  double v_max = 0, a_max = 0, clearance = 1e9;
  for (double t = traj.start_time(); t <= traj.end_time(); t += 0.005) {
    const TrajectorySample s = traj.Sample(t);
    v_max = std::max(v_max, s.v.norm());
    a_max = std::max(a_max, s.a.norm());
    clearance = std::min(clearance, field.Distance(s.p));
  }
  EXPECT_LE(v_max, o.v_max + 1e-6) << what << ": " << r.message;
  EXPECT_LE(a_max, o.a_max + 1e-6) << what << ": " << r.message;
  EXPECT_GE(clearance, o.robot_radius) << what << ": " << r.message;
}

TEST_P(PlannerContractTest, RoutesAroundAPillar) {
  const AsciiWorld w = PillarWorld();
  const PlannerOptions o = Options();
  const PlanResult r = Plan(RequestFor(w), o);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_FALSE(r.goal_is_local);
  EXPECT_GT(r.search_path.size(), 2u) << "the straight line is blocked";
  const Trajectory& traj = *r.trajectory;
  EXPECT_LT((traj.end_point() - w.goal).norm(), 1e-9);
  // It leaves the line y = 2.25 by more than the pillar's half width.
  double deviation = 0;
  for (double t = traj.start_time(); t <= traj.end_time(); t += 0.01) {
    deviation = std::max(deviation, std::abs(traj.Sample(t).p.y() - 2.25));
  }
  EXPECT_GT(deviation, 0.5 + o.robot_radius - 0.05);
  ExpectFeasibleAndClear(r, w.grid, o, "pillar");
}

TEST_P(PlannerContractTest, GoesThroughAGapInAWall) {
  const AsciiWorld w = GapWorld();
  const PlannerOptions o = Options();
  const PlanResult r = Plan(RequestFor(w), o);
  ASSERT_TRUE(r.ok()) << r.message;
  const Trajectory& traj = *r.trajectory;
  // Where it crosses the wall (x = 5.0 .. 5.5) it is inside the gap (y in [3.0, 4.5]).
  bool crossed = false;
  for (double t = traj.start_time(); t <= traj.end_time(); t += 0.005) {
    const Eigen::Vector3d p = traj.Sample(t).p;
    if (p.x() < 5.0 || p.x() > 5.5) continue;
    crossed = true;
    EXPECT_GT(p.y(), 3.0 + o.robot_radius - 1e-6) << "t = " << t;
    EXPECT_LT(p.y(), 4.5 - o.robot_radius + 1e-6) << "t = " << t;
  }
  EXPECT_TRUE(crossed);
  EXPECT_LT((traj.end_point() - w.goal).norm(), 1e-9);
  ExpectFeasibleAndClear(r, w.grid, o, "gap");
}

TEST_P(PlannerContractTest, ClosedBoxGivesNoPathNotACrash) {
  // A hollow 4 x 4 x 2 m box with 0.3 m walls (floor and roof too) around the start; the goal
  // outside it. Plan view at z = 1.5 m, 1 char = 0.5 m:
  //   ................
  //   ..............G.
  //   ................
  //   ....########....
  //   ....#......#....
  //   ....#......#....
  //   ....#...S..#....
  //   ....#......#....
  //   ....#......#....
  //   ....########....
  //   ................
  VoxelGrid grid(Eigen::Vector3d::Zero(), 0.1, {80, 80, 30}, CellState::kFree);
  testing::FillBox(&grid, Eigen::Vector3d(2.0, 2.0, 0.5), Eigen::Vector3d(6.0, 6.0, 2.5));
  testing::FillBox(&grid, Eigen::Vector3d(2.3, 2.3, 0.8), Eigen::Vector3d(5.7, 5.7, 2.2), CellState::kFree);
  AsciiWorld w{grid, Eigen::Vector3d(4, 4, 1.5), Eigen::Vector3d(7, 7, 1.5)};
  PlannerOptions o = Options();
  o.max_search_iterations = 2000;
  const PlanResult r = Plan(RequestFor(w), o);
  EXPECT_EQ(r.status, PlanStatus::kNoPath) << ToString(r.status) << ": " << r.message;
  EXPECT_EQ(r.trajectory, nullptr);
  EXPECT_EQ(r.search_iterations, 2000);
  EXPECT_EQ(r.work.Get(WorkUnit::kPlannerIteration), 2000);
}

TEST_P(PlannerContractTest, GoalOutsideTheGridGivesALocalGoalOnTheGoalSide) {
  const AsciiWorld w = PillarWorld();
  PlanRequest req = RequestFor(w);
  req.goal_W = Eigen::Vector3d(30.0, 5.0, 1.5);
  req.flight_bounds_W = Eigen::AlignedBox3d(Eigen::Vector3d(-50, -50, 0), Eigen::Vector3d(50, 50, 3));
  const PlanResult r = Plan(req, Options());
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_TRUE(r.goal_is_local);
  EXPECT_TRUE(w.grid.Box().contains(r.goal_used_W)) << r.goal_used_W.transpose();
  EXPECT_GT(r.goal_used_W.x(), 7.5) << "at the grid's far side, towards the goal";
  EXPECT_LT((req.goal_W - r.goal_used_W).norm(), (req.goal_W - w.start).norm() - 6.0);
  EXPECT_LT((r.trajectory->end_point() - r.goal_used_W).norm(), 1e-9);
}

TEST_P(PlannerContractTest, GoalInsideAnObstacleGivesAFreeLocalGoalNextToIt) {
  const AsciiWorld w = PillarWorld();
  PlanRequest req = RequestFor(w);
  req.goal_W = Eigen::Vector3d(4.0, 2.0, 1.5);  // the pillar's centre
  const PlanResult r = Plan(req, Options());
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_TRUE(r.goal_is_local);
  EXPECT_LT((r.goal_used_W - req.goal_W).norm(), 1.5) << r.goal_used_W.transpose();
  ExpectFeasibleAndClear(r, w.grid, Options(), "goal in obstacle");
}

TEST_P(PlannerContractTest, SameSeedGivesABitIdenticalTrajectoryWhateverRanBefore) {
  const AsciiWorld gap = GapWorld(), pillar = PillarWorld();
  const PlanResult first = Plan(RequestFor(gap, 42), Options());
  ASSERT_TRUE(first.ok()) << first.message;
  ASSERT_GT(first.search_iterations, 0) << "the random search must have run";
  // Other plans in between, with other seeds and worlds.
  for (std::uint32_t seed : {1u, 2u, 43u}) {
    ASSERT_TRUE(Plan(RequestFor(gap, seed), Options()).ok());
    ASSERT_TRUE(Plan(RequestFor(pillar, seed), Options()).ok());
  }
  const PlanResult again = Plan(RequestFor(gap, 42), Options());
  ASSERT_TRUE(again.ok()) << again.message;
  EXPECT_EQ(again.search_path, first.search_path);
  EXPECT_EQ(again.search_iterations, first.search_iterations);
  EXPECT_EQ(again.trajectory->spline().dt(), first.trajectory->spline().dt());
  EXPECT_EQ(again.trajectory->spline().control_points(), first.trajectory->spline().control_points());
  EXPECT_EQ(again.work.n, first.work.n);
}

TEST_P(PlannerContractTest, TrajectoryStartsExactlyAtTheStartState) {
  const AsciiWorld w = PillarWorld();
  PlanRequest req = RequestFor(w);
  req.start.v = Eigen::Vector3d(1.2, -0.5, 0.2);
  req.start.a = Eigen::Vector3d(0.5, 1.0, -0.3);
  req.start.yaw = -0.4;
  const PlanResult r = Plan(req, Options());
  ASSERT_TRUE(r.ok()) << r.message;
  const TrajectorySample s = r.trajectory->Sample(req.t_start);
  EXPECT_DOUBLE_EQ(r.trajectory->start_time(), req.t_start);
  EXPECT_LT((s.p - req.start.p).norm(), 1e-12);
  EXPECT_LT((s.v - req.start.v).norm(), 1e-12);
  EXPECT_LT((s.a - req.start.a).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(s.yaw, -0.4);
}

TEST_P(PlannerContractTest, RespectsLimitsAndClearanceInAPark) {
  const AsciiWorld park = testing::ParkWorld(12.0, 4.0, 0.1, 40, 8, 7);
  const PlannerOptions o = Options();
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    ExpectFeasibleAndClear(Plan(RequestFor(park, seed), o), park.grid, o,
                           "park seed " + std::to_string(seed));
  }
  // Also from a moving start, heading away from the goal.
  PlanRequest req = RequestFor(park, 5);
  req.start.v = Eigen::Vector3d(-1.0, 1.0, 0.0);
  ExpectFeasibleAndClear(Plan(req, o), park.grid, o, "park, moving start");
}

TEST_P(PlannerContractTest, StartInInflatedSpaceEscapesInsteadOfGivingUp) {
  const AsciiWorld w = PillarWorld();
  PlanRequest req = RequestFor(w);
  req.start.p = Eigen::Vector3d(3.3, 2.0, 1.5);  // 0.2 m from the pillar's face
  const PlannerOptions o = Options();
  const PlanResult r = Plan(req, o);
  ASSERT_TRUE(r.ok()) << ToString(r.status) << ": " << r.message;
  EXPECT_TRUE(r.start_escape);
  EXPECT_LT((r.trajectory->Sample(req.t_start).p - req.start.p).norm(), 1e-12);
  EXPECT_GE(r.min_clearance, o.robot_radius) << "outside the escape ball";
}

TEST_P(PlannerContractTest, StartClearByDistanceButInsideTheCubeInflationOfACornerPlans) {
  // 0.42 m diagonally off the pillar's corner (3.5, 2.5): the exact clearance meets the search's
  // 0.4 m, the rebound map's cube inflation (Chebyshev 0.3 m) does not. Where a hold after an
  // emergency stop puts the vehicle, every later plan used to fail as start_in_collision.
  const AsciiWorld w = PillarWorld();
  PlanRequest req = RequestFor(w);
  req.start.p = Eigen::Vector3d(3.5 - 0.42 / std::sqrt(2.0), 2.5 + 0.42 / std::sqrt(2.0), 1.5);
  const PlannerOptions o = Options();
  const PlanResult r = Plan(req, o);
  ASSERT_TRUE(r.ok()) << ToString(r.status) << ": " << r.message;
  EXPECT_LT((r.trajectory->Sample(req.t_start).p - req.start.p).norm(), 1e-12);
  ExpectFeasibleAndClear(r, w.grid, o, "from the corner");
}

TEST_P(PlannerContractTest, StartBelowTheMinimumAltitudeClimbsFirst) {
  const AsciiWorld w = PillarWorld();
  PlanRequest req = RequestFor(w);
  req.start.p.z() = 0.2;
  PlannerOptions o = Options();
  o.min_altitude = 0.8;
  const PlanResult r = Plan(req, o);
  ASSERT_TRUE(r.ok()) << r.message;
  ASSERT_GE(r.search_path.size(), 2u);
  EXPECT_EQ(r.search_path[0], req.start.p);
  EXPECT_GE(r.search_path[1].z(), 0.8 - 1e-6);
}

TEST_P(PlannerContractTest, WorkCountsGrowWithGridSize) {
  const auto plan_in = [](double size) {
    AsciiWorld w;
    w.grid = VoxelGrid(Eigen::Vector3d::Zero(), 0.1, Eigen::Vector3i(size * 10, size * 10, 30), CellState::kFree);
    testing::FillBox(&w.grid, Eigen::Vector3d(1.6, 1.6, 0), Eigen::Vector3d(2.4, 2.4, 3));
    w.start = Eigen::Vector3d(0.5, 0.5, 1.5);
    w.goal = Eigen::Vector3d(3.5, 3.5, 1.5);
    return Plan(RequestFor(w), Options());
  };
  const PlanResult small = plan_in(4.0), large = plan_in(8.0);
  ASSERT_TRUE(small.ok()) << small.message;
  ASSERT_TRUE(large.ok()) << large.message;
  if (Esdf()) {
    EXPECT_EQ(small.work.Get(WorkUnit::kDistanceCell), 40 * 40 * 30);
    EXPECT_EQ(large.work.Get(WorkUnit::kDistanceCell), 4 * 40 * 40 * 30);
  } else {
    // No distance transform: the occupancy packed into bits and dilated three times (search,
    // collision and anchor inflations).
    EXPECT_EQ(small.work.Get(WorkUnit::kDistanceCell), 0);
    EXPECT_EQ(small.work.Get(WorkUnit::kInflateCell), 4 * 40 * 40 * 30);
    EXPECT_EQ(large.work.Get(WorkUnit::kInflateCell), 4 * 4 * 40 * 40 * 30);
  }
  EXPECT_GT(small.work.Get(WorkUnit::kStateCheck), 0);
  EXPECT_GT(small.work.Get(WorkUnit::kOptimizerEval), 0);
  EXPECT_GT(small.work.Get(WorkUnit::kTrajectorySample), 0);
}

TEST_P(PlannerContractTest, ReplanningFromTheReferenceReachesAFarGoal) {
  // A 30 x 30 m park at 0.2 m; every 0.5 s a new plan over PlanningVolume() from the current
  // reference, as the navigation loop does. The vehicle must reach the goal 28 m away with
  // clearance from the full world at all times.
  testing::AsciiWorld park = testing::ParkWorld(30.0, 4.0, 0.2, 90, 12, 31);
  const DistanceField full(park.grid);
  const PlannerOptions o = Options();
  const Eigen::AlignedBox3d flight = park.grid.Box();
  std::shared_ptr<const Trajectory> traj;
  TrajectorySample hover;
  hover.p = park.start;
  double t = 0.0, clearance = 1e9;
  int replans = 0;
  for (; t < 60.0 && !(traj && (traj->Sample(t).p - park.goal).norm() < 0.2); t += 0.5) {
    PlanRequest req;
    req.t_start = t;
    req.start = traj ? traj->Sample(t) : hover;
    req.goal_W = park.goal;
    req.flight_bounds_W = flight;
    req.grid = std::make_shared<const VoxelGrid>(
        testing::ExtractBox(park.grid, PlanningVolume(req.start.p, park.goal, flight, o)));
    req.seed = replans++;
    const PlanResult r = Plan(req, o);
    ASSERT_TRUE(r.ok()) << "t = " << t << ": " << ToString(r.status) << ", " << r.message;
    // The planning volume reaches camera_range ahead horizontally.
    const double ahead = (park.goal - req.start.p).head<2>().norm();
    if (std::abs(ahead - o.camera_range) > 0.5) {
      EXPECT_EQ(r.goal_is_local, ahead > o.camera_range) << "t = " << t;
    }
    traj = r.trajectory;
    for (double tt = t; tt < t + 0.5; tt += 0.01) clearance = std::min(clearance, full.Distance(traj->Sample(tt).p));
  }
  EXPECT_LT((traj->Sample(t).p - park.goal).norm(), 0.2) << "not at the goal after " << t << " s";
  EXPECT_LT(t, 28.0 / 1.0) << "slower than 1 m/s on average";
  EXPECT_GE(clearance, o.robot_radius);
}

TEST_P(PlannerContractTest, StartOutsideTheGridIsAStatus) {
  const AsciiWorld w = PillarWorld();
  PlanRequest req = RequestFor(w);
  req.start.p = Eigen::Vector3d(-3, 2, 1.5);
  EXPECT_EQ(Plan(req, Options()).status, PlanStatus::kStartOutsideGrid);
}

TEST_P(PlannerContractTest, BadInputThrowsInvalidArgument) {
  const AsciiWorld w = PillarWorld();
  PlanRequest req = RequestFor(w);
  req.grid = nullptr;
  EXPECT_THROW(Plan(req, Options()), std::invalid_argument);
  req = RequestFor(w);
  req.goal_W.x() = std::nan("");
  EXPECT_THROW(Plan(req, Options()), std::invalid_argument);
  PlannerOptions o = Options();
  o.v_max = -1.0;
  try {
    Plan(RequestFor(w), o);
    ADD_FAILURE() << "negative v_max accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("v_max"), std::string::npos) << e.what();
  }
}

// 10 x 6 m, a wall across with a 1.5 m door on the straight line from S to G.
AsciiWorld DoorWorld() {
  return Ascii(R"(
    ..........#.........
    ..........#.........
    ..........#.........
    ..........#.........
    ....................
    ...S..............G.
    ....................
    ..........#.........
    ..........#.........
    ..........#.........
    ..........#.........
    ..........#.........)");
}

TEST_P(PlannerContractTest, FliesThroughADoorOnTheWay) {
  const AsciiWorld w = DoorWorld();
  const PlannerOptions o = Options();
  const PlanResult r = Plan(RequestFor(w), o);
  ASSERT_TRUE(r.ok()) << r.message;
  const Trajectory& traj = *r.trajectory;
  // Where it crosses the wall (x = 5.0 .. 5.5) it is inside the door (y in [2.5, 4.0]).
  bool crossed = false;
  for (double t = traj.start_time(); t <= traj.end_time(); t += 0.005) {
    const Eigen::Vector3d p = traj.Sample(t).p;
    if (p.x() < 5.0 || p.x() > 5.5) continue;
    crossed = true;
    EXPECT_GT(p.y(), 2.5 + o.robot_radius - 1e-6) << "t = " << t;
    EXPECT_LT(p.y(), 4.0 - o.robot_radius + 1e-6) << "t = " << t;
  }
  EXPECT_TRUE(crossed);
  ExpectFeasibleAndClear(r, w.grid, o, "door");
}

TEST_P(PlannerContractTest, WorkBudgetStopsTheSearchWithATimeout) {
  // The gap world needs RRT-Connect (about 10 samples); the hook trips once the search has drawn
  // n samples after the hook's first call (grid_astar_test covers the A*).
  const AsciiWorld w = GapWorld();
  const WorkUnit unit = WorkUnit::kPlannerIteration;
  const int n = 3;
  PlanRequest req = RequestFor(w);
  int calls = 0;
  std::int64_t at_first_call = -1;
  req.over_budget = [&](const WorkCounts& work) {
    if (calls++ == 0) at_first_call = work.Get(unit);
    return work.Get(unit) - at_first_call >= n;
  };
  const PlanResult r = Plan(req, Options());
  EXPECT_EQ(r.status, PlanStatus::kSearchTimeout) << ToString(r.status) << ": " << r.message;
  EXPECT_STREQ(ToString(r.status), "search_timeout");
  EXPECT_EQ(r.trajectory, nullptr);
  EXPECT_EQ(r.work.Get(unit), at_first_call + n) << "stopped as soon as the hook said so";
  EXPECT_GT(calls, n);
  // A budget that is never spent changes nothing.
  PlanRequest generous = RequestFor(w);
  generous.over_budget = [](const WorkCounts&) { return false; };
  const PlanResult a = Plan(generous, Options()), b = Plan(RequestFor(w), Options());
  ASSERT_TRUE(a.ok()) << a.message;
  EXPECT_EQ(a.trajectory->spline().control_points(), b.trajectory->spline().control_points());
  EXPECT_EQ(a.work.n, b.work.n);
}

TEST_P(PlannerContractTest, NoTrajectoryInCollisionOverManyParks) {
  // Whatever each plan's outcome, a returned trajectory keeps robot_radius from every obstacle.
  const PlannerOptions o = Options();
  int ok = 0;
  for (std::uint32_t world = 1; world <= 6; ++world) {
    const AsciiWorld park = testing::ParkWorld(12.0, 4.0, 0.1, 40, 8, 100 + world);
    const PlanResult r = Plan(RequestFor(park, world), o);
    if (!r.ok()) continue;
    ++ok;
    ExpectFeasibleAndClear(r, park.grid, o, "park " + std::to_string(world));
  }
  EXPECT_EQ(ok, 6) << "every park has a way through";
}

INSTANTIATE_TEST_SUITE_P(Optimizers, PlannerContractTest,
                         ::testing::Values(PlannerOptimizer::kEsdf, PlannerOptimizer::kRebound),
                         [](const ::testing::TestParamInfo<PlannerOptimizer>& info) {
                           return std::string(ToString(info.param));
                         });

TEST(PlannerOptionsTest, OptimizerHasNamesAndIsValidated) {
  PlannerOptimizer o = PlannerOptimizer::kEsdf;
  EXPECT_TRUE(ParsePlannerOptimizer("rebound", &o));
  EXPECT_EQ(o, PlannerOptimizer::kRebound);
  EXPECT_TRUE(ParsePlannerOptimizer("esdf", &o));
  EXPECT_EQ(o, PlannerOptimizer::kEsdf);
  EXPECT_FALSE(ParsePlannerOptimizer("ego", &o));
  EXPECT_EQ(PlannerOptions{}.optimizer, PlannerOptimizer::kEsdf) << "the default stays the ESDF one";
  PlannerOptions bad;
  bad.optimizer = static_cast<PlannerOptimizer>(2);
  try {
    bad.Validate();
    ADD_FAILURE() << "optimizer 2 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("optimizer"), std::string::npos) << e.what();
  }
  bad = PlannerOptions{};
  bad.rebound_dist0 = 0.0;
  EXPECT_THROW(bad.Validate(), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack
