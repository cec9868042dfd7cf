#include "worlds/movers.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "tests/unit/worlds/test_util.h"
#include "worlds/generators.h"
#include "worlds/validate.h"
#include "worlds/world_io.h"

// Moving obstacles: where a mover is when, how world files describe them (and refuse bad ones
// with file, line, field and reason), and the generators that add them.

namespace enavi::worlds {
namespace {

using testing::TempDir;

constexpr double kEps = 1e-12;

Mover Walker(MoverMode mode, double delay = 0.0) {
  Mover m;
  m.name = "walker";
  Cylinder body;
  body.radius = 0.25;
  body.height = 1.75;
  m.shape = {body};
  MoverWaypoint a, b, c;
  a.position = Eigen::Vector3d(0, 0, 0);
  b.position = Eigen::Vector3d(4, 0, 0);
  c.position = Eigen::Vector3d(4, 3, 0);
  m.waypoints = {a, b, c};
  m.speed = 1.0;
  m.mode = mode;
  m.start_delay = delay;
  return m;
}

void ExpectPose(const MoverPose& p, double x, double y, double yaw, const std::string& what) {
  EXPECT_NEAR(p.position.x(), x, 1e-9) << what;
  EXPECT_NEAR(p.position.y(), y, 1e-9) << what;
  EXPECT_NEAR(p.cos_yaw, std::cos(yaw), 1e-9) << what;
  EXPECT_NEAR(p.sin_yaw, std::sin(yaw), 1e-9) << what;
}

// The path: (0,0) -> (4,0) -> (4,3), 7 m at 1 m/s; a loop closes it with 5 m back to (0,0).
TEST(MoverTrajectoryTest, SpeedMoverFollowsItsPathHeadingAlongIt) {
  const MoverTrajectory loop(Walker(MoverMode::kLoop, 2.0));
  EXPECT_NEAR(loop.period(), 12.0, kEps);
  ExpectPose(loop.Pose(0.0), 0, 0, 0, "stands at the first waypoint during the delay");
  ExpectPose(loop.Pose(2.0), 0, 0, 0, "starts after the delay");
  ExpectPose(loop.Pose(4.0), 2, 0, 0, "2 m along the first leg");
  ExpectPose(loop.Pose(7.5), 4, 1.5, M_PI / 2, "turned up the second leg");
  ExpectPose(loop.Pose(11.5), 4 - 0.8 * 2.5, 3 - 0.6 * 2.5, std::atan2(-3, -4), "on the closing leg");
  ExpectPose(loop.Pose(14.0 + 12.0 * 5), 0, 0, 0, "round again, five loops later");
}

TEST(MoverTrajectoryTest, BackAndForthTurnsAroundAndOnceStops) {
  const MoverTrajectory bf(Walker(MoverMode::kBackAndForth));
  EXPECT_NEAR(bf.period(), 14.0, kEps);
  ExpectPose(bf.Pose(6.0), 4, 2, M_PI / 2, "forth");
  ExpectPose(bf.Pose(8.0), 4, 2, -M_PI / 2, "back, facing the way it goes");
  ExpectPose(bf.Pose(12.0), 2, 0, M_PI, "back along the first leg");
  ExpectPose(bf.Pose(14.0 + 1.0), 1, 0, 0, "forth again");
  const MoverTrajectory once(Walker(MoverMode::kOnce));
  ExpectPose(once.Pose(100.0), 4, 3, M_PI / 2, "stays at the last waypoint");
}

TEST(MoverTrajectoryTest, TimedMoverTurnsTheShortWayBetweenWaypoints) {
  Mover m = Walker(MoverMode::kLoop);
  m.speed = 0.0;
  m.waypoints[0].t = 1.0;
  m.waypoints[0].yaw = 3.0;
  m.waypoints[1].t = 3.0;
  m.waypoints[1].yaw = -3.0;  // 0.28 rad further round through pi, not 6 rad back
  m.waypoints[2].t = 4.0;
  const MoverTrajectory t(m);
  EXPECT_NEAR(t.period(), 4.0, kEps);
  ExpectPose(t.Pose(0.5), 0, 0, 3.0, "before the first waypoint's time");
  ExpectPose(t.Pose(2.0), 2, 0, 3.0 + 0.5 * (2 * M_PI - 6.0), "half way, through pi");
  ExpectPose(t.Pose(3.5), 4, 1.5, -1.5, "");
  ExpectPose(t.Pose(4.5), 0, 0, 3.0, "a loop starts over at the first waypoint (it jumps, as Gazebo's actors)");
}

TEST(MoverTrajectoryTest, SamePoseBitsEveryTime) {
  const MoverTrajectory a(Walker(MoverMode::kBackAndForth, 0.3)), b(Walker(MoverMode::kBackAndForth, 0.3));
  for (double t = 0; t < 30; t += 0.001 * 37) {
    const MoverPose pa = a.Pose(t), pb = b.Pose(t);
    ASSERT_EQ(pa.position, pb.position);
    ASSERT_EQ(pa.cos_yaw, pb.cos_yaw);
  }
}

// A 20 x 10 m yard; a walker crosses the start-goal line back and forth at x = 0:
//
//   y  5 +-------------------+
//        |         ^         |
//      0 | S       |       G |
//        |         v         |
//     -5 +-------------------+
constexpr const char* kYard = R"(format: enavi-world/1
name: "yard"
bounds: {min: [-10.0, -5.0, 0.0], max: [10.0, 5.0, 4.0]}
ground: {z: 0.0}
start: [-8.0, 0.0, 1.5]
goal: [8.0, 0.0, 1.5]
objects: []
movers:
  - name: "walker"
    mode: "back_and_forth"
    speed: 1.4
    start_delay: 1.5
    shape:
      - cylinder: {base: [0.0, 0.0, 0.0], radius: 0.25, height: 1.75}
    waypoints:
      - [0.0, -4.0, 0.0]
      - [0.0, 4.0, 0.0]
  - name: "actor"
    mode: "loop"
    shape:
      - box: {center: [0.0, 0.0, 0.9], size: [0.4, 0.6, 1.8], yaw: 0.0}
    waypoints:
      - {t: 0.0, position: [5.0, -3.0, 0.0], yaw: 1.5708}
      - {t: 4.0, position: [5.0, 3.0, 0.0], yaw: 1.5708}
)";

std::string Replaced(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << "test bug: '" << from << "' not in the world";
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

TEST(MoverWorldFileTest, ReadsBothFormsAndWritesThemBackByteForByte) {
  const World w = ParseWorld(kYard, "yard.yaml", ".");
  ASSERT_EQ(w.movers.size(), 2u);
  EXPECT_EQ(w.movers[0].name, "walker");
  EXPECT_EQ(w.movers[0].mode, MoverMode::kBackAndForth);
  EXPECT_DOUBLE_EQ(w.movers[0].speed, 1.4);
  EXPECT_DOUBLE_EQ(w.movers[0].start_delay, 1.5);
  EXPECT_EQ(w.movers[1].speed, 0.0);
  EXPECT_DOUBLE_EQ(w.movers[1].waypoints[1].t, 4.0);
  const std::string text = WorldToYaml(w);
  EXPECT_NE(text.find("movers:\n  - name: \"walker\"\n"), std::string::npos) << text;
  EXPECT_EQ(WorldToYaml(ParseWorld(text, "again.yaml", ".")), text);
}

struct BadMover {
  std::string from, to;
  int line;
  std::string field, reason;
};

TEST(MoverWorldFileTest, BadMoversNameFileLineFieldAndReason) {
  const BadMover cases[] = {
      {"mode: \"back_and_forth\"", "mode: \"sideways\"", 10, "movers[0].mode", "unknown mode 'sideways'"},
      {"speed: 1.4", "speed: -1", 11, "movers[0].speed", "must be > 0"},
      {"      - [0.0, 4.0, 0.0]", "      - [0.0, 40.0, 0.0]", 17, "movers[0].waypoints[1]", "outside the bounds"},
      {"      - [0.0, 4.0, 0.0]", "      - [0.0, -4.0, 0.0]", 16, "movers[0].waypoints", "no length"},
      {"      - [0.0, 4.0, 0.0]\n", "", 16, "movers[0].waypoints", "at least two"},
      {"{t: 4.0,", "{t: 0.0,", 24, "movers[1].waypoints[1].t", "must be later"},
      {"    shape:\n      - cylinder: {base: [0.0, 0.0, 0.0], radius: 0.25, height: 1.75}", "    shape: []", 13,
       "movers[0].shape", "non-empty"},
      {"name: \"actor\"", "name: \"walker\"", 18, "movers[1].name", "duplicate name"},
      {"start_delay: 1.5", "start_dealy: 1.5", 12, "movers[0].start_dealy", "unknown"},
  };
  for (const BadMover& c : cases) {
    SCOPED_TRACE(c.to);
    try {
      ParseWorld(Replaced(kYard, c.from, c.to), "yard.yaml", ".");
      ADD_FAILURE() << "accepted";
    } catch (const WorldError& e) {
      EXPECT_EQ(e.file(), "yard.yaml");
      EXPECT_EQ(e.line(), c.line) << e.what();
      EXPECT_EQ(e.field(), c.field) << e.what();
      EXPECT_NE(e.reason().find(c.reason), std::string::npos) << e.what();
    }
  }
}

TEST(MoverWorldFileTest, AVehicleMayNotStartInsideAMover) {
  const std::string text = Replaced(kYard, "      - [0.0, -4.0, 0.0]", "      - [-8.0, 0.2, 0.0]");
  try {
    ParseWorld(text, "yard.yaml", ".");
    ADD_FAILURE() << "accepted";
  } catch (const WorldError& e) {
    EXPECT_EQ(e.field(), "movers[0]") << e.what();
    EXPECT_EQ(e.line(), 9) << e.what();
    EXPECT_NE(e.reason().find("'walker' stands within 0.50 m of start"), std::string::npos) << e.what();
  }
}

TEST(MoverGeneratorTest, EachMoverScenarioHasAMoverCrossingTheStraightLine) {
  for (const char* id : {"park-people", "street-traffic"}) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      const World w = Generate(id, seed);
      ASSERT_GE(w.movers.size(), 2u) << id << " seed " << seed;
      // Every mover starts inside the bounds, stays there and clears the start.
      for (const Mover& m : w.movers) {
        const MoverTrajectory trajectory(m);
        for (double t = 0; t < 60; t += 0.5) {
          EXPECT_TRUE(w.bounds.contains(trajectory.Pose(t).position)) << id << " " << m.name << " t " << t;
        }
      }
      // The first mover meets the line: at some time it is within 1 m of it.
      const Eigen::Vector3d d = (w.goal - w.start).normalized();
      const MoverTrajectory first(w.movers[0]);
      double closest = 1e9;
      for (double t = 0; t < first.period() + w.movers[0].start_delay; t += 0.05) {
        Eigen::Vector3d p = first.Pose(t).position;
        p.z() = w.start.z();
        const Eigen::Vector3d rel = p - w.start;
        closest = std::min(closest, (rel - rel.dot(d) * d).norm());
      }
      EXPECT_LT(closest, 1.0) << id << " seed " << seed;
    }
  }
}

TEST(MoverGeneratorTest, MoversZeroIsTheSameWorldWithoutThem) {
  for (const char* id : {"park-people", "street-traffic"}) {
    World with = Generate(id, 3);
    const World without = Generate(id, 3, {{"movers", "0"}});
    EXPECT_TRUE(without.movers.empty()) << id;
    with.movers.clear();
    with.metadata.params = without.metadata.params;
    EXPECT_EQ(WorldToYaml(with), WorldToYaml(without)) << id;
  }
}

TEST(MoverGeneratorTest, StreetTrafficIsS4WithVans) {
  World traffic = Generate("street-traffic", 2);
  const World s4 = Generate("s4", 2);
  EXPECT_EQ(traffic.objects.size(), s4.objects.size());
  traffic.movers.clear();
  traffic.metadata = s4.metadata;  // names the scenario, and its `movers` parameter
  EXPECT_EQ(WorldToYaml(traffic), WorldToYaml(s4)) << "the static city is s4's, the vans are drawn after it";
}

}  // namespace
}  // namespace enavi::worlds
