#include "worlds/resolve.h"

#include <gtest/gtest.h>

#include "tests/unit/worlds/test_util.h"
#include "worlds/generators.h"
#include "worlds/world_io.h"

namespace enavi::worlds {
namespace {

std::string ErrorOf(const WorldRequest& r) {
  try {
    ResolveWorld(r);
  } catch (const WorldError& e) {
    return e.what();
  }
  return "";
}

constexpr const char* kCube = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                              "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

TEST(ResolveTest, ScenarioIdGeneratesWithSeedAndParams) {
  WorldRequest r;
  r.world = "forest";
  r.seed = 9;
  r.params = {{"density", "1.5"}};
  const World w = ResolveWorld(r);
  EXPECT_EQ(WorldToYaml(w), WorldToYaml(Generate("forest", 9, {{"density", "1.5"}})));
}

TEST(ResolveTest, StartGoalOverrideIsValidated) {
  WorldRequest r;
  r.world = "empty";
  r.goal = Eigen::Vector3d(5, 1, 2);
  EXPECT_EQ(ResolveWorld(r).goal, Eigen::Vector3d(5, 1, 2));
  r.goal = Eigen::Vector3d(500, 0, 2);
  EXPECT_EQ(ErrorOf(r).rfind("empty: goal: [500.00, 0.00, 2.00] is outside the bounds", 0), 0u) << ErrorOf(r);
}

TEST(ResolveTest, YamlFileIsLoaded) {
  testing::TempDir dir;
  const auto path = dir.path() / "w.yaml";
  SaveWorldFile(Generate("s4", 2), path);
  WorldRequest r;
  r.world = path.string();
  EXPECT_EQ(ResolveWorld(r).metadata.scenario, "s4");
  r.params = {{"length", "40"}};
  EXPECT_EQ(ErrorOf(r), path.string() + ": params: generator parameters apply to scenario ids only, not to files");
}

TEST(ResolveTest, ObjNeedsStartAndGoal) {
  testing::TempDir dir;
  const auto path = dir.Write("cube.obj", kCube);
  WorldRequest r;
  r.world = path.string();
  EXPECT_EQ(ErrorOf(r), path.string() + ": start: required for a mesh world (--start x,y,z)");
  r.start = Eigen::Vector3d(-2, 0.5, 0.5);
  EXPECT_EQ(ErrorOf(r), path.string() + ": goal: required for a mesh world (--goal x,y,z)");
  r.goal = Eigen::Vector3d(3, 0.5, 0.5);
  const World w = ResolveWorld(r);
  EXPECT_EQ(w.metadata.scenario, "custom");
  EXPECT_FALSE(w.ground.enabled);
  r.goal = Eigen::Vector3d(0.5, 0.5, 0.5);  // inside the cube
  EXPECT_EQ(ErrorOf(r), path.string() + ": goal: [0.50, 0.50, 0.50] is inside objects[0] (mesh)");
}

TEST(ResolveTest, UnknownWorldIsNamed) {
  WorldRequest r;
  r.world = "moon";
  EXPECT_EQ(ErrorOf(r),
            "world: 'moon' is neither a scenario (s1, s2, s3, s4, s5, canyon, forest, empty, park-people, "
            "street-traffic) nor a world "
            "file (.yaml, .obj, .gltf, .glb, .dae, .stl, .ply, .fbx, .sdf, .world)");
}

}  // namespace
}  // namespace enavi::worlds
