// E-Navi with the shipped policy on street canyons, a world it was not trained on: near building
// corners the policy slows its map and collision-check rates, and before the reaction constraint
// nothing kept those rates (or the speed) within what the vehicle needs to stop before a wall.
#include <algorithm>
#include <limits>

#include <gtest/gtest.h>

#include "tests/integration/loop_test_util.h"
#include "workers/sim/episode.h"
#include "worlds/generators.h"
#include "worlds/validate.h"

namespace enavi::integration {
namespace {

// Least distance from the flown path to any building, m.
double MinClearance(const api::EpisodeResult& r, const worlds::World& world) {
  const worlds::ObstacleField field(world, /*include_ground=*/false);
  double least = std::numeric_limits<double>::infinity();
  for (const auto& p : r.series.position) least = std::min(least, field.Distance(Eigen::Vector3d(p[0], p[1], p[2])));
  return least;
}

TEST(CanyonSafetyTest, EnaviRoundsTheCornersWithThePlannersClearance) {
  // canyon seed 6 on x86: without the reaction constraint E-Navi came round a corner at 5 Hz map
  // updates and 2 Hz checks at 1.6 m/s and passed 0.39 m from a wall (the frame is 0.29 m in
  // radius). The planner aims for robot radius 0.3 + safe_distance_margin 0.2 = 0.5 m.
  api::EpisodeSpec spec = Spec("canyon", 6);
  spec.board = "x86";
  spec.method = "enavi";
  const api::EpisodeResult r = sim::RunEpisode(spec);
  ASSERT_TRUE(r.success) << Describe(r);
  EXPECT_FALSE(r.collided);
  EXPECT_GE(MinClearance(r, worlds::Generate("canyon", 6)), 0.5) << Describe(r);
}

}  // namespace
}  // namespace enavi::integration
