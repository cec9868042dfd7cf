// `enavi fly` refuses bad input before flying: exit code 2, one message on stderr naming the flag
// or file, the field and the reason, and no output written. Runs the built binary.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "api/episode.h"
#include "tests/unit/worlds/test_util.h"
#include "workers/emulation/emulated_nav_link.h"
#include "workers/sim/episode_config.h"

namespace enavi::cli {
namespace {

using worlds::testing::ReadFile;
using worlds::testing::TempDir;

struct CliRun {
  int code = -1;
  std::string out, err;
};

CliRun Enavi(const TempDir& dir, const std::string& args) {
  const auto out = dir.path() / "stdout.txt", err = dir.path() / "stderr.txt";
  const std::string cmd =
      std::string(ENAVI_BINARY_DIR) + "/bin/enavi " + args + " >" + out.string() + " 2>" + err.string();
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadFile(out);
  r.err = ReadFile(err);
  return r;
}

CliRun Fly(const TempDir& dir, const std::string& args) { return Enavi(dir, "fly " + args); }
// The worker's child command; a result file unless the test names one.
CliRun Episode(const TempDir& dir, const std::string& args) {
  const bool has_result = args.find("--result-file") != std::string::npos;
  return Enavi(dir, "episode " + args + (has_result ? "" : " --result-file " + (dir.path() / "r.json").string()));
}

bool Has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// Bad input: exit 2, the expected parts in the message, nothing on stdout.
void ExpectRefused(const CliRun& r, std::initializer_list<const char*> parts, const std::string& what) {
  EXPECT_EQ(r.code, 2) << what << "\nstderr: " << r.err;
  for (const char* part : parts) EXPECT_TRUE(Has(r.err, part)) << what << ": no '" << part << "' in: " << r.err;
  EXPECT_EQ(r.out, "") << what;
}

TEST(FlyCliInputTest, UnknownBoardMethodOrWorldIsRefusedWithTheKnownOnes) {
  TempDir dir;
  ExpectRefused(Fly(dir, "--board zz"), {"--board", "zz", "tx2", "pi4b"}, "unknown board");
  ExpectRefused(Fly(dir, "--method rrt"), {"--method", "rrt", "baseline"}, "unknown method");
  ExpectRefused(Fly(dir, "--world s9"), {"world", "'s9'", "s1", "forest", ".yaml"}, "unknown scenario");
  const std::string missing = (dir.path() / "nowhere.yaml").string();
  ExpectRefused(Fly(dir, "--world " + missing), {missing.c_str(), "not found"}, "missing world file");
  ExpectRefused(Fly(dir, "--world forest --param density=99"), {"params.density", "[0.0, 10.0]", "99"},
                "world parameter out of range");
}

TEST(FlyCliInputTest, BadAirOrOdometryIsRefusedNamingTheFlag) {
  TempDir dir;
  ExpectRefused(Fly(dir, "--world empty --turbulence stormy"), {"--turbulence", "stormy", "severe"}, "unknown level");
  ExpectRefused(Fly(dir, "--world empty --wind 41"), {"--wind", "41"}, "wind above the limit");
  ExpectRefused(Fly(dir, "--world empty --wind -1"), {"--wind"}, "negative wind");
  ExpectRefused(Fly(dir, "--world empty --gust-rise 0"), {"--gust-rise", "0"}, "a gust that rises in no time");
  ExpectRefused(Fly(dir, "--world empty --odometry-noise awful"), {"--odometry-noise", "awful", "typical"},
                "unknown odometry preset");
  // The same checks guard eval's flags (its job spec).
  ExpectRefused(Enavi(dir, "eval --turbulence stormy"), {"--turbulence", "stormy"}, "eval: unknown level");
}

TEST(FlyCliInputTest, MalformedStartOrGoalIsRefused) {
  TempDir dir;
  ExpectRefused(Fly(dir, "--world empty --start 1,2"), {"--start", "x,y,z", "'1,2'"}, "two coordinates");
  ExpectRefused(Fly(dir, "--world empty --start 1,2,x"), {"--start", "'1,2,x'"}, "not a number");
  ExpectRefused(Fly(dir, "--world empty --goal '1;2;3'"), {"--goal", "'1;2;3'"}, "wrong separator");
  // One parser for every subcommand (server/cli/cli_values.h): a name given twice is ambiguous.
  ExpectRefused(Fly(dir, "--world forest --param length=5 --param length=6"), {"--param", "'length' given twice"},
                "duplicate --param");
  ExpectRefused(Fly(dir, "--world empty --set planner.v_max=1 --set planner.v_max=2"),
                {"--set", "'planner.v_max' given twice"}, "duplicate --set");
}

TEST(FlyCliInputTest, SetOfAnUnknownTunableListsTheKnownOnes) {
  TempDir dir;
  ExpectRefused(Fly(dir, "--world empty --set planner.vmax=1"),
                {"planner.vmax", "unknown parameter", "planner.v_max", "map.resolution"}, "misspelt tunable");
  ExpectRefused(Fly(dir, "--world empty --set planner.v_max"), {"--set", "name=value"}, "no value");
  ExpectRefused(Fly(dir, "--world empty --set planner.v_max=fast"), {"--set planner.v_max", "'fast'", "not a number"},
                "value not a number");
}

TEST(FlyCliInputTest, SetOutOfRangeNamesTheFieldAndItsRange) {
  TempDir dir;
  ExpectRefused(Fly(dir, "--world empty --set planner.v_max=99"), {"planner.v_max", "99", "outside", "0.2", "10"},
                "above the range");
  ExpectRefused(Fly(dir, "--world empty --set map.resolution=0.01"), {"map.resolution", "0.01", "0.05", "1"},
                "below the range");
  ExpectRefused(Fly(dir, "--world empty --set perception.stride=2.5"), {"perception.stride", "integer"},
                "integer tunable given a fraction");
}

TEST(FlyCliInputTest, ObjWorldNeedsStartAndGoal) {
  TempDir dir;
  const std::string obj = dir.Write("tri.obj", "v 0 0 0\nv 4 0 0\nv 0 4 0\nf 1 2 3\n").string();
  ExpectRefused(Fly(dir, "--world " + obj), {obj.c_str(), "start", "required for a mesh world"}, "no start");
  ExpectRefused(Fly(dir, "--world " + obj + " --start 1,1,1"), {obj.c_str(), "goal", "required for a mesh world"},
                "no goal");
}

TEST(EpisodeCliInputTest, MissingOrCorruptSpecFileIsRefusedNamingTheFile) {
  TempDir dir;
  const std::string missing = (dir.path() / "none.json").string();
  ExpectRefused(Episode(dir, "--spec-file " + missing), {missing.c_str(), "cannot read"}, "missing spec file");

  const std::string truncated = dir.Write("truncated.json", "{\"world\": \"s3\", \"seed\": ").string();
  ExpectRefused(Episode(dir, "--spec-file " + truncated), {truncated.c_str(), "not an episode spec", "parse error"},
                "truncated JSON");
  const std::string wrong_type = dir.Write("type.json", "{\"world\": \"s3\", \"seed\": \"one\"}").string();
  ExpectRefused(Episode(dir, "--spec-file " + wrong_type), {wrong_type.c_str(), "not an episode spec"},
                "seed is a string");
  const std::string board = dir.Write("board.json", "{\"world\": \"s3\", \"board\": \"zz\"}").string();
  ExpectRefused(Episode(dir, "--spec-file " + board), {"board", "'zz'"}, "unknown board in the spec");
}

TEST(EpisodeCliInputTest, SpecFileThatIsNotAnObjectOrHasUnknownFieldsIsRefused) {
  // Either would otherwise fly the default spec (s1 on host) instead of the one meant.
  TempDir dir;
  const std::string array = dir.Write("array.json", "[\"s3\", 1]").string();
  ExpectRefused(Episode(dir, "--spec-file " + array), {array.c_str(), "object"}, "a JSON array");
  const std::string typo = dir.Write("typo.json", "{\"world\": \"s3\", \"bord\": \"tx2\"}").string();
  ExpectRefused(Episode(dir, "--spec-file " + typo), {typo.c_str(), "bord", "unknown field", "board"}, "misspelt field");
}

TEST(TrainCliInputTest, AnUnknownHeadOrAHeadForAPolicyThatHasOneIsRefused) {
  TempDir dir;
  const std::string out = " --out " + (dir.path() / "p.json").string();
  ExpectRefused(Enavi(dir, "train --head wide" + out), {"--head", "wide", "factored"}, "unknown head");
  ExpectRefused(Enavi(dir, "train --head factored --init some.json" + out), {"--head", "--init"},
                "--head with --init");
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "p.json.train")) << "refused before any work";
}

TEST(FlyCliInputTest, NegativeSeedOrTimeoutIsRefused) {
  TempDir dir;
  ExpectRefused(Fly(dir, "--world empty --seed -3"), {"--seed"}, "negative seed");
  ExpectRefused(Fly(dir, "--world empty --timeout -1"), {"--timeout"}, "negative timeout");
  const std::string spec = dir.Write("spec.json", "{\"world\": \"empty\", \"timeout_s\": -1}").string();
  ExpectRefused(Episode(dir, "--spec-file " + spec), {"timeout_s", "-1"}, "negative timeout in a spec file");
}

TEST(FlyCliInputTest, BadInputWritesNoOutput) {
  TempDir dir;
  const auto out = dir.path() / "out";
  const auto result = dir.path() / "result.json";
  ExpectRefused(Fly(dir, "--world empty --set planner.v_max=99 --out " + out.string()), {"planner.v_max"}, "--out");
  EXPECT_FALSE(std::filesystem::exists(out)) << "bad input must not create the output directory";
  const std::string spec = dir.Write("spec.json", "{\"world\": \"empty\", \"overrides\": {\"nope\": 1}}").string();
  ExpectRefused(Episode(dir, "--spec-file " + spec + " --result-file " + result.string()), {"overrides.nope"},
                "--result-file");
  EXPECT_FALSE(std::filesystem::exists(result)) << "bad input must not write a result file";
}

TEST(FlyCliInputTest, HelpExitsZeroAndListsTheFlags) {
  TempDir dir;
  const CliRun r = Fly(dir, "--help");
  EXPECT_EQ(r.code, 0) << r.err;
  for (const char* flag : {"--world", "--seed", "--start", "--goal", "--param", "--board", "--method", "--clock",
                           "--cost", "--timeout", "--set", "--out", "--json"})
    EXPECT_TRUE(Has(r.out, flag)) << flag << " missing from --help:\n" << r.out;
}

// The help texts read the registries: every board, scenario and clock has its line.
TEST(FlyCliInputTest, HelpListsEveryRegisteredBoardScenarioAndClock) {
  TempDir dir;
  const CliRun r = Fly(dir, "--help");
  ASSERT_EQ(r.code, 0) << r.err;
  emulation::RegisterEmulatedLink();  // the clocks enavi's main registers
  const api::Catalog catalog = sim::FarmCatalog();
  ASSERT_EQ(catalog.clocks.size(), 2u);
  for (const auto* names : {&catalog.boards, &catalog.scenarios, &catalog.clocks})
    for (const std::string& name : *names) EXPECT_TRUE(Has(r.out, "    " + name + ": ")) << name << " missing from:\n" << r.out;
}

// `enavi bench raycast` (its core is the enavi::raycast_bench library in bench/sim, outside the simulator's).
TEST(BenchCliTest, RaycastRendersWithBothRenderersAndPrintsJson) {
  TempDir dir;
  const CliRun r = Enavi(dir, "bench raycast --world empty --frames 2 --bullet-frames 1 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(Has(r.out, "\"embree_mrays_per_s_per_core\"")) << r.out;
  EXPECT_TRUE(Has(r.out, "\"bullet_frames\": 1,")) << r.out;
  ExpectRefused(Enavi(dir, "bench raycast --world empty --frames 0"), {"--frames"}, "zero frames");
}

}  // namespace
}  // namespace enavi::cli
