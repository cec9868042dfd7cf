#include "worlds/world_io.h"

#include <filesystem>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "tests/unit/worlds/test_util.h"
#include "worlds/obj_import.h"

namespace enavi::worlds {
namespace {

using testing::TempDir;

// Top view (z up); a 20 x 10 m yard with one box and a chair mesh:
//
//   y
//   5 +------------------------------+
//     |          ##                  |
//   0 | S        ##        chair   G |
//     |          ##                  |
//  -5 +------------------------------+
//    -10                             10  x
constexpr const char* kWorld = R"(format: enavi-world/1
name: "yard"
metadata:
  scenario: "custom"
  seed: 0
  generator_version: 0
  params: {}
bounds: {min: [-10.0, -5.0, 0.0], max: [10.0, 5.0, 4.0]}
ground: {z: 0.0}
start: [-8.0, 0.0, 1.5]
goal: [8.0, 0.0, 1.5]
objects:
  - box: {center: [-3.0, 0.0, 1.0], size: [1.0, 3.0, 2.0], yaw: 0.0}
  - cylinder: {base: [0.0, 4.0, 0.0], radius: 0.3, height: 3.0}
  - ellipsoid: {center: [0.0, -4.0, 2.0], radii: [0.8, 0.8, 1.0]}
  - mesh: {file: "models/chair.obj", position: [4.0, 0.0, 0.0], yaw: 0.3, scale: 1.0}
)";

constexpr const char* kChair = "v 0 0 0\nv 0.5 0 0\nv 0.5 0.5 0\nv 0 0.5 0\nv 0 0 1\nv 0.5 0 1\nv 0.5 0.5 1\n"
                               "v 0 0.5 1\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

WorldFileOptions NoValidation() {
  WorldFileOptions o;
  o.validate = false;
  return o;
}

// Writes kWorld with one substitution (the first occurrence of `from` replaced by `to`).
std::filesystem::path WriteWorld(const TempDir& dir, const std::string& from = "", const std::string& to = "") {
  std::string text = kWorld;
  if (!from.empty()) {
    const auto pos = text.find(from);
    EXPECT_NE(pos, std::string::npos) << "test bug: '" << from << "' not in the template";
    if (pos != std::string::npos) text.replace(pos, from.size(), to);
  }
  dir.Write("models/chair.obj", kChair);
  return dir.Write("w.yaml", text);
}

// The WorldError a load throws; fails the test if there is none.
WorldError LoadError(const std::filesystem::path& path, const WorldFileOptions& options = {}) {
  try {
    LoadWorldFile(path, options);
  } catch (const WorldError& e) {
    return e;
  }
  ADD_FAILURE() << "expected a WorldError loading " << path;
  return WorldError("", 0, "", "");
}

// Checks file, line and field of the error, and that the message has the documented form.
void ExpectError(const WorldError& e, const std::filesystem::path& file, int line, const std::string& field,
                 const std::string& reason_part) {
  EXPECT_EQ(e.file(), file.string());
  EXPECT_EQ(e.line(), line) << e.what();
  EXPECT_EQ(e.field(), field) << e.what();
  EXPECT_NE(e.reason().find(reason_part), std::string::npos) << "reason '" << e.reason() << "' lacks '" << reason_part << "'";
  const std::string expected = file.string() + (line > 0 ? ":" + std::to_string(line) : "") + ": " + field + ": " + e.reason();
  EXPECT_EQ(std::string(e.what()), expected);
}

TEST(WorldIoTest, LoadsEveryObjectKind) {
  TempDir dir;
  const World w = LoadWorldFile(WriteWorld(dir));
  EXPECT_EQ(w.metadata.name, "yard");
  EXPECT_EQ(w.bounds.max(), Eigen::Vector3d(10, 5, 4));
  ASSERT_EQ(w.objects.size(), 4u);
  EXPECT_EQ(std::get<Box>(w.objects[0]).size, Eigen::Vector3d(1, 3, 2));
  EXPECT_EQ(std::get<Cylinder>(w.objects[1]).radius, 0.3);
  EXPECT_EQ(std::get<Ellipsoid>(w.objects[2]).radii, Eigen::Vector3d(0.8, 0.8, 1.0));
  const auto& chair = std::get<MeshObject>(w.objects[3]);
  EXPECT_EQ(chair.path, "models/chair.obj");
  EXPECT_EQ(chair.mesh.triangle_count(), 12u);
  EXPECT_EQ(chair.yaw, 0.3);
}

TEST(WorldIoTest, WriteThenReadGivesTheSameBytes) {
  TempDir dir;
  const World w = LoadWorldFile(WriteWorld(dir));
  const std::string text = WorldToYaml(w);
  EXPECT_EQ(text, kWorld) << "the writer's canonical form is the template's";
  const World again = ParseWorld(text, "again.yaml", dir.path());
  EXPECT_EQ(WorldToYaml(again), text);
}

TEST(WorldIoTest, WriterRoundsToFourDecimalsAndNeverWritesMinusZero) {
  World w;
  w.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, 0), Eigen::Vector3d(1, 1, 2));
  w.start = Eigen::Vector3d(-0.00001, 0.123456789, 1e-9);
  w.goal = Eigen::Vector3d(-0.0, 2.5, 1234.56785);
  w.metadata.name = "quote\" back\\slash";
  w.metadata.params["k"] = "v";
  const std::string text = WorldToYaml(w);
  EXPECT_NE(text.find("start: [0.0, 0.1235, 0.0]\n"), std::string::npos) << text;
  EXPECT_NE(text.find("goal: [0.0, 2.5, 1234.5679]\n"), std::string::npos) << text;
  EXPECT_NE(text.find("name: \"quote\\\" back\\\\slash\"\n"), std::string::npos) << text;
  EXPECT_NE(text.find("params: {k: \"v\"}"), std::string::npos) << text;
  EXPECT_NE(text.find("objects: []"), std::string::npos) << text;
  const World back = ParseWorld(text, "q.yaml", ".", NoValidation());
  EXPECT_EQ(back.metadata.name, w.metadata.name);
}

TEST(WorldIoTest, GroundNoneAndDefaults) {
  TempDir dir;
  const World w = LoadWorldFile(WriteWorld(dir, "ground: {z: 0.0}", "ground: none"), NoValidation());
  EXPECT_FALSE(w.ground.enabled);
  // Without metadata and name: scenario "custom", name from the file.
  const World bare = ParseWorld("format: enavi-world/1\nbounds: {min: [0, 0, 0], max: [4, 4, 4]}\n"
                                "start: [1, 1, 1]\ngoal: [3, 3, 1]\n",
                                "dir/bare.yaml", ".");
  EXPECT_EQ(bare.metadata.scenario, "custom");
  EXPECT_EQ(bare.metadata.name, "bare");
  EXPECT_TRUE(bare.objects.empty());
}

TEST(WorldIoTest, MalformedYamlNamesTheLine) {
  TempDir dir;
  const auto path = WriteWorld(dir, "goal: [8.0, 0.0, 1.5]", "goal: [8.0, 0.0, 1.5");
  const WorldError e = LoadError(path);
  EXPECT_EQ(e.field(), "yaml");
  EXPECT_GE(e.line(), 11) << e.what();
  EXPECT_EQ(e.file(), path.string());
}

TEST(WorldIoTest, UnknownKeysAreRefusedAnywhere) {
  TempDir dir;
  ExpectError(LoadError(WriteWorld(dir, "ground:", "colour: red\nground:")), dir.path() / "w.yaml", 9, "colour",
              "unknown key");
  ExpectError(LoadError(WriteWorld(dir, "yaw: 0.0}", "yaw: 0.0, colour: red}")), dir.path() / "w.yaml", 13,
              "objects[0].box.colour", "unknown key (allowed: center, size, yaw)");
  ExpectError(LoadError(WriteWorld(dir, "seed: 0", "seed: 0\n  author: me")), dir.path() / "w.yaml", 6,
              "metadata.author", "unknown key");
  ExpectError(LoadError(WriteWorld(dir, "max: [10.0", "maxi: [10.0")), dir.path() / "w.yaml", 8, "bounds.maxi",
              "unknown key");
  ExpectError(LoadError(WriteWorld(dir, "  - cylinder:", "  - cone:")), dir.path() / "w.yaml", 14, "objects[1].cone",
              "unknown key (allowed: box, cylinder, ellipsoid, mesh)");
}

TEST(WorldIoTest, DuplicateKeysAreRefused) {
  TempDir dir;
  ExpectError(LoadError(WriteWorld(dir, "goal: [8.0, 0.0, 1.5]", "goal: [8.0, 0.0, 1.5]\ngoal: [7.0, 0.0, 1.5]")),
              dir.path() / "w.yaml", 12, "goal", "duplicate key");
}

TEST(WorldIoTest, WrongTypesNameTheField) {
  TempDir dir;
  const auto file = dir.path() / "w.yaml";
  ExpectError(LoadError(WriteWorld(dir, "start: [-8.0, 0.0, 1.5]", "start: somewhere")), file, 10, "start",
              "expected [x, y, z] (got a scalar)");
  ExpectError(LoadError(WriteWorld(dir, "size: [1.0, 3.0, 2.0]", "size: [1.0, 3.0]")), file, 13,
              "objects[0].box.size", "expected [x, y, z] (got 2 values)");
  ExpectError(LoadError(WriteWorld(dir, "radius: 0.3", "radius: thin")), file, 14, "objects[1].cylinder.radius",
              "expected a finite number (got thin)");
  ExpectError(LoadError(WriteWorld(dir, "ground: {z: 0.0}", "ground: flat")), file, 9, "ground",
              "expected {z: number} or none");
  ExpectError(LoadError(WriteWorld(dir, "seed: 0", "seed: -4")), file, 5, "metadata.seed", "unsigned integer");
}

TEST(WorldIoTest, ObjectsMustBeASequenceOfOneKindEach) {
  const std::string head = "format: enavi-world/1\nbounds: {min: [0, 0, 0], max: [4, 4, 4]}\nstart: [1, 1, 1]\n"
                           "goal: [3, 3, 1]\n";
  try {
    ParseWorld(head + "objects: 3\n", "o.yaml", ".");
    FAIL() << "expected an error";
  } catch (const WorldError& e) {
    EXPECT_EQ(std::string(e.what()), "o.yaml:5: objects: expected a sequence (got a scalar)");
  }
  try {
    ParseWorld(head + "objects:\n  - {box: {center: [1, 1, 1], size: [1, 1, 1]}, cylinder: {}}\n", "o.yaml", ".");
    FAIL() << "expected an error";
  } catch (const WorldError& e) {
    EXPECT_EQ(e.field(), "objects[0]");
    EXPECT_EQ(e.line(), 6);
  }
}

TEST(WorldIoTest, MissingRequiredFieldsAreNamed) {
  TempDir dir;
  const auto file = dir.path() / "w.yaml";
  ExpectError(LoadError(WriteWorld(dir, "start: [-8.0, 0.0, 1.5]\n", "")), file, 1, "start", "missing (required)");
  ExpectError(LoadError(WriteWorld(dir, "goal: [8.0, 0.0, 1.5]\n", "")), file, 1, "goal", "missing (required)");
  ExpectError(LoadError(WriteWorld(dir, "bounds: {min: [-10.0, -5.0, 0.0], max: [10.0, 5.0, 4.0]}\n", "")), file, 1,
              "bounds", "missing (required)");
  ExpectError(LoadError(WriteWorld(dir, "format: enavi-world/1\n", "")), file, 1, "format", "missing (required)");
  ExpectError(LoadError(WriteWorld(dir, ", radius: 0.3", "")), file, 14, "objects[1].cylinder.radius",
              "missing (required)");
}

TEST(WorldIoTest, NonFiniteAndAbsurdNumbersAreRefused) {
  TempDir dir;
  const auto file = dir.path() / "w.yaml";
  ExpectError(LoadError(WriteWorld(dir, "size: [1.0, 3.0, 2.0]", "size: [1.0, -1, 2.0]")), file, 13,
              "objects[0].box.size", "must be > 0.0 (got -1)");
  ExpectError(LoadError(WriteWorld(dir, "start: [-8.0, 0.0, 1.5]", "start: [.nan, 0.0, 1.5]")), file, 10, "start",
              "expected a finite number (got .nan)");
  ExpectError(LoadError(WriteWorld(dir, "start: [-8.0, 0.0, 1.5]", "start: [1e400, 0.0, 1.5]")), file, 10, "start",
              "expected a finite number");
  ExpectError(LoadError(WriteWorld(dir, "center: [-3.0, 0.0, 1.0]", "center: [-3.0, 1e7, 1.0]")), file, 13,
              "objects[0].box.center", "must be <= 100000.0");
  ExpectError(LoadError(WriteWorld(dir, "yaw: 0.0}", "yaw: 99.0}")), file, 13, "objects[0].box.yaw",
              "must be <= 6.2832 (got 99.0)");
  ExpectError(LoadError(WriteWorld(dir, "scale: 1.0", "scale: 0")), file, 16, "objects[3].mesh.scale",
              "must be > 0.0 (got 0)");
}

TEST(WorldIoTest, BoundsMustBeOrderedAndAtMostTwoKilometres) {
  TempDir dir;
  const auto file = dir.path() / "w.yaml";
  ExpectError(LoadError(WriteWorld(dir, "max: [10.0, 5.0, 4.0]", "max: [10.0, -6.0, 4.0]")), file, 8, "bounds.max",
              "must exceed bounds.min along y");
  ExpectError(LoadError(WriteWorld(dir, "max: [10.0, 5.0, 4.0]", "max: [2000.0, 5.0, 4.0]")), file, 8, "bounds",
              "extent along x is 2010.0 m (limit 2000 m)");
}

TEST(WorldIoTest, ObjectAndTriangleLimitsAreEnforced) {
  TempDir dir;
  const auto file = dir.path() / "w.yaml";
  WorldFileOptions few;
  few.max_objects = 3;
  ExpectError(LoadError(WriteWorld(dir), few), file, 13, "objects", "more than 3 objects (4)");
  WorldFileOptions small;
  small.max_triangles = 100;  // box 12 + cylinder 96 > 100
  ExpectError(LoadError(WriteWorld(dir), small), file, 14, "objects[1]", "exceeds 100 triangles");
}

TEST(WorldIoTest, DefaultTriangleLimitIsFiveMillion) {
  // 22,400 ellipsoids x 224 triangles > 5,000,000.
  std::string text =
      "format: enavi-world/1\nbounds: {min: [0, 0, 0], max: [100, 100, 10]}\nstart: [1, 1, 1]\ngoal: [2, 2, 1]\n"
      "objects:\n";
  for (int i = 0; i < 22400; ++i) text += "  - ellipsoid: {center: [50, 50, 5], radii: [1, 1, 1]}\n";
  try {
    ParseWorld(text, "big.yaml", ".", NoValidation());
    FAIL() << "expected the triangle limit";
  } catch (const WorldError& e) {
    EXPECT_EQ(e.field(), "objects[22321]");
    EXPECT_EQ(e.line(), 6 + 22321);
    EXPECT_NE(e.reason().find("5000000 triangles"), std::string::npos) << e.what();
  }
}

TEST(WorldIoTest, FileOver256MiBIsRefusedBeforeParsing) {
  TempDir dir;
  const auto path = dir.path() / "huge.yaml";
  { std::ofstream(path) << "format: enavi-world/1\n"; }
  std::filesystem::resize_file(path, (256ull << 20) + 1);  // sparse: no disk used
  ExpectError(LoadError(path), path, 0, "file", "too large (268435457 bytes; limit 256 MiB)");
}

TEST(WorldIoTest, MeshFilesMustExistAndStayInsideTheWorldDirectory) {
  TempDir dir;
  const auto file = dir.path() / "w.yaml";
  ExpectError(LoadError(WriteWorld(dir, "models/chair.obj", "models/table.obj")), file, 16, "objects[3].mesh.file",
              "file not found");
  ExpectError(LoadError(WriteWorld(dir, "models/chair.obj", "../chair.obj")), file, 16, "objects[3].mesh.file",
              "'..' is not allowed");
  ExpectError(LoadError(WriteWorld(dir, "models/chair.obj", "/etc/passwd")), file, 16, "objects[3].mesh.file",
              "absolute paths are not allowed");
  // A symlink pointing out of the tree is caught too.
  TempDir outside;
  const auto target = outside.Write("chair.obj", kChair);
  std::filesystem::create_directories(dir.path() / "models");
  std::filesystem::create_symlink(target, dir.path() / "models" / "link.obj");
  ExpectError(LoadError(WriteWorld(dir, "models/chair.obj", "models/link.obj")), file, 16, "objects[3].mesh.file",
              "resolves outside the world file's directory");
}

TEST(WorldIoTest, ErrorsInsideAMeshNameTheObjFileAndLine) {
  TempDir dir;
  const auto path = WriteWorld(dir);
  dir.Write("models/chair.obj", "v 0 0 0\nv 1 0 0\nf 1 2 9\n");
  const WorldError e = LoadError(path);
  EXPECT_EQ(e.file(), (dir.path() / "models/chair.obj").string());
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.field(), "f");
  // ... and the world entry that asked for it.
  EXPECT_NE(std::string(e.what()).find("(mesh of " + path.string() + ":16: objects[3].mesh.file)"), std::string::npos)
      << e.what();
}

TEST(WorldIoTest, StartAndGoalMustBeInsideTheBoundsAndClear) {
  TempDir dir;
  const auto file = dir.path() / "w.yaml";
  ExpectError(LoadError(WriteWorld(dir, "start: [-8.0, 0.0, 1.5]", "start: [-12.0, 0.0, 1.5]")), file, 10, "start",
              "outside the bounds");
  ExpectError(LoadError(WriteWorld(dir, "goal: [8.0, 0.0, 1.5]", "goal: [-3.0, 0.0, 1.0]")), file, 11, "goal",
              "is inside objects[0] (box)");
  ExpectError(LoadError(WriteWorld(dir, "goal: [8.0, 0.0, 1.5]", "goal: [-2.3, 0.0, 1.0]")), file, 11, "goal",
              "0.20 m from objects[0] (box); needs at least 0.50 m clearance");
  ExpectError(LoadError(WriteWorld(dir, "start: [-8.0, 0.0, 1.5]", "start: [-8.0, 0.0, 0.3]")), file, 10, "start",
              "0.30 m from the ground");
}

TEST(WorldIoTest, BlockedRouteIsReportedOnTheGoal) {
  TempDir dir;
  // A wall across the whole yard, taller than the bounds.
  const auto path = WriteWorld(dir, "size: [1.0, 3.0, 2.0]", "size: [1.0, 30.0, 20.0]");
  ExpectError(LoadError(path), dir.path() / "w.yaml", 11, "goal", "no collision-free route at least 1.00 m wide");
}

TEST(WorldIoTest, CommandLineStartOverridesTheFile) {
  TempDir dir;
  WorldFileOptions options;
  options.start = Eigen::Vector3d(-8.0, 2.0, 2.0);
  const World w = LoadWorldFile(WriteWorld(dir, "start: [-8.0, 0.0, 1.5]\n", ""), options);
  EXPECT_EQ(w.start, Eigen::Vector3d(-8.0, 2.0, 2.0));
  // A bad override is reported without a file line.
  options.start = Eigen::Vector3d(-3.0, 0.0, 1.0);
  ExpectError(LoadError(WriteWorld(dir), options), dir.path() / "w.yaml", 0, "start", "is inside objects[0] (box)");
}

TEST(WorldIoTest, MutatedFilesNeverCrashOnlyThrowWorldError) {
  TempDir dir;
  WriteWorld(dir);
  std::mt19937_64 rng(11);
  const std::string base = kWorld;
  int loaded = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::string text = base;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int k = 0; k < edits; ++k) {
      const std::size_t pos = rng() % text.size();
      switch (rng() % 3) {
        case 0: text[pos] = static_cast<char>(rng() % 256); break;
        case 1: text.erase(pos, 1 + rng() % 8); break;
        default: text.insert(pos, std::string(1 + rng() % 3, "[]{}:,-#\"'&*!|>\n 0.9e"[rng() % 22])); break;
      }
    }
    try {
      ParseWorld(text, "fuzz.yaml", dir.path());
      ++loaded;
    } catch (const WorldError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("fuzz.yaml", 0), 0u) << e.what();
    }
  }
  EXPECT_LT(loaded, 400) << "mutations should break at least some files";
}

TEST(WorldIoTest, DeepNestingIsAnErrorNotAStackOverflow) {
  const std::string text = "format: enavi-world/1\nobjects: " + std::string(100000, '[');
  EXPECT_THROW(ParseWorld(text, "deep.yaml", "."), WorldError);
}

}  // namespace
}  // namespace enavi::worlds
