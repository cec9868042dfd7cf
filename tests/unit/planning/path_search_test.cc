#include "navstack/planning/path_search.h"

#include <gtest/gtest.h>

#include "tests/unit/planning/planning_test_worlds.h"

namespace enavi::navstack {
namespace {

class PathSearchTest : public ::testing::Test {
 protected:
  void SetUp() override {
    RouteOmplLog([](OmplLogLevel, const std::string& m) { ADD_FAILURE() << "OMPL: " << m; },
                 OmplLogLevel::kWarn);
  }
};

// 6 x 4 m at 0.1 m: a wall with a 1 m opening near the top, S and G on either side.
testing::AsciiWorld WallWorld() {
  return testing::WorldFromAscii(R"(
      ............
      ............
      ......#.....
      ......#.....
      .S....#...G.
      ......#.....
      ......#.....
      ......#.....)", 0.5, 0.1, 2.0, 1.0);
}

TEST_F(PathSearchTest, FindsAPathWhoseSegmentsAreFree) {
  const testing::AsciiWorld w = WallWorld();
  const DistanceField field(w.grid);
  PlannerOptions o;
  o.min_altitude = 0.0;
  const Eigen::AlignedBox3d bounds = SearchBounds(field, w.grid.Box(), o);
  const ClearanceRule rule = MakeClearanceRule(field, w.start, o);
  WorkCounts work;
  const PathSearchResult r = SearchPath(field, bounds, rule, w.start, w.goal, 9, o, &work);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.path.front(), w.start);
  EXPECT_EQ(r.path.back(), w.goal);
  for (std::size_t i = 1; i < r.path.size(); ++i) {
    EXPECT_TRUE(SegmentIsFree(field, rule, r.path[i - 1], r.path[i], o, nullptr)) << "segment " << i;
  }
  EXPECT_GT(r.iterations, 0);
  EXPECT_EQ(work.Get(WorkUnit::kPlannerIteration), r.iterations);
  EXPECT_GT(work.Get(WorkUnit::kStateCheck), r.iterations);
}

TEST_F(PathSearchTest, SameSeedSamePathDifferentSeedsStillValid) {
  const testing::AsciiWorld w = WallWorld();
  const DistanceField field(w.grid);
  PlannerOptions o;
  o.min_altitude = 0.0;
  const Eigen::AlignedBox3d bounds = SearchBounds(field, w.grid.Box(), o);
  const ClearanceRule rule = MakeClearanceRule(field, w.start, o);
  const PathSearchResult a = SearchPath(field, bounds, rule, w.start, w.goal, 5, o, nullptr);
  for (std::uint32_t seed = 100; seed < 110; ++seed) {
    EXPECT_TRUE(SearchPath(field, bounds, rule, w.start, w.goal, seed, o, nullptr).ok()) << seed;
  }
  const PathSearchResult b = SearchPath(field, bounds, rule, w.start, w.goal, 5, o, nullptr);
  EXPECT_EQ(a.path, b.path);
  EXPECT_EQ(a.iterations, b.iterations);
}

TEST_F(PathSearchTest, ShortcutLeavesNoRemovableVertexOnAStraightRun) {
  VoxelGrid grid(Eigen::Vector3d::Zero(), 0.1, {50, 20, 20}, CellState::kFree);
  const DistanceField field(grid);
  const PlannerOptions o;
  const ClearanceRule rule = MakeClearanceRule(field, Eigen::Vector3d(0.5, 1, 1), o);
  const std::vector<Eigen::Vector3d> zigzag = {{0.5, 1, 1}, {1.5, 1.5, 1}, {2.5, 0.5, 1}, {4.5, 1, 1}};
  const auto cut = ShortcutPath(zigzag, field, rule, o, nullptr);
  ASSERT_EQ(cut.size(), 2u);
  EXPECT_EQ(cut.front(), zigzag.front());
  EXPECT_EQ(cut.back(), zigzag.back());
}

TEST_F(PathSearchTest, StartTooCloseWithoutEscapeIsInvalid) {
  const testing::AsciiWorld w = WallWorld();
  const DistanceField field(w.grid);
  PlannerOptions o;
  o.min_altitude = 0.0;
  ClearanceRule strict;  // no escape ball
  strict.required = o.robot_radius + o.search_margin;
  const Eigen::Vector3d near_wall(2.9, 1.25, 1.0);
  const PathSearchResult r =
      SearchPath(field, SearchBounds(field, w.grid.Box(), o), strict, near_wall, w.goal, 1, o, nullptr);
  EXPECT_EQ(r.status, SearchStatus::kInvalidStart);
  // With the escape rule the same start is usable.
  const ClearanceRule escape = MakeClearanceRule(field, near_wall, o);
  EXPECT_GT(escape.escape_radius, 0.0);
  EXPECT_TRUE(SearchPath(field, SearchBounds(field, w.grid.Box(), o), escape, near_wall, w.goal, 1, o,
                         nullptr).ok());
}

TEST_F(PathSearchTest, LocalGoalIsWhereTheWayToTheGoalLeavesTheVolume) {
  VoxelGrid grid(Eigen::Vector3d::Zero(), 0.1, {60, 40, 20}, CellState::kFree);
  const DistanceField field(grid);
  PlannerOptions o;
  o.min_altitude = 0.0;
  const Eigen::AlignedBox3d bounds = SearchBounds(field, grid.Box(), o);
  const Eigen::Vector3d start(1, 2, 1);
  const ClearanceRule rule = MakeClearanceRule(field, start, o);
  bool local = false;
  const auto goals = GoalCandidates(field, bounds, rule, start, Eigen::Vector3d(21, 2, 1), o, &local, nullptr);
  ASSERT_FALSE(goals.empty());
  EXPECT_TRUE(local);
  EXPECT_NEAR(goals.front().x(), 6.0, 1e-5);
  EXPECT_NEAR(goals.front().y(), 2.0, 1e-9);
  // A goal inside and free is used as is.
  const auto direct = GoalCandidates(field, bounds, rule, start, Eigen::Vector3d(5, 3, 1), o, &local, nullptr);
  ASSERT_EQ(direct.size(), 1u);
  EXPECT_FALSE(local);
}

TEST_F(PathSearchTest, PlanningVolumeIsBiasedTowardsTheGoalAndBounded) {
  const PlannerOptions o;
  const Eigen::AlignedBox3d flight(Eigen::Vector3d(-100, -100, 0), Eigen::Vector3d(100, 100, 5));
  const Eigen::Vector3d start(0, 0, 1.5), goal(50, 0, 1.5);
  const Eigen::AlignedBox3d box = PlanningVolume(start, goal, flight, o);
  EXPECT_TRUE(box.contains(start));
  EXPECT_NEAR(box.max().x() - start.x(), o.camera_range, 1e-9) << "camera range ahead";
  EXPECT_NEAR(start.x() - box.min().x(), o.volume_back_margin, 1e-9);
  EXPECT_TRUE(flight.contains(box));
  EXPECT_LE(box.volume() / (0.1 * 0.1 * 0.1), 1.0e6) << "cells at 0.1 m";
  // A near goal: the box is centred between start and goal.
  const Eigen::AlignedBox3d near = PlanningVolume(start, Eigen::Vector3d(-4, 0, 1.5), flight, o);
  EXPECT_NEAR(near.center().x(), -2.0, 1e-9);
  // At the edge of the flight bounds it shifts inwards and keeps its size.
  const Eigen::AlignedBox3d edge = PlanningVolume(Eigen::Vector3d(99, 0, 1.5), Eigen::Vector3d(99, 50, 1.5), flight, o);
  EXPECT_TRUE(flight.contains(edge));
  EXPECT_NEAR(edge.sizes().x(), o.camera_range + o.volume_back_margin, 1e-9);
}

TEST(PlannerOptionsTest, ValidateNamesTheFieldAndRange) {
  PlannerOptions o;
  EXPECT_NO_THROW(o.Validate());
  o.max_search_iterations = 0;
  try {
    o.Validate();
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_search_iterations"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("[1, "), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace enavi::navstack
