// Worlds as users bring them: every mesh format, units, up axes, recentring, Gazebo SDF worlds,
// malformed files of each kind, `enavi world convert` and job specs that name such worlds.
#include "worlds/mesh_import.h"

#include <cmath>
#include <random>
#include <string>
#include <variant>

#include <gtest/gtest.h>

#include "api/job_spec.h"
#include "tests/unit/worlds/test_util.h"
#include "tests/unit/worlds/import_fixtures.h"
#include "worlds/mesh.h"
#include "worlds/movers.h"
#include "worlds/primitives.h"
#include "worlds/resolve.h"
#include "worlds/sdf_import.h"
#include "worlds/world_convert.h"
#include "worlds/world_io.h"

namespace enavi::worlds {
namespace {

using testing::TempDir;

// The message of the WorldError `f()` throws ("" if it throws nothing).
template <typename F>
std::string ErrorOf(F&& f) {
  try {
    f();
  } catch (const WorldError& e) {
    return e.what();
  }
  return "";
}

void ExpectBox(const Eigen::AlignedBox3d& b, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double tol,
               const std::string& what) {
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(b.min()[a], lo[a], tol) << what << " min along " << "xyz"[a];
    EXPECT_NEAR(b.max()[a], hi[a], tol) << what << " max along " << "xyz"[a];
  }
}

// The mesh world of one file, as `enavi fly --world FILE --start ... --goal ...` resolves it.
World MeshWorld(const std::filesystem::path& file, const MeshPlacement& placement = {}) {
  WorldRequest r;
  r.world = file.string();
  r.start = testing::kFixtureStart;
  r.goal = testing::kFixtureGoal;
  r.placement = placement;
  return ResolveWorld(r);
}

Eigen::AlignedBox3d PlacedBounds(const World& w) {
  const Eigen::AlignedBox3f b = BuildWorldMesh(w).Bounds();
  return Eigen::AlignedBox3d(b.min().cast<double>(), b.max().cast<double>());
}

TEST(MeshImportTest, EveryFormatGivesTheSourceTrianglesAndBounds) {
  TempDir dir;
  const TriangleMesh box = testing::FixtureBox();
  const std::pair<const char*, std::string> files[] = {
      {"box.gltf", testing::Gltf(box)},      {"box.glb", testing::Glb(box)},
      {"box.dae", testing::DaeMmZUp(box)},   {"box.stl", testing::StlAscii(box)},
      {"binary.stl", testing::StlBinary(box)}, {"box.ply", testing::PlyAscii(box)},
      {"binary.ply", testing::PlyBinary(box)}};
  for (const auto& [name, content] : files) {
    const World w = MeshWorld(dir.Write(name, content));
    EXPECT_EQ(BuildWorldMesh(w).triangle_count(), 12u) << name;
    ExpectBox(PlacedBounds(w), testing::kBoxMin, testing::kBoxMax, 1e-4, name);
  }
}

TEST(MeshImportTest, ObjInMillimetresFarFromTheOriginIsPlacedByUnitsAndRecentring) {
  TempDir dir;
  // A city-block export: millimetres, z up, georeferenced near 1,000 km.
  const auto obj = dir.Write("block.obj", testing::ObjMm(testing::FixtureBox(), {991408123.4, 1002345678.9, 45000.0}));
  EXPECT_NE(ErrorOf([&] { MeshWorld(obj); }).find("give its unit (--units m, cm, mm, in, ft) or --scale"),
            std::string::npos)
      << "in metres the block spans 2 km and lies 1e9 m out";
  MeshPlacement mm;
  mm.units = "mm";
  const std::string far = ErrorOf([&] { MeshWorld(obj, mm); });
  EXPECT_EQ(far.rfind(obj.string() + ": mesh: placed, the mesh reaches 1002350.7 m from the origin", 0), 0u) << far;
  EXPECT_NE(far.find("--recenter moves it to the origin"), std::string::npos) << far;

  mm.recenter = true;
  const World w = MeshWorld(obj, mm);
  EXPECT_EQ(BuildWorldMesh(w).triangle_count(), 12u);
  // 2 x 2 x 2 m, centred on x = y = 0, standing on z = 0: to 0.1 mm, though floats near 1e9 mm
  // are 64 mm apart (placement is done in double).
  ExpectBox(PlacedBounds(w), {-1, -1, 0}, {1, 1, 2}, 1e-4, "recentred block");
  // --scale 0.001 is the same as --units mm for a file that declares no unit.
  MeshPlacement scaled;
  scaled.scale = 0.001;
  scaled.recenter = true;
  ExpectBox(PlacedBounds(MeshWorld(obj, scaled)), {-1, -1, 0}, {1, 1, 2}, 1e-4, "scaled block");
}

TEST(MeshImportTest, DeclaredUnitsAndAxesYieldToTheOnesGiven) {
  TempDir dir;
  const TriangleMesh box = testing::FixtureBox();
  // glTF is y up by its spec; told z, the file's y stays y: the box lies at z in [-5, -3].
  MeshPlacement z_up;
  z_up.up = UpAxis::kZ;
  const ImportedMesh gltf = LoadMeshFile(dir.Write("box.gltf", testing::Gltf(box)));
  ExpectBox(ObjectBounds(PlaceMesh(gltf, z_up, "box.gltf", "box.gltf")), {2, 0, -5}, {4, 2, -3}, 1e-4, "glTF as z up");
  // The DAE says millimetres; told metres, it is a thousand times larger.
  MeshPlacement metres;
  metres.units = "m";
  const ImportedMesh dae = LoadMeshFile(dir.Write("box.dae", testing::DaeMmZUp(box)));
  ExpectBox(ObjectBounds(PlaceMesh(dae, metres, "box.dae", "box.dae")), {2000, 3000, 0}, {4000, 5000, 2000}, 1e-1,
            "DAE in metres");
  EXPECT_EQ(dae.file_unit_m, 0.001);
  EXPECT_EQ(dae.file_up, UpAxis::kZ);
  // Inches and feet are exact.
  MeshPlacement feet;
  feet.units = "ft";
  ExpectBox(ObjectBounds(PlaceMesh(LoadMeshFile(dir.Write("box.stl", testing::StlAscii(box))), feet, "b", "b")),
            0.3048 * testing::kBoxMin, 0.3048 * testing::kBoxMax, 1e-5, "STL in feet");
}

TEST(MeshImportTest, MalformedFilesOfEachFormatAreRefusedNamingTheFile) {
  TempDir dir;
  const TriangleMesh box = testing::FixtureBox();
  std::string nan_stl = testing::StlBinary(box);
  const float nan = std::nanf("");
  std::memcpy(&nan_stl[84 + 12], &nan, 4);  // first vertex of the first triangle
  std::string nan_glb = testing::Glb(box);
  std::memcpy(&nan_glb[nan_glb.size() - 12], &nan, 4);  // last vertex's x
  TriangleMesh far_index = box;
  far_index.triangles[3] = Eigen::Vector3i(0, 1, 40);
  std::string dae_bad_index = testing::DaeMmZUp(far_index);
  std::string ply = testing::PlyAscii(far_index);
  std::string dae_nan = testing::DaeMmZUp(box);
  const std::size_t first = dae_nan.find("\">", dae_nan.find("<float_array")) + 2;
  dae_nan.replace(first, dae_nan.find(' ', first) - first, "nan");
  const std::pair<const char*, std::string> bad[] = {
      {"truncated.gltf", testing::Gltf(box).substr(0, 200)},
      {"truncated.glb", testing::Glb(box).substr(0, 100)},
      {"nan.glb", nan_glb},
      {"index.gltf", testing::Gltf(far_index)},
      {"truncated.dae", testing::DaeMmZUp(box).substr(0, 400)},
      {"index.dae", dae_bad_index},
      {"nan.dae", dae_nan},
      {"truncated.stl", testing::StlBinary(box).substr(0, 300)},
      {"nan.stl", nan_stl},
      {"index.ply", ply},
      {"truncated.ply", testing::PlyAscii(box).substr(0, 150)},
      {"empty.stl", ""},
      {"notamesh.fbx", "hello"},
  };
  for (const auto& [name, content] : bad) {
    const auto path = dir.Write(name, content);
    const std::string e = ErrorOf([&] { LoadMeshFile(path); });
    EXPECT_EQ(e.rfind(path.string() + ":", 0), 0u) << name << ": " << e;
  }
  EXPECT_EQ(ErrorOf([&] { LoadMeshFile(dir.path() / "absent.glb"); }),
            (dir.path() / "absent.glb").string() + ": file: not found or not a regular file");
}

TEST(MeshImportTest, MutatedFilesAreReadOrRefusedButNeverCrash) {
  TempDir dir;
  const TriangleMesh box = testing::FixtureBox();
  const std::pair<const char*, std::string> files[] = {
      {"m.gltf", testing::Gltf(box)},     {"m.glb", testing::Glb(box)},           {"m.dae", testing::DaeMmZUp(box)},
      {"m.stl", testing::StlBinary(box)}, {"a.stl", testing::StlAscii(box)},      {"m.ply", testing::PlyAscii(box)},
      {"b.ply", testing::PlyBinary(box)}, {"m.obj", testing::ObjMm(box, {0, 0, 0})}};
  std::mt19937 rng(14);
  for (const auto& [name, content] : files) {
    for (int i = 0; i < 100; ++i) {
      // Flipped bytes, a cut, or a hole: what a broken download or a bad exporter leaves.
      std::string s = content;
      switch (rng() % 3) {
        case 0:
          for (int k = 0; k < 4; ++k) s[rng() % s.size()] = static_cast<char>(rng());
          break;
        case 1:
          s.resize(rng() % s.size());
          break;
        default:
          s.erase(rng() % s.size(), rng() % 20);
      }
      const auto path = dir.Write(name, s);
      try {
        LoadMeshFile(path);
      } catch (const WorldError& e) {
        EXPECT_EQ(std::string(e.what()).rfind(path.string() + ":", 0), 0u) << name << " #" << i << ": " << e.what();
      }
    }
  }
}

// The Gazebo world of import_fixtures.h with its pillar model in `models/`.
std::filesystem::path WriteGazebo(const TempDir& dir) {
  dir.Write("models/pillar/model.config", testing::PillarModelConfig());
  dir.Write("models/pillar/model.sdf", testing::PillarModelSdf());
  dir.Write("models/pillar/meshes/pillar.stl", testing::StlAscii(testing::UnitCube()));
  return dir.Write("yard.world", testing::GazeboWorld());
}

TEST(SdfImportTest, StaticModelsBecomeObjectsAtTheirPoses) {
  TempDir dir;
  const auto file = WriteGazebo(dir);
  const World w = LoadSdfWorld(file, testing::kFixtureStart, testing::kFixtureGoal, {dir.path() / "models"});
  ASSERT_EQ(w.objects.size(), 4u) << "crate, post, ball, pillar; the rover is not static";
  ASSERT_TRUE(std::holds_alternative<Box>(w.objects[0]));
  const Box& crate = std::get<Box>(w.objects[0]);
  EXPECT_NEAR(crate.yaw, 0.3, 1e-9);
  EXPECT_NEAR((crate.center - Eigen::Vector3d(3, 4, 1)).norm(), 0.0, 1e-9);
  EXPECT_EQ(crate.size, Eigen::Vector3d(2, 1, 2));
  ASSERT_TRUE(std::holds_alternative<Cylinder>(w.objects[1]));
  ExpectBox(ObjectBounds(w.objects[1]), {-0.5, -4.5, 0}, {0.5, -3.5, 3}, 1e-9, "post");
  ASSERT_TRUE(std::holds_alternative<Ellipsoid>(w.objects[2])) << "a link with no collision gives its visual";
  ExpectBox(ObjectBounds(w.objects[2]), {2.25, -4.75, 0.25}, {3.75, -3.25, 1.75}, 1e-9, "ball");
  ASSERT_TRUE(std::holds_alternative<MeshObject>(w.objects[3]));
  EXPECT_EQ(TriangleCount(w.objects[3]), 12u) << "the collision mesh, not the 9 m visual box";
  ExpectBox(ObjectBounds(w.objects[3]), {-3, 4, 0}, {-2, 5, 2}, 1e-6, "pillar (scale 1 1 2)");
  EXPECT_TRUE(w.ground.enabled);
  EXPECT_EQ(w.ground.z, 0.0);
  EXPECT_EQ(BuildWorldMesh(w).triangle_count(), 12u + 96u + 224u + 12u + 2u);
  EXPECT_EQ(w.bounds.min().z(), 0.0) << "the flight volume stands on the ground";
  EXPECT_EQ(w.metadata.name, "yard");
  EXPECT_EQ(w.metadata.import_note,
            "SDF: ignored 2 light(s); physics settings; 1 plugin(s); non-static model(s) 'rover'");
}

TEST(SdfImportTest, PosedPrimitivesAndMeshesAreStoredInTheWorldFrame) {
  TempDir dir;
  const auto file = dir.Write("tilt.sdf", R"(<?xml version="1.0"?>
<sdf version="1.6"><world name="w">
  <model name="ramp"><static>true</static><pose>0 5 1 0.5 0 0</pose><link name="l">
    <collision name="c"><geometry><box><size>2 2 0.2</size></box></geometry></collision></link></model>
</world></sdf>
)");
  const World w = LoadSdfWorld(file, testing::kFixtureStart, testing::kFixtureGoal, {});
  ASSERT_EQ(w.objects.size(), 1u);
  const auto* ramp = std::get_if<MeshObject>(&w.objects[0]);
  ASSERT_NE(ramp, nullptr) << "a box tilted about x is a mesh";
  EXPECT_TRUE(ramp->path.empty());
  const double h = std::cos(0.5) * 1.0 + std::sin(0.5) * 0.1;  // half-extent along y
  ExpectBox(ObjectBounds(*ramp), {-1, 5 - h, 1 - (std::sin(0.5) + 0.1 * std::cos(0.5))},
            {1, 5 + h, 1 + (std::sin(0.5) + 0.1 * std::cos(0.5))}, 1e-5, "ramp");
  EXPECT_FALSE(w.ground.enabled);
}

TEST(SdfImportTest, BadWorldsAreRefusedNamingTheFile) {
  TempDir dir;
  const auto missing = dir.Write("missing.world", R"(<?xml version="1.0"?>
<sdf version="1.6"><world name="w"><include><uri>model://sun</uri></include>
<include><uri>model://warehouse_shelf</uri></include></world></sdf>
)");
  const std::string e = ErrorOf([&] { LoadSdfWorld(missing, testing::kFixtureStart, testing::kFixtureGoal, {}); });
  EXPECT_EQ(e.rfind(missing.string() + ": include: model://warehouse_shelf not found: give its directory with "
                                       "--model-path or GAZEBO_MODEL_PATH",
                    0),
            0u)
      << e;
  const std::pair<const char*, std::string> bad[] = {
      {"truncated.world", testing::GazeboWorld().substr(0, 300)},
      {"heightmap.sdf", R"(<?xml version="1.0"?><sdf version="1.6"><world name="w"><model name="m"><static>true</static>
<link name="l"><collision name="c"><geometry><heightmap><uri>h.png</uri></heightmap></geometry></collision></link></model></world></sdf>)"},
      {"nomesh.sdf", R"(<?xml version="1.0"?><sdf version="1.6"><world name="w"><model name="m"><static>true</static>
<link name="l"><collision name="c"><geometry><mesh><uri>meshes/none.dae</uri></mesh></geometry></collision></link></model></world></sdf>)"},
      {"model.sdf", R"(<?xml version="1.0"?><sdf version="1.6"><model name="m"><link name="l"/></model></sdf>)"},
      {"nan.sdf", R"(<?xml version="1.0"?><sdf version="1.6"><world name="w"><model name="m"><static>true</static>
<pose>nan 0 0 0 0 0</pose><link name="l"><collision name="c"><geometry><box><size>1 1 1</size></box></geometry></collision></link></model></world></sdf>)"},
  };
  for (const auto& [name, content] : bad) {
    const auto path = dir.Write(name, content);
    const std::string m = ErrorOf([&] { LoadSdfWorld(path, testing::kFixtureStart, testing::kFixtureGoal, {}); });
    EXPECT_EQ(m.rfind(path.string() + ":", 0), 0u) << name << ": " << m;
  }
}

// examples/worlds/actor_crossing.sdf: a box-bodied actor walks x = 1 from y = -4 to 4 in 4 s,
// turns, and back by t = 8 s, looping after a 0.5 s delay; a static wall stands aside.
TEST(SdfImportTest, AnActorsScriptedTrajectoryIsATimedMover) {
  const auto file = std::filesystem::path(ENAVI_SOURCE_DIR) / "examples/worlds/actor_crossing.sdf";
  const World w = LoadSdfWorld(file, {-6, 0, 1.5}, {6, 0, 1.5}, {});
  ASSERT_EQ(w.objects.size(), 1u) << "the wall";
  ASSERT_EQ(w.movers.size(), 1u);
  const Mover& m = w.movers[0];
  EXPECT_EQ(m.name, "walker");
  EXPECT_EQ(m.speed, 0.0) << "timed";
  EXPECT_EQ(m.mode, MoverMode::kLoop);
  EXPECT_DOUBLE_EQ(m.start_delay, 0.5);
  ASSERT_EQ(m.waypoints.size(), 4u);
  EXPECT_DOUBLE_EQ(m.waypoints[3].t, 8.0);
  ASSERT_EQ(m.shape.size(), 1u);
  const auto* torso = std::get_if<Box>(&m.shape[0]);
  ASSERT_NE(torso, nullptr) << "an upright box stays a box, in the actor's frame";
  EXPECT_NEAR(torso->center.z(), 0.9, 1e-12);
  const MoverTrajectory trajectory(m);
  EXPECT_NEAR(trajectory.Pose(0.5 + 2.0).position.y(), 0.0, 1e-9) << "crosses the line at t = 2.5 s";
  EXPECT_NEAR(trajectory.Pose(0.5 + 6.25).position.y(), 0.0, 1e-9) << "and back at 6.75 s";
  EXPECT_NEAR(trajectory.Pose(0.5 + 8.0 + 2.0).position.y(), 0.0, 1e-9) << "looping";
  EXPECT_TRUE(w.bounds.contains(Eigen::Vector3d(1, 4.3, 1.8))) << "the bounds hold where it walks";
  EXPECT_EQ(w.metadata.import_note.find("actor"), std::string::npos) << w.metadata.import_note;
  // It survives a world file: written (timed waypoints) and read back the same.
  const std::string text = WorldToYaml(w);
  EXPECT_EQ(WorldToYaml(ParseWorld(text, "actor.yaml", ".")), text);
}

TEST(SdfImportTest, AnActorWithoutGeometryIsRefused) {
  TempDir dir;
  const auto file = dir.Write("ghost.sdf", R"(<?xml version="1.0"?><sdf version="1.6"><world name="w">
<actor name="ghost"><script><trajectory id="0" type="t"><waypoint><time>0</time><pose>0 0 0 0 0 0</pose></waypoint>
<waypoint><time>1</time><pose>1 0 0 0 0 0</pose></waypoint></trajectory></script></actor></world></sdf>)");
  const std::string e = ErrorOf([&] { LoadSdfWorld(file, testing::kFixtureStart, testing::kFixtureGoal, {}); });
  EXPECT_EQ(e, file.string() + ": actor 'ghost': has neither links with geometry nor a <skin>: nothing to see or hit");
}

TEST(WorldConvertTest, AnImportedWorldIsWrittenOnceAndReadBackTheSame) {
  TempDir dir;
  const auto obj = dir.Write("block.obj", testing::ObjMm(testing::FixtureBox(), {991408123.4, 1002345678.9, 45000.0}));
  MeshPlacement mm;
  mm.units = "mm";
  mm.recenter = true;
  const World w = MeshWorld(obj, mm);
  const auto yaml = dir.path() / "block.yaml";
  ConvertWorld(w, dir.path(), yaml);
  const std::string text = testing::ReadFile(yaml);
  EXPECT_NE(text.find(R"(- mesh: {file: "block.obj", position: [0.0, 0.0, 0.0], yaw: 0.0, scale: 1.0, units: "mm", recenter: true})"),
            std::string::npos)
      << text;
  WorldRequest again;
  again.world = yaml.string();
  const World back = ResolveWorld(again);
  EXPECT_EQ(BuildWorldMesh(back).vertices, BuildWorldMesh(w).vertices) << "the same placed geometry";
  ConvertWorld(back, dir.path(), dir.path() / "again.yaml");
  EXPECT_EQ(testing::ReadFile(dir.path() / "again.yaml"), text) << "byte-identical";

  // An SDF world: its geometry beside the output as OBJ, then the same triangles.
  const auto world = WriteGazebo(dir);
  const World sdf = LoadSdfWorld(world, testing::kFixtureStart, testing::kFixtureGoal, {dir.path() / "models"});
  ConvertWorld(sdf, dir.path(), dir.path() / "out" / "yard.yaml");
  EXPECT_TRUE(std::filesystem::is_regular_file(dir.path() / "out" / "yard_meshes" / "object3.obj"));
  WorldRequest converted;
  converted.world = (dir.path() / "out" / "yard.yaml").string();
  const World read = ResolveWorld(converted);
  EXPECT_EQ(BuildWorldMesh(read).triangle_count(), BuildWorldMesh(sdf).triangle_count());
  ExpectBox(PlacedBounds(read), PlacedBounds(sdf).min(), PlacedBounds(sdf).max(), 1e-4, "converted SDF world");
}

TEST(JobSpecWorldsTest, ScenarioEntriesCarryPlacementAndEveryMeshFormatIsAccepted) {
  TempDir dir;
  for (const auto& f : kMeshFormats) dir.Write(std::string("m") + f.extension, "x");
  dir.Write("w.world", "x");
  dir.Write("p.stl", "x");
  dir.Write("models/pillar/model.config", "x");
  api::JobSpecOptions options;
  options.allowed_roots = {dir.path()};
  // Placement is independent of the methods, boards and clocks.
  options.catalog.methods = {{"baseline", "", {}}};
  options.catalog.boards = {"host"};
  options.catalog.scenarios = {"s1"};
  options.catalog.clocks = {"virtual"};
  std::string scenarios;
  for (const auto& f : kMeshFormats) {
    scenarios += std::string("  - {world: m") + f.extension + ", start: [0, 0, 1], goal: [4, 0, 1]}\n";
  }
  const api::JobSpec job = api::ParseJobSpec(
      "boards: [host]\nmethods: [baseline]\nseeds: 1\nscenarios:\n" + scenarios +
          "  - {world: w.world, model_path: [models], start: [0, 0, 1], goal: [4, 0, 1]}\n"
          "  - {world: p.stl, units: mm, up: y, recenter: true, scale: 2, start: [0, 0, 1], goal: [5, 0, 1]}\n",
      "job.yaml", options);
  const auto episodes = api::ExpandJob(job);
  ASSERT_EQ(episodes.size(), kMeshFormats.size() + 2);
  const api::EpisodeSpec& placed = episodes.back();
  EXPECT_EQ(placed.units, "mm");
  EXPECT_EQ(placed.up, "y");
  EXPECT_TRUE(placed.recenter);
  EXPECT_EQ(placed.scale, 2.0);
  ASSERT_EQ(episodes[kMeshFormats.size()].model_path.size(), 1u);
  EXPECT_EQ(episodes[kMeshFormats.size()].model_path[0], (dir.path() / "models").string());
  // Placement on a farm world file, a bad unit, a mesh without start and goal: refused.
  auto error = [&](const std::string& entry) {
    try {
      api::ParseJobSpec("boards: [host]\nmethods: [baseline]\nseeds: 1\nscenarios:\n  - " + entry + "\n", "job.yaml",
                        options);
    } catch (const api::JobSpecError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error("{world: m.stl, units: furlong, start: [0, 0, 1], goal: [4, 0, 1]}").find("unknown unit 'furlong'"),
            std::string::npos);
  EXPECT_NE(error("m.glb").find("is a mesh or SDF world: give start and goal"), std::string::npos);
  for (const auto& u : kLengthUnits) {
    EXPECT_EQ(error(std::string("{world: m.stl, units: ") + u.name + ", start: [0, 0, 1], goal: [4, 0, 1]}"), "")
        << u.name;
  }
}

}  // namespace
}  // namespace enavi::worlds
