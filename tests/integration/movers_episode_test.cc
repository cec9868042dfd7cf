// Episodes in worlds with movers (issue 45 part 2): a Gazebo actor flown moving, collisions with
// a mover told apart from the static world's, and the same spec giving the same bytes.
#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "api/episode.h"
#include "tests/integration/loop_test_util.h"
#include "workers/sim/episode.h"
#include "worlds/movers.h"

namespace enavi::integration {
namespace {

//   top view (y up):   S (-6,0) ------------------------------ G (6,0)
//                                <<<< runner, from x = 6 to x = -8 along y = 0 at 4 m/s
// A hand-written Gazebo world whose actor runs the start-goal line head-on at the vehicle: it
// starts beyond the goal, so a vehicle that met it where it stood at t = 0 would be at the goal.
constexpr const char* kRunnerWorld = R"(<?xml version="1.0"?>
<sdf version="1.6"><world name="runner">
  <include><uri>model://ground_plane</uri></include>
  <actor name="runner">
    <link name="body"><pose>0 0 1 0 0 0</pose>
      <collision name="c"><geometry><box><size>0.6 1.6 2</size></box></geometry></collision>
    </link>
    <script><loop>false</loop><delay_start>1</delay_start>
      <trajectory id="0" type="run">
        <waypoint><time>0</time><pose>7 0 0 0 0 3.1416</pose></waypoint>
        <waypoint><time>3.75</time><pose>-8 0 0 0 0 3.1416</pose></waypoint>
      </trajectory>
    </script>
  </actor>
</world></sdf>
)";

api::EpisodeSpec RunnerSpec(const TempDir& dir) {
  api::EpisodeSpec spec = Spec(dir.Write("runner.sdf", kRunnerWorld).string(), 1);
  spec.start = api::Vec3{-6, 0, 1.5};
  spec.goal = api::Vec3{6, 0, 1.5};
  spec.timeout_s = 20;
  return spec;
}

TEST(MoversEpisodeTest, AnSdfActorMovesInTheFlightAndWhatWasHitIsNamed) {
  const TempDir dir;
  const api::EpisodeSpec spec = RunnerSpec(dir);
  const api::EpisodeResult r = sim::RunEpisode(spec);
  EXPECT_EQ(r.notes.at("movers"), "1");
  // Nothing static stands between start and goal: a collision can only be the runner, met
  // between the two, far from x = 7 where it stood when the flight began.
  ASSERT_TRUE(r.collided) << Describe(r);
  EXPECT_EQ(r.collided_with, "mover:runner") << Describe(r);
  ASSERT_TRUE(r.collision_point.has_value());
  EXPECT_LT((*r.collision_point)[0], 4.0) << Describe(r);
  EXPECT_GT((*r.collision_point)[0], -6.5) << Describe(r);
  const nlohmann::json summary = api::ResultSummaryJson(r);
  EXPECT_EQ(summary["collided_with"], "mover:runner");
  EXPECT_EQ(summary["collided_mover"], true);
}

// A static collision says "static": CollisionTest in episode_loop_test.cc.

TEST(MoversEpisodeTest, SameSpecTwiceGivesIdenticalJsonWithMovers) {
  // park-people: people on footpaths, one timed to cross the line when the flight gets there.
  api::EpisodeSpec spec = Spec("park-people", 2, {{"length", "24"}});
  spec.method = "fixed";
  spec.timeout_s = 5;
  const auto world = sim::PrepareSpecWorld(spec);
  ASSERT_FALSE(world->world.movers.empty());
  // One run reuses a prepared world (no state carried over), the other regenerates it.
  const api::EpisodeResult first = sim::RunEpisode(spec, *world);
  const api::EpisodeResult second = sim::RunEpisode(spec);
  ASSERT_GT(first.series.size(), 40u) << Describe(first);
  EXPECT_EQ(nlohmann::json(first).dump(), nlohmann::json(second).dump());
}

// E-Navi replans when its map is refined, not when it is coarsened with the trajectory being
// flown checked clear on the coarser map (docs/models.md, "Resolution Adapter"). The flight that
// showed replans at coarsenings picking new routes while a van passed: street-traffic seed 1 on
// tx2 (docs/results.md, "E-Navi without a replan at each coarsening").
TEST(MoversEpisodeTest, EnaviReplansOnARefinedMapNotOnACoarsenedOne) {
  api::EpisodeSpec spec = Spec("street-traffic", 1);
  spec.board = "tx2";
  spec.method = "enavi";
  const api::EpisodeResult r = sim::RunEpisode(spec);
  const api::TimeSeries& s = r.series;
  ASSERT_GT(s.size(), 100u) << Describe(r);
  int coarsenings = 0, refinements = 0;
  for (std::size_t i = 1; i < s.size(); ++i) {
    coarsenings += s.res[i] > s.res[i - 1];
    refinements += s.res[i] < s.res[i - 1];
  }
  ASSERT_GE(coarsenings, 3) << "the flight has coarsenings to answer or not";
  ASSERT_GE(refinements, 3);
  int resolution_replans = 0, after_coarsening = 0;
  for (const api::EpisodeEvent& e : r.events) {
    if (e.kind != "replan" || e.detail != "resolution") continue;
    ++resolution_replans;
    // The map the plan was made on (the first sample at or after the plan) and the map before
    // its last switch.
    std::size_t i = 0;
    while (i + 1 < s.size() && s.t[i] < e.t) ++i;
    std::size_t j = i;
    while (j > 0 && s.res[j - 1] == s.res[i]) --j;
    ASSERT_GT(j, 0u) << "a resolution replan at t = " << e.t << " with no switch before it";
    if (s.res[i] < s.res[j - 1]) continue;  // a refinement
    // A coarsening replans only when another plan replaced the checked trajectory meanwhile:
    // one landed after the coarser level was announced.
    ++after_coarsening;
    double announced = -1;
    for (const api::EpisodeEvent& a : r.events)
      if (a.t <= e.t && a.kind == "resolution" && std::abs(std::stod(a.detail) - s.res[i]) < 1e-9) announced = a.t;
    bool replaced = false;
    for (const api::EpisodeEvent& p : r.events)
      replaced |= p.kind == "replan" && p.t > announced && p.t < e.t;
    EXPECT_TRUE(replaced) << "a replan at t = " << e.t << " after the map went from " << s.res[j - 1] << " to "
                          << s.res[i] << " m, its trajectory unchanged since " << announced;
  }
  EXPECT_EQ(resolution_replans, r.replans_by_trigger.at("resolution"));
  EXPECT_LT(after_coarsening, resolution_replans - after_coarsening) << "most are refinements' replans";
}

}  // namespace
}  // namespace enavi::integration
