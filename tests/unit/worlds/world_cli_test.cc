// Runs the built `enavi` binary: `enavi world gen|check|show`, their exit codes (0 ok, 2 bad
// input) and what they print.
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "server/report/canvas.h"
#include "tests/unit/worlds/test_util.h"

namespace enavi::worlds {
namespace {

struct CliRun {
  int code = -1;
  std::string out, err;
};

CliRun Enavi(const testing::TempDir& dir, const std::string& args) {
  const auto out = dir.path() / "stdout.txt", err = dir.path() / "stderr.txt";
  const std::string cmd = std::string(ENAVI_BINARY_DIR) + "/bin/enavi " + args + " >" + out.string() + " 2>" +
                          err.string();
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = testing::ReadFile(out);
  r.err = testing::ReadFile(err);
  return r;
}

TEST(WorldCliTest, GenWritesTheSameFileTwice) {
  testing::TempDir dir;
  const auto a = dir.path() / "a.yaml", b = dir.path() / "b.yaml";
  CliRun r = Enavi(dir, "world gen --scenario forest --seed 3 --param density=2 --out " + a.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("forest-seed3 (forest)"), std::string::npos) << r.out;
  r = Enavi(dir, "world gen --scenario forest --seed 3 --param density=2 --out " + b.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(testing::ReadFile(a), testing::ReadFile(b));
}

TEST(WorldCliTest, GenRefusesBadInputWithExitCodeTwo) {
  testing::TempDir dir;
  const auto out = (dir.path() / "x.yaml").string();
  CliRun r = Enavi(dir, "world gen --scenario s9 --out " + out);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("scenario: unknown scenario 's9'"), std::string::npos) << r.err;
  r = Enavi(dir, "world gen --scenario forest --param density=99 --out " + out);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("forest: params.density: must be in [0.0, 10.0] (got 99)"), std::string::npos) << r.err;
  r = Enavi(dir, "world gen --scenario s1 --param length --out " + out);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--param: expected name=value"), std::string::npos) << r.err;
  r = Enavi(dir, "world gen --scenario forest --param length=5 --param length=6 --out " + out);
  EXPECT_EQ(r.code, 2) << "a name given twice, as in enavi fly";
  EXPECT_NE(r.err.find("--param: 'length' given twice"), std::string::npos) << r.err;
  r = Enavi(dir, "world gen --scenario s1 --bogus --out " + out);
  EXPECT_EQ(r.code, 2) << "unknown flag";
  r = Enavi(dir, "world gen --out " + out);
  EXPECT_EQ(r.code, 2) << "missing --scenario";
  EXPECT_FALSE(std::filesystem::exists(out)) << "bad input must change nothing";
}

TEST(WorldCliTest, CheckAcceptsAGoodFileAndPrintsOneLine) {
  testing::TempDir dir;
  const auto w = dir.path() / "w.yaml";
  ASSERT_EQ(Enavi(dir, "world gen --scenario s3 --seed 2 --out " + w.string()).code, 0);
  const CliRun r = Enavi(dir, "world check " + w.string());
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.rfind(w.string() + ": ok: s3-seed2 (s3), ", 0), 0u) << r.out;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
}

TEST(WorldCliTest, CheckPrintsFileLineFieldReasonOnStderr) {
  testing::TempDir dir;
  const auto w = dir.Write("bad.yaml",
                           "format: enavi-world/1\n"
                           "bounds: {min: [0, 0, 0], max: [10, 10, 4]}\n"
                           "start: [1, 1, 1.5]\n"
                           "goal: [9, 9, 1.5]\n"
                           "objects:\n"
                           "  - box: {center: [5, 5, 1], size: [1, -1, 2]}\n");
  const CliRun r = Enavi(dir, "world check " + w.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, w.string() + ":6: objects[0].box.size: must be > 0.0 (got -1)\n");
  EXPECT_EQ(Enavi(dir, "world check " + (dir.path() / "none.yaml").string()).code, 2);
}

TEST(WorldCliTest, CheckTakesStartAndGoalForAnObj) {
  testing::TempDir dir;
  const auto obj = dir.Write("cube.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                                         "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
  CliRun r = Enavi(dir, "world check " + obj.string() + " --start -2,0.5,0.5 --goal 3,0.5,0.5");
  EXPECT_EQ(r.code, 0) << r.err;
  r = Enavi(dir, "world check " + obj.string() + " --start -2,0.5,0.5");
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, obj.string() + ": goal: required for a mesh world (--goal x,y,z)\n");
  r = Enavi(dir, "world check " + obj.string() + " --start -2,0.5 --goal 3,0.5,0.5");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--start: expected x,y,z"), std::string::npos) << r.err;
}

TEST(WorldCliTest, ShowDrawsAPngOfAScenarioOrAFile) {
  testing::TempDir dir;
  const auto png = dir.path() / "top.png";
  CliRun r = Enavi(dir, "world show s2 --seed 4 --out " + png.string() + " --width 800");
  ASSERT_EQ(r.code, 0) << r.err;
  const report::PngImage img = report::ReadPng(png.string());
  EXPECT_EQ(img.width, 800);
  EXPECT_GE(img.height, 540);

  r = Enavi(dir, "world show s2 --seed 4 --out " + (dir.path() / "no/such/dir/top.png").string());
  EXPECT_EQ(r.code, 1) << "an unwritable output is a failure, not bad input";
  EXPECT_NE(r.err.find("no/such/dir/top.png"), std::string::npos) << r.err;
  r = Enavi(dir, "world show nowhere.yaml --out " + png.string());
  EXPECT_EQ(r.code, 2);
  r = Enavi(dir, "world show s2 --width 5 --out " + png.string());
  EXPECT_EQ(r.code, 2) << "width out of range";
}

TEST(WorldCliTest, EverySubcommandHasHelp) {
  testing::TempDir dir;
  for (const char* sub : {"world", "world gen", "world check", "world show"}) {
    const CliRun r = Enavi(dir, std::string(sub) + " --help");
    EXPECT_EQ(r.code, 0) << sub;
    EXPECT_NE(r.out.find("Usage"), std::string::npos) << sub << ": " << r.out;
  }
}

}  // namespace
}  // namespace enavi::worlds
