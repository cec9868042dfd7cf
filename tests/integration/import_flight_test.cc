// Worlds users bring, flown: a mesh world of each format (OBJ in millimetres far from the
// origin, glTF, DAE, STL) and a Gazebo SDF world, each by both methods to its goal; and the
// built `enavi` refusing a malformed file of each format with exit code 2 and the file's name.
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "api/episode.h"
#include "tests/integration/loop_test_util.h"
#include "tests/unit/worlds/import_fixtures.h"
#include "workers/sim/episode.h"

namespace enavi::integration {
namespace {

namespace fx = worlds::testing;

struct Case {
  std::string file;
  api::Vec3 start, goal;
  std::string units;
  bool recenter = false;
  std::vector<std::string> model_path;
};

// The worlds of import_fixtures.h, written to `dir`.
std::vector<Case> WriteWorlds(const TempDir& dir) {
  const worlds::TriangleMesh box = fx::FixtureBox();
  const api::Vec3 s{-2.5, 0, 1.5}, g{2.5, 0, 1.5};
  std::vector<Case> cases;
  // Recentred, the block stands on [-1, 1]^2: fly past it at y = -3.
  cases.push_back({dir.Write("block.obj", fx::ObjMm(box, {991408123.4, 1002345678.9, 45000.0})).string(),
                   {-2.5, -3, 1.5}, {2.5, -3, 1.5}, "mm", true, {}});
  cases.push_back({dir.Write("box.gltf", fx::Gltf(box)).string(), s, g, "", false, {}});
  cases.push_back({dir.Write("box.dae", fx::DaeMmZUp(box)).string(), s, g, "", false, {}});
  cases.push_back({dir.Write("box.stl", fx::StlBinary(box)).string(), s, g, "", false, {}});
  dir.Write("models/pillar/model.config", fx::PillarModelConfig());
  dir.Write("models/pillar/model.sdf", fx::PillarModelSdf());
  dir.Write("models/pillar/meshes/pillar.stl", fx::StlAscii(fx::UnitCube()));
  cases.push_back({dir.Write("yard.world", fx::GazeboWorld()).string(), s, g, "", false,
                   {(dir.path() / "models").string()}});
  return cases;
}

TEST(ImportFlightTest, EveryFormatIsFlownToItsGoalByBothMethods) {
  TempDir dir;
  for (const Case& c : WriteWorlds(dir)) {
    for (const char* method : {"baseline", "enavi"}) {
      api::EpisodeSpec spec = Spec(c.file, 1);
      spec.method = method;
      spec.start = c.start;
      spec.goal = c.goal;
      spec.units = c.units;
      spec.recenter = c.recenter;
      spec.model_path = c.model_path;
      spec.timeout_s = 30;
      const api::EpisodeResult r = sim::RunEpisode(spec);
      EXPECT_TRUE(r.success) << c.file << ": " << Describe(r);
      EXPECT_EQ(r.end_reason, "goal_reached") << c.file << ": " << Describe(r);
      if (c.file.ends_with(".world")) {
        EXPECT_EQ(r.notes.at("world_import"),
                  "SDF: ignored 2 light(s); physics settings; 1 plugin(s); non-static model(s) 'rover'");
      }
    }
  }
}

TEST(ImportFlightTest, TheCliFliesAGazeboWorldFromTheReadme) {
  TempDir dir;
  const Case yard = WriteWorlds(dir).back();
  const CliRun r = Enavi(dir, "fly --world " + yard.file + " --model-path " + yard.model_path[0] +
                                  " --start -2.5,0,1.5 --goal 2.5,0,1.5 --method enavi --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["success"], true) << r.out;
}

TEST(ImportFlightTest, ConvertWritesAWorldFileThatChecksAndFliesTheSame) {
  TempDir dir;
  const Case block = WriteWorlds(dir).front();
  const std::string yaml = (dir.path() / "block.yaml").string();
  const std::string convert = "world convert " + block.file + " --units mm --recenter --start -2.5,-3,1.5 "
                              "--goal 2.5,-3,1.5 --out ";
  CliRun r = Enavi(dir, convert + yaml);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string first = ReadFile(yaml);
  ASSERT_EQ(Enavi(dir, convert + yaml).code, 0);
  EXPECT_EQ(ReadFile(yaml), first) << "convert is deterministic";
  r = Enavi(dir, "world check " + yaml);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("12 triangles"), std::string::npos) << r.out;
  // The converted world flies exactly like the imported one.
  const std::string fly = " --method baseline --json";
  const CliRun from_yaml = Enavi(dir, "fly --world " + yaml + fly);
  const CliRun from_obj =
      Enavi(dir, "fly --world " + block.file + " --units mm --recenter --start -2.5,-3,1.5 --goal 2.5,-3,1.5" + fly);
  ASSERT_EQ(from_yaml.code, 0) << from_yaml.err;
  ASSERT_EQ(from_obj.code, 0) << from_obj.err;
  nlohmann::json a = nlohmann::json::parse(from_yaml.out), b = nlohmann::json::parse(from_obj.out);
  EXPECT_EQ(a["success"], true);
  EXPECT_EQ(a["flight_time_s"], b["flight_time_s"]);
  EXPECT_EQ(a["path_length_m"], b["path_length_m"]);
}

TEST(ImportFlightTest, MalformedFilesOfEachFormatExitTwoNamingTheFile) {
  TempDir dir;
  const worlds::TriangleMesh box = fx::FixtureBox();
  worlds::TriangleMesh far_index = box;
  far_index.triangles[5] = Eigen::Vector3i(0, 1, 99);
  std::string nan_stl = fx::StlBinary(box);
  const float nan = std::nanf("");
  std::memcpy(&nan_stl[84 + 12], &nan, 4);
  const std::vector<std::filesystem::path> bad = {
      dir.Write("truncated.obj", fx::ObjMm(box, {0, 0, 0}).substr(0, 50)),
      dir.Write("index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"),
      dir.Write("nan.obj", "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
      dir.Write("truncated.glb", fx::Glb(box).substr(0, 120)),
      dir.Write("index.gltf", fx::Gltf(far_index)),
      dir.Write("truncated.dae", fx::DaeMmZUp(box).substr(0, 500)),
      dir.Write("index.dae", fx::DaeMmZUp(far_index)),
      dir.Write("nan.stl", nan_stl),
      dir.Write("truncated.ply", fx::PlyAscii(box).substr(0, 120)),
      dir.Write("missing.world", R"(<?xml version="1.0"?>
<sdf version="1.6"><world name="w"><include><uri>model://ground_plane</uri></include>
<include><uri>model://no_such_model</uri></include></world></sdf>
)"),
  };
  for (const auto& file : bad) {
    for (const std::string cmd : {"world check ", "fly --world "}) {
      const CliRun r = Enavi(dir, cmd + file.string() + " --start -2.5,0,1.5 --goal 2.5,0,1.5");
      EXPECT_EQ(r.code, 2) << cmd << file << ": " << r.err;
      EXPECT_NE(r.err.find(file.string() + ":"), std::string::npos) << cmd << file << ": " << r.err;
    }
  }
}

}  // namespace
}  // namespace enavi::integration
