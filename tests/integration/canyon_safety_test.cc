// E-Navi with the shipped policy on street canyons, a world it was not trained on. Before the
// reaction constraint, the policy slowed its map and collision-check rates near building corners
// and nothing kept them within what the vehicle needs to stop before a wall.
#include <gtest/gtest.h>

#include "tests/integration/loop_test_util.h"
#include "workers/sim/episode.h"

namespace enavi::integration {
namespace {

// E-Navi on canyon `seed` and `board`: reaches the goal without a collision or an emergency stop.
api::EpisodeResult ExpectSafeFlight(std::uint64_t seed, const char* board) {
  api::EpisodeSpec spec = Spec("canyon", seed);
  spec.board = board;
  spec.method = "enavi";
  const api::EpisodeResult r = sim::RunEpisode(spec);
  EXPECT_TRUE(r.success) << Describe(r);
  EXPECT_FALSE(r.collided);
  EXPECT_EQ(r.emergency_stops, 0) << Describe(r);
  return r;
}

TEST(CanyonSafetyTest, EnaviSeesTheWallRoundTheCornerInTimeToAvoidItWithoutAnEmergencyStop) {
  // canyon seed 1 on opi5, 37 s in: coming round a corner at 1.5 m/s with 5 Hz map updates and
  // 2 Hz checks, the check found the wall 0.46 s ahead, too late for a replan: emergency stop,
  // 0.44 m from the wall (the frame is 0.29 m in radius; the x86 flight, 0.2 s ahead at
  // 1.7 m/s, hit). The reaction constraint masks those rates there: the planner hears of the wall
  // in time to steer round it.
  //
  // The same flight, 23.4 s in, once refinement steps expired on their own: the map went from
  // 0.4 to 0.5 m beside a wall, the trajectory planned on the finer map ran into the coarser
  // map's inflated cells 0.3 s ahead and the check stopped the vehicle. A coarser map that puts
  // the trajectory being flown in collision is no longer adopted.
  const api::EpisodeResult r = ExpectSafeFlight(1, "opi5");
  int kept = 0;
  for (const api::EpisodeEvent& e : r.events) kept += e.kind == "resolution_kept";
  EXPECT_GE(kept, 1) << "a coarser map was refused at least once: " << Describe(r);
}

TEST(CanyonSafetyTest, EnaviDoesNotFlyIntoSpaceItNeverSaw) {
  // canyon seed 5 on x86, 30.7 s in: flying 1 m beside a wall, a replan reversed the vehicle and
  // dived it 2 m towards the foot of that wall, unknown (so free to the planner) because the level
  // camera never saw it from that close; the check saw the wall 0.15 s before the hit. Unknown
  // space within stopping reach now counts as an obstacle (navstack/planning/observed_space.h).
  ExpectSafeFlight(5, "x86");
}

}  // namespace
}  // namespace enavi::integration
