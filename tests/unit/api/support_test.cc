// The shared helpers of api/: the atomic file write, the number formatter and the validated JSON
// reader (through the episode records, its first user).
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "api/atomic_file.h"
#include "api/episode.h"
#include "api/fixed.h"

namespace enavi::api {
namespace {

namespace fs = std::filesystem;

std::string Read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class AtomicFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("enavi_atomic_file_test_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(AtomicFileTest, WritesAndReplacesWholeFiles) {
  const fs::path p = dir_ / "a.json";
  WriteFileAtomic(p, "first\n");
  EXPECT_EQ(Read(p), "first\n");
  WriteFileAtomic(p, std::string("sec\0ond", 7));
  EXPECT_EQ(Read(p), std::string("sec\0ond", 7));
  EXPECT_FALSE(fs::exists(dir_ / "a.json.tmp")) << "the temporary file is renamed away";
}

TEST_F(AtomicFileTest, MissingDirectoryThrowsNamingTheFileAndLeavesNothing) {
  const fs::path p = dir_ / "no_such_dir" / "a.json";
  try {
    WriteFileAtomic(p, "x");
    FAIL() << "expected a throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(p));
}

TEST_F(AtomicFileTest, FailedRenameKeepsTheOldFile) {
  // A directory where the file should go: the rename fails, the old entry stays, no .tmp is left.
  const fs::path p = dir_ / "taken";
  fs::create_directories(p / "inside");
  EXPECT_THROW(WriteFileAtomic(p, "x"), std::runtime_error);
  EXPECT_TRUE(fs::is_directory(p / "inside"));
  EXPECT_FALSE(fs::exists(dir_ / "taken.tmp"));
}

TEST(FixedTest, RoundsToTheGivenDecimals) {
  EXPECT_EQ(Fixed(2.5, 2), "2.50");
  EXPECT_EQ(Fixed(0.125, 2), "0.12") << "round half to even on the exact binary value, as printf";
  EXPECT_EQ(Fixed(-1.0 / 3.0, 3), "-0.333");
  EXPECT_EQ(Fixed(1234.5678, 0), "1235");
  EXPECT_EQ(Fixed(1e-9, 4), "0.0000");
}

// `what` is thrown by reading `json_text` as a T, and the message names `field`.
template <typename T>
void ExpectRefused(const std::string& json_text, const std::string& field, const std::string& reason) {
  try {
    (void)nlohmann::json::parse(json_text).get<T>();
    FAIL() << "accepted " << json_text;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field + ": " + reason), std::string::npos) << e.what();
  }
}

TEST(EpisodeJsonTest, SpecRoundTripsAndAbsentOptionalKeysKeepTheirDefaults) {
  EpisodeSpec spec;
  spec.world = "s3";
  spec.seed = 7;
  spec.start = Vec3{1, 2, 3};
  spec.overrides["planner.v_max"] = 1.5;
  spec.world_params["length"] = "10";
  const EpisodeSpec back = nlohmann::json(spec).get<EpisodeSpec>();
  EXPECT_EQ(nlohmann::json(back), nlohmann::json(spec));
  const EpisodeSpec minimal =
      nlohmann::json::parse(R"({"world": "s3", "board": "tx2", "policy": null})")
          .get<EpisodeSpec>();
  EXPECT_EQ(minimal.seed, 1u);
  EXPECT_EQ(minimal.clock, "virtual");
  EXPECT_EQ(minimal.timeout_s, 0.0);
  EXPECT_FALSE(minimal.start.has_value());
}

TEST(EpisodeJsonTest, BadSpecsNameTheField) {
  const std::string base = R"("world": "s1", "board": "tx2", "method": "enavi")";
  ExpectRefused<EpisodeSpec>("{" + base + R"(, "seed": "one"})", "seed", "expected an integer >= 0");
  ExpectRefused<EpisodeSpec>("{" + base + R"(, "seed": -1})", "seed", "expected an integer >= 0");
  ExpectRefused<EpisodeSpec>("{" + base + R"(, "seed": 1, "start": [1, 2]})", "start", "expected 3 numbers");
  ExpectRefused<EpisodeSpec>("{" + base + R"(, "seed": 1, "overrides": {"a": "x"}})", "overrides.a",
                             "expected a number");
  ExpectRefused<EpisodeSpec>(R"({"world": 3})", "episode spec: world", "expected a string");
  ExpectRefused<EpisodeSpec>(R"([1, 2])", "episode spec: (root)", "expected an object");
}

TEST(EpisodeJsonTest, ResultRoundTripsAndBadResultsNameTheField) {
  EpisodeResult r;
  r.success = true;
  r.end_reason = "goal_reached";
  r.collision_point = Vec3{0.5, 0, 1};
  r.replans_by_trigger["distance"] = 3;
  r.events.push_back({1.5, "replan", "start"});
  r.series.t = {0, 0.1};
  r.series.position = {Vec3{0, 0, 1}, Vec3{0.1, 0, 1}};
  r.series.events = {"", "replan"};
  EXPECT_EQ(nlohmann::json(nlohmann::json(r).get<EpisodeResult>()), nlohmann::json(r));

  ExpectRefused<EpisodeResult>(R"({"end_reason": "timeout"})", "episode result: success", "missing");
  ExpectRefused<EpisodeResult>(R"({"success": true, "end_reason": "x", "replans": 1.5})", "replans",
                               "expected an integer");
  ExpectRefused<EpisodeResult>(R"({"success": true, "end_reason": "x", "events": [{"t": 1, "kind": "a"}]})",
                               "events[0].detail", "missing");
  ExpectRefused<EpisodeResult>(R"({"success": true, "end_reason": "x", "series": {"position": [[1, 2, "z"]]}})",
                               "series.position[0][2]", "expected a number");
}

}  // namespace
}  // namespace enavi::api
