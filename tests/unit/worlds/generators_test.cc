#include "worlds/generators.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "tests/unit/worlds/test_util.h"
#include "worlds/mesh.h"
#include "worlds/primitives.h"
#include "worlds/validate.h"
#include "worlds/world_io.h"

// One contract every generator passes (STYLE.md: contract tests for pluggable parts), plus
// per-scenario expectations and parameter handling.

namespace enavi::worlds {
namespace {

const std::filesystem::path kGoldenDir = std::filesystem::path(ENAVI_SOURCE_DIR) / "tests/unit/worlds/golden";

class GeneratorContractTest : public ::testing::TestWithParam<std::string> {};

TEST_P(GeneratorContractTest, GeneratesValidWorldsForSeveralSeeds) {
  for (std::uint64_t seed : {1u, 2u, 3u, 17u}) {
    const World w = Generate(GetParam(), seed);
    const ValidationResult v = ValidateWorld(w);
    EXPECT_TRUE(v.ok) << GetParam() << " seed " << seed << ": " << v.field << ": " << v.reason;
    EXPECT_EQ(w.metadata.scenario, GetParam());
    EXPECT_EQ(w.metadata.seed, seed);
    EXPECT_EQ(w.metadata.generator_version, kGeneratorVersion);
    EXPECT_EQ(w.metadata.name, GetParam() + "-seed" + std::to_string(seed));
  }
}

TEST_P(GeneratorContractTest, StartGoalDistanceIsThePapersFlightPath) {
  const GeneratorInfo* info = FindGenerator(GetParam());
  ASSERT_NE(info, nullptr);
  double expected = info->paper_path_length;
  if (expected == 0.0) expected = info->params[0].default_value;  // forest/empty: the length parameter
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const World w = Generate(GetParam(), seed);
    const double d = (w.goal - w.start).norm();
    EXPECT_NEAR(d, expected, 0.15 * expected) << GetParam() << " seed " << seed;
  }
}

TEST_P(GeneratorContractTest, StartAndGoalFlyAtTheGeneratorsAltitudeAboveTheGround) {
  const GeneratorInfo* info = FindGenerator(GetParam());
  ASSERT_NE(info, nullptr);
  const World w = Generate(GetParam(), 4);
  // Ground plane or, without one, the top of the floor/terrain right below.
  auto ground_below = [&](const Eigen::Vector3d& p) {
    double top = w.ground.enabled ? w.ground.z : -1e9;
    for (const auto& o : w.objects) {
      const Eigen::AlignedBox3d b = ObjectBounds(o);
      if (b.max().z() <= p.z() && b.min().x() <= p.x() && p.x() <= b.max().x() && b.min().y() <= p.y() &&
          p.y() <= b.max().y()) {
        top = std::max(top, b.max().z());
      }
    }
    return top;
  };
  EXPECT_NEAR(w.start.z() - ground_below(w.start), info->flight_altitude, 1e-9);
  EXPECT_NEAR(w.goal.z() - ground_below(w.goal), info->flight_altitude, 1e-9);
  EXPECT_LE(w.bounds.sizes().z(), 10.0) << "flight volumes stay low";
}

TEST_P(GeneratorContractTest, SameInputsGiveTheSameBytes) {
  const std::string a = WorldToYaml(Generate(GetParam(), 7));
  const std::string b = WorldToYaml(Generate(GetParam(), 7));
  EXPECT_EQ(a, b);
  if (GetParam() != "empty") {
    // Another seed, another world (compared without the metadata, which names the seed).
    World w7 = Generate(GetParam(), 7), w8 = Generate(GetParam(), 8);
    w8.metadata = w7.metadata;
    EXPECT_NE(WorldToYaml(w7), WorldToYaml(w8)) << "seeds 7 and 8 gave the same " << GetParam() << " world";
  }
}

TEST_P(GeneratorContractTest, FileRoundTripIsExact) {
  const World w = Generate(GetParam(), 5);
  const std::string text = WorldToYaml(w);
  const World back = ParseWorld(text, GetParam() + ".yaml", ".");
  EXPECT_EQ(WorldToYaml(back), text);
  EXPECT_EQ(back.objects.size(), w.objects.size());
  EXPECT_EQ(back.start, w.start) << "the generator must quantise to the file precision";
}

TEST_P(GeneratorContractTest, MatchesTheGoldenFile) {
  // Golden files pin the exact bytes for seed 1 (any machine, any compiler). After an intended
  // generator change: bump kGeneratorVersion and regenerate with ENAVI_UPDATE_GOLDEN=1.
  const std::string text = WorldToYaml(Generate(GetParam(), 1));
  const auto path = kGoldenDir / (GetParam() + "-seed1.yaml");
  if (std::getenv("ENAVI_UPDATE_GOLDEN") != nullptr) {
    std::ofstream(path, std::ios::binary) << text;
  }
  ASSERT_TRUE(std::filesystem::exists(path)) << path;
  EXPECT_EQ(text, testing::ReadFile(path)) << "generator output changed for " << GetParam() << " seed 1";
}

TEST_P(GeneratorContractTest, MeshIsBoundedAndWithinTheTriangleBudget) {
  const World w = Generate(GetParam(), 2);
  const TriangleMesh m = BuildWorldMesh(w);
  EXPECT_GT(m.triangle_count(), 0u);
  EXPECT_LT(m.triangle_count(), 100'000u) << "scenes should stay cheap to ray-cast";
  for (const auto& o : w.objects) {
    const Eigen::AlignedBox3d b = ObjectBounds(o);
    EXPECT_GE(b.max().x(), w.bounds.min().x() - 1e-9);
    EXPECT_LE(b.min().x(), w.bounds.max().x() + 1e-9);
  }
}

// Every registered generator, read from the registry: a new one passes the contract (and needs
// its golden file) without being listed here.
std::vector<std::string> RegisteredIds() {
  std::vector<std::string> ids;
  for (const GeneratorInfo& g : Generators()) ids.push_back(g.id);
  return ids;
}

// A scenario id as a test name (letters, digits and '_' only).
std::string TestName(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = info.param;
  for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return name;
}

INSTANTIATE_TEST_SUITE_P(AllScenarios, GeneratorContractTest, ::testing::ValuesIn(RegisteredIds()), TestName);

class PaperScenarioTest : public ::testing::TestWithParam<std::string> {};

TEST_P(PaperScenarioTest, StraightLineIsBlockedSoTheFlightMustSteer) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const World w = Generate(GetParam(), seed);
    const ObstacleField f(w, /*include_ground=*/false);
    EXPECT_LT(f.SegmentClearance(w.start, w.goal), 0.3) << GetParam() << " seed " << seed;
  }
}

// The generators after the paper's scenarios (those with its path length).
std::vector<std::string> PaperIds() {
  std::vector<std::string> ids;
  for (const GeneratorInfo& g : Generators())
    if (g.paper_path_length > 0) ids.push_back(g.id);
  return ids;
}

INSTANTIATE_TEST_SUITE_P(PaperScenarios, PaperScenarioTest, ::testing::ValuesIn(PaperIds()),
                         [](const auto& info) { return info.param; });

TEST(GeneratorsTest, EveryGeneratorIsListedOnceAndFoundByItsId) {
  std::set<std::string> ids;
  for (const auto& g : Generators()) {
    EXPECT_TRUE(ids.insert(g.id).second) << g.id;
    EXPECT_EQ(FindGenerator(g.id), &g);
    EXPECT_EQ(ScenarioOf(g.id), g.id);
  }
  EXPECT_EQ(FindGenerator("s9"), nullptr);
  EXPECT_EQ(ScenarioOf("s9"), "custom");
  EXPECT_EQ(ScenarioOf("/data/worlds/hall.yaml"), "custom");
}

TEST(GeneratorsTest, ScenarioFlavours) {
  // s3 is indoors: no ground plane, a ceiling above the start; s5 has terrain lower than the
  // ground (the river channel) and no ground plane.
  const World hall = Generate("s3", 1);
  EXPECT_FALSE(hall.ground.enabled);
  const ObstacleField hall_field(hall);
  EXPECT_LT(hall_field.SegmentClearance(hall.start, hall.start + Eigen::Vector3d(0, 0, 5)), 0.0)
      << "a ceiling above the start";
  const World village = Generate("s5", 1);
  EXPECT_FALSE(village.ground.enabled);
  double lowest_top = 1e9;
  for (const auto& o : village.objects) lowest_top = std::min(lowest_top, ObjectBounds(o).max().z());
  EXPECT_LE(lowest_top, -1.0) << "the river bed lies below the banks";
  // s4's buildings are of similar height, s1's vary.
  auto height_spread = [](const World& w) {
    double lo = 1e9, hi = -1e9;
    for (const auto& o : w.objects) {
      if (const auto* b = std::get_if<Box>(&o); b != nullptr && b->size.z() > 8.0) {
        lo = std::min(lo, b->size.z());
        hi = std::max(hi, b->size.z());
      }
    }
    return hi - lo;
  };
  EXPECT_LE(height_spread(Generate("s4", 1)), 3.0);
  EXPECT_GE(height_spread(Generate("s1", 1)), 5.0);
}

// canyon: every street 6-10 m wide, buildings 3-48 m with some below the flight altitude (to fly
// over) and most far above it, the straight line blocked, so the route along the streets turns.
TEST(GeneratorsTest, CanyonIsStreetsBetweenBuildingsOfMixedHeights) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const World w = Generate("canyon", seed);
    int low = 0, tall = 0;
    std::vector<Eigen::AlignedBox3d> boxes;
    for (const auto& o : w.objects) {
      const auto* b = std::get_if<Box>(&o);
      ASSERT_NE(b, nullptr) << "canyon is made of boxes";
      EXPECT_GE(b->size.z(), 3.0 - 1e-9);
      EXPECT_LE(b->size.z(), 48.0 + 1e-9);
      low += b->size.z() < w.start.z();
      tall += b->size.z() > 20.0;
      boxes.push_back(ObjectBounds(o));
    }
    EXPECT_GT(low, 0) << "seed " << seed << ": some roofs below the flight altitude";
    EXPECT_GT(tall, 0) << "seed " << seed << ": some towers";
    // Two buildings facing each other with nothing in between either touch (one block, up to
    // the file precision) or stand across a street of 6-10 m, widened by setbacks of up to
    // 0.8 m on either side.
    auto overlap = [](double lo0, double hi0, double lo1, double hi1) { return std::min(hi0, hi1) - std::max(lo0, lo1); };
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      for (std::size_t j = 0; j < boxes.size(); ++j) {
        for (int a = 0; a < 2; ++a) {
          const int o = 1 - a;
          const double lo = boxes[i].max()[a], hi = boxes[j].min()[a];
          const double o_lo = std::max(boxes[i].min()[o], boxes[j].min()[o]);
          const double o_hi = std::min(boxes[i].max()[o], boxes[j].max()[o]);
          if (i == j || hi < lo || o_hi - o_lo <= 0.01) continue;
          const bool between = std::any_of(boxes.begin(), boxes.end(), [&](const Eigen::AlignedBox3d& k) {
            return overlap(k.min()[a], k.max()[a], lo, hi) > 0.0 && overlap(k.min()[o], k.max()[o], o_lo, o_hi) > 0.0;
          });
          if (between) continue;
          const double street = hi - lo;
          EXPECT_TRUE(street < 0.001 || (street >= 6.0 - 1e-9 && street <= 11.6 + 1e-9))
              << "seed " << seed << ": " << street << " m between buildings " << i << " and " << j;
        }
      }
    }
    const ObstacleField field(w, /*include_ground=*/false);
    EXPECT_LT(field.SegmentClearance(w.start, w.goal), 0.3) << "seed " << seed;
    EXPECT_GE(field.Distance(w.start), 2.5) << "seed " << seed << ": the start lies in a street";
    EXPECT_GE(field.Distance(w.goal), 2.5) << "seed " << seed << ": the goal lies in a street";
  }
}

TEST(GeneratorsTest, ParametersAreCheckedByNameAndRange) {
  auto error = [](const std::string& id, const std::map<std::string, std::string>& params) -> std::string {
    try {
      Generate(id, 1, params);
    } catch (const WorldError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error("forest", {{"density", "20"}}), "forest: params.density: must be in [0.0, 10.0] (got 20)");
  EXPECT_EQ(error("forest", {{"density", "lots"}}),
            "forest: params.density: not a number (got 'lots'; allowed range [0.0, 10.0])");
  EXPECT_EQ(error("s1", {{"density", "2"}}), "s1: params.density: unknown parameter (allowed: length)");
  EXPECT_EQ(error("s3", {{"length", "100"}}), "s3: params.length: must be in [8.0, 60.0] (got 100)");
  EXPECT_EQ(error("s7", {}).rfind("scenario: unknown scenario 's7' (known: s1, s2, s3, s4, s5, canyon, forest, empty, park-people, street-traffic)", 0),
            0u);
}

TEST(GeneratorsTest, ParametersShapeTheWorldAndAreRecorded) {
  const World sparse = Generate("forest", 3, {{"density", "1"}});
  const World dense = Generate("forest", 3, {{"density", "4"}});
  EXPECT_LT(sparse.objects.size(), dense.objects.size());
  EXPECT_TRUE(Generate("forest", 3, {{"density", "0"}}).objects.empty());
  EXPECT_EQ(dense.metadata.params.at("density"), "4.0");
  EXPECT_EQ(dense.metadata.params.at("length"), "40.0");
  const World long_city = Generate("s1", 2, {{"length", "80"}});
  EXPECT_NEAR((long_city.goal - long_city.start).norm(), 80.0, 0.15 * 80.0);
  // "2" and "2.0" are the same parameter value, so the same file.
  EXPECT_EQ(WorldToYaml(Generate("forest", 1, {{"density", "2"}})),
            WorldToYaml(Generate("forest", 1, {{"density", "2.0"}})));
}

}  // namespace
}  // namespace enavi::worlds
