#include "api/job_spec.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace enavi::api {
namespace {

namespace fs = std::filesystem;

// A scratch allowed root with a couple of world files in it.
class JobSpecTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("job_spec_test-" + std::to_string(getpid()) + "-" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(root_ / "worlds");
    std::ofstream(root_ / "worlds/hall.yaml") << "name: hall\n";
    std::ofstream(root_ / "worlds/yard.obj") << "v 0 0 0\n";
    options_.allowed_roots = {root_};
    // A catalog of the registry's shape: one common tunable, one of E-Navi's own.
    const TunableRange v_max{"planner.v_max", 0.2, 10.0, false};
    options_.catalog.methods = {{"baseline", "", {v_max, {"ego.emergency_stop", 0, 1, true}}},
                                {"fixed", "", {v_max}},
                                {"enavi", "", {v_max, {"strategy.f_adapt", 1.0, 30.0, false}}}};
    options_.catalog.boards = {"pi4b", "tx2", "nx", "opi5", "x86", "host"};
    options_.catalog.scenarios = {"s1", "s2", "s3", "s4", "s5", "forest", "empty"};
    options_.catalog.clocks = {"virtual", "emulated"};
  }
  void TearDown() override { fs::remove_all(root_); }

  JobSpec Parse(const std::string& yaml) { return ParseJobSpec(yaml, "job.yaml", options_); }

  // The error message of a spec that must be rejected.
  std::string Error(const std::string& yaml) {
    try {
      Parse(yaml);
    } catch (const JobSpecError& e) {
      return e.what();
    }
    ADD_FAILURE() << "spec was accepted:\n" << yaml;
    return "";
  }

  fs::path root_;
  JobSpecOptions options_;
};

constexpr const char* kMinimal = R"(name: small
boards: [tx2]
scenarios: [s1]
methods: [baseline, enavi]
seeds: 2
)";

TEST_F(JobSpecTest, MinimalSpecParsesWithDefaults) {
  const JobSpec job = Parse(kMinimal);
  EXPECT_EQ(job.name, "small");
  EXPECT_EQ(job.boards, std::vector<std::string>{"tx2"});
  ASSERT_EQ(job.scenarios.size(), 1u);
  EXPECT_EQ(job.scenarios[0].world, "s1");
  EXPECT_EQ(job.seeds, (std::vector<std::uint64_t>{1, 2}));
  EXPECT_EQ(job.clock, "virtual");
  EXPECT_EQ(job.cost, "model");
  EXPECT_EQ(job.MatrixSize(), 4u);
}

TEST_F(JobSpecTest, LabelsAreParsedAndValidated) {
  const JobSpec job = Parse(std::string(kMinimal) + "labels: {branch: main, commit: 1a2b3c, suite: nightly}\n");
  EXPECT_EQ(job.labels, (std::map<std::string, std::string>{{"branch", "main"}, {"commit", "1a2b3c"},
                                                           {"suite", "nightly"}}));
  EXPECT_EQ(Error(std::string(kMinimal) + "labels: {Suite: x}\n"),
            "job.yaml:6: labels.Suite: label keys are lower-case letters, digits and _ . - (starting with a letter or digit)");
  EXPECT_EQ(Error(std::string(kMinimal) + "labels: {suite: \"<b>\"}\n"),
            "job.yaml:6: labels.suite: label values are letters, digits and _ . : / @ + -");
  EXPECT_EQ(Error(std::string(kMinimal) + "labels: {suite: \"\"}\n"),
            "job.yaml:6: labels.suite: label values have 1..128 characters");
  EXPECT_EQ(Error(std::string(kMinimal) + "labels: {" + std::string(64, 'k') + ": v}\n"),
            "job.yaml:6: labels." + std::string(64, 'k') + ": label keys have 1..63 characters");
  EXPECT_EQ(Error(std::string(kMinimal) + "labels: [a, b]\n"), "job.yaml:6: labels: expected a map of name: value");
  EXPECT_EQ(Error(std::string(kMinimal) + "labels: {a: 1, a: 2}\n"), "job.yaml:6: labels.a: duplicate key");
}

TEST_F(JobSpecTest, LabelFiltersParseKeyEqualsValue) {
  EXPECT_EQ(ParseLabelFilter("suite=nightly", "--label"), (std::pair<std::string, std::string>{"suite", "nightly"}));
  EXPECT_EQ(ParseLabelFilter("ref=origin/main@1a2b", "--label").second, "origin/main@1a2b");
  EXPECT_THROW(ParseLabelFilter("k=a=b", "--label"), std::invalid_argument);
  EXPECT_THROW(ParseLabelFilter("suite", "--label"), std::invalid_argument);
  EXPECT_THROW(ParseLabelFilter("suite=a b", "--label"), std::invalid_argument);
}

TEST_F(JobSpecTest, NameDefaultsToFileStem) {
  const JobSpec job = ParseJobSpec("boards: tx2\nscenarios: s1\nmethods: enavi\nseeds: 1\n",
                                   "/x/nightly-tx2.yaml", options_);
  EXPECT_EQ(job.name, "nightly-tx2");
}

TEST_F(JobSpecTest, ExpansionOrderIsBoardsScenariosMethodsSeeds) {
  const JobSpec job = Parse(R"(boards: [tx2, pi4b]
scenarios: [s1, s2]
methods: [baseline, enavi]
seeds: [3, 9]
)");
  const auto episodes = ExpandJob(job);
  ASSERT_EQ(episodes.size(), 16u);
  EXPECT_EQ(episodes[0].board, "tx2");
  EXPECT_EQ(episodes[0].world, "s1");
  EXPECT_EQ(episodes[0].method, "baseline");
  EXPECT_EQ(episodes[0].seed, 3u);
  EXPECT_EQ(episodes[1].seed, 9u) << "seeds vary fastest";
  EXPECT_EQ(episodes[2].method, "enavi") << "then methods";
  EXPECT_EQ(episodes[4].world, "s2") << "then scenarios";
  EXPECT_EQ(episodes[8].board, "pi4b") << "boards vary slowest";
  EXPECT_EQ(episodes[15].board, "pi4b");
  EXPECT_EQ(episodes[15].world, "s2");
  EXPECT_EQ(episodes[15].method, "enavi");
  EXPECT_EQ(episodes[15].seed, 9u);
}

TEST_F(JobSpecTest, ExpansionIsDeterministic) {
  const std::string yaml = std::string(kMinimal) + "overrides: {planner.v_max: 1.5}\n";
  const auto a = ExpandJob(Parse(yaml));
  const auto b = ExpandJob(Parse(yaml));
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(nlohmann::json(a[i]).dump(), nlohmann::json(b[i]).dump()) << "episode " << i;
  }
}

TEST_F(JobSpecTest, EpisodeOverridesApplyToMatchingEpisodesOnlyLaterWins) {
  const JobSpec job = Parse(R"(boards: [tx2, pi4b]
scenarios: [s1]
methods: [baseline, enavi]
seeds: 2
timeout_s: 60
overrides: {planner.v_max: 3}
episode_overrides:
  - match: {board: tx2, method: enavi}
    timeout_s: 120
    overrides: {planner.v_max: 2}
  - match: {seed: 2, board: tx2, method: [enavi]}
    overrides: {planner.v_max: 1}
)");
  for (const EpisodeSpec& e : ExpandJob(job)) {
    const bool tx2_enavi = e.board == "tx2" && e.method == "enavi";
    EXPECT_EQ(e.timeout_s, tx2_enavi ? 120.0 : 60.0) << e.board << " " << e.method;
    const double expected = !tx2_enavi ? 3.0 : (e.seed == 2 ? 1.0 : 2.0);
    EXPECT_EQ(e.overrides.at("planner.v_max"), expected) << e.board << " " << e.method << " " << e.seed;
  }
}

TEST_F(JobSpecTest, DilationIsANumberOrAutoForTheSmallestThatFitsWhenTheEpisodeStarts) {
  const JobSpec job = Parse(R"(boards: [tx2, pi4b]
scenarios: [s1]
methods: [baseline]
seeds: 1
clock: emulated
dilation: auto
episode_overrides:
  - match: {board: pi4b}
    dilation: "2.5"
)");
  EXPECT_EQ(job.dilation, kAutoDilation);
  for (const EpisodeSpec& e : ExpandJob(job)) EXPECT_EQ(e.dilation, e.board == "pi4b" ? 2.5 : kAutoDilation) << e.board;
  EXPECT_EQ(Parse(std::string(kMinimal) + "dilation: 3\n").dilation, 3.0);
  EXPECT_EQ(Parse(kMinimal).dilation, 1.0) << "the default stays 1: a stored spec means what it meant";
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: enavi\nseeds: 1\ndilation: sometimes\n"),
            "job.yaml:5: dilation: expected wall seconds per sim second in [0.01, 100] or auto (got sometimes)");
}

TEST_F(JobSpecTest, AnEmulatedJobSaysWhatItsWorkersDoWithTheHostsSpeedProbe) {
  const JobSpec job = Parse(std::string(kMinimal) + "clock: emulated\nspeed_probe: use\n");
  for (const EpisodeSpec& e : ExpandJob(job)) {
    EXPECT_EQ(e.speed_probe, "use");
    const nlohmann::json j = e;
    EXPECT_EQ(j.at("speed_probe"), "use");
    EXPECT_EQ(j.get<EpisodeSpec>().speed_probe, "use") << "the worker's spec file carries it";
  }
  for (const EpisodeSpec& e : ExpandJob(Parse(std::string(kMinimal) + "clock: emulated\n"))) {
    EXPECT_EQ(e.speed_probe, "check");
    EXPECT_FALSE(nlohmann::json(e).contains("speed_probe")) << "the default is not written: specs stay as they were";
  }
  EXPECT_EQ(Error(std::string(kMinimal) + "clock: emulated\nspeed_probe: sometimes\n"),
            "job.yaml:7: speed_probe: unknown speed probe mode 'sometimes' (known: check, use, off)");
  EXPECT_EQ(Error(std::string(kMinimal) + "speed_probe: off\n"),
            "job.yaml:6: speed_probe: the emulated clock's (this job's clock is virtual)");
}

TEST_F(JobSpecTest, WindAndOdometryNoiseReachEveryEpisodeAndBadValuesNameTheirField) {
  const JobSpec job = Parse(std::string(kMinimal) + R"(wind:
  speed_mps: 4
  direction_deg: 90
  turbulence: moderate
  gust: {speed_mps: 6, start_s: 10, rise_s: 1.5, hold_s: 2}
odometry_noise: typical
)");
  for (const EpisodeSpec& e : ExpandJob(job)) {
    EXPECT_EQ(e.wind.speed_mps, 4.0);
    EXPECT_EQ(e.wind.turbulence, "moderate");
    EXPECT_EQ(e.wind.gust.rise_s, 1.5);
    EXPECT_EQ(e.odometry_noise, "typical");
    const nlohmann::json j = e;
    EXPECT_EQ(j.get<EpisodeSpec>().wind, e.wind) << "the worker's spec file carries it";
    EXPECT_EQ(j.get<EpisodeSpec>().odometry_noise, "typical");
  }
  for (const EpisodeSpec& e : ExpandJob(Parse(kMinimal))) {
    const nlohmann::json j = e;
    EXPECT_FALSE(j.contains("wind") || j.contains("odometry_noise")) << "still air is not written: specs stay as they were";
  }
  EXPECT_EQ(Error(std::string(kMinimal) + "wind: {turbulence: stormy}\n"),
            "job.yaml:6: wind.turbulence: unknown turbulence level 'stormy' (known: none, light, moderate, severe)");
  EXPECT_EQ(Error(std::string(kMinimal) + "wind:\n  speed_mps: 41\n").rfind("job.yaml:7: wind.speed_mps:", 0), 0u);
  EXPECT_EQ(Error(std::string(kMinimal) + "wind: {gust: {rise: 1}}\n").rfind("job.yaml:6: wind.gust", 0), 0u)
      << Error(std::string(kMinimal) + "wind: {gust: {rise: 1}}\n");
  EXPECT_EQ(Error(std::string(kMinimal) + "odometry_noise: awful\n"),
            "job.yaml:6: odometry_noise: unknown odometry noise preset 'awful' (known: none, good, typical, poor)");
}

TEST_F(JobSpecTest, WorldFilesResolveUnderTheAllowedRoot) {
  const JobSpec job = Parse(R"(boards: tx2
methods: enavi
seeds: 1
scenarios:
  - worlds/hall.yaml
  - {world: worlds/yard.obj, start: [0, 0, 1], goal: [30, 0, 1], params: {k: v}}
)");
  ASSERT_EQ(job.scenarios.size(), 2u);
  EXPECT_EQ(job.scenarios[0].world, fs::weakly_canonical(root_ / "worlds/hall.yaml").string());
  const auto episodes = ExpandJob(job);
  ASSERT_TRUE(episodes[1].start.has_value());
  EXPECT_EQ((*episodes[1].goal)[0], 30.0);
  EXPECT_EQ(episodes[1].world_params.at("k"), "v");
}

// ---- every bad input names file, line and field ----

TEST_F(JobSpecTest, UnknownBoardNamesLineAndField) {
  EXPECT_EQ(Error("boards: [tx2, rpi9]\nscenarios: [s1]\nmethods: [enavi]\nseeds: 1\n"),
            "job.yaml:1: boards: unknown board 'rpi9' (known: pi4b, tx2, nx, opi5, x86, host)");
}

TEST_F(JobSpecTest, UnknownMethodScenarioClockAreRejected) {
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: [fast]\nseeds: 1\n")
                .rfind("job.yaml:3: methods: unknown method 'fast'", 0),
            0u);
  EXPECT_EQ(Error("boards: tx2\nscenarios: [s1, moon]\nmethods: enavi\nseeds: 1\n")
                .rfind("job.yaml:2: scenarios: unknown scenario 'moon'", 0),
            0u);
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: enavi\nseeds: 1\nclock: wall\n")
                .rfind("job.yaml:5: clock: unknown clock 'wall'", 0),
            0u);
}

TEST_F(JobSpecTest, NegativeAndAbsurdSeedCountsAreRejected) {
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: enavi\nseeds: -3\n"),
            "job.yaml:4: seeds: count -3 outside [1, 1000]");
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: enavi\nseeds: 50000\n"),
            "job.yaml:4: seeds: count 50000 outside [1, 1000]");
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: enavi\nseeds: 2.5\n"),
            "job.yaml:4: seeds: expected an integer (got 2.5)");
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: enavi\nseeds: [1, 1]\n"),
            "job.yaml:4: seeds: seed 1 listed twice");
}

TEST_F(JobSpecTest, MatrixAboveTheLimitIsRejected) {
  // 6 boards x 7 scenarios x 2 methods x 200 seeds = 16800 > 10000.
  const std::string e = Error(R"(boards: [pi4b, tx2, nx, opi5, x86, host]
scenarios: [s1, s2, s3, s4, s5, forest, empty]
methods: [baseline, enavi]
seeds: 200
)");
  EXPECT_EQ(e, "job.yaml:4: matrix: 6 boards x 7 scenarios x 2 methods x 200 seeds = 16800 "
               "episodes, above the limit 10000");
}

TEST_F(JobSpecTest, PathsOutsideTheAllowedRootsAreRejected) {
  const std::string e = Error("boards: tx2\nmethods: enavi\nseeds: 1\nscenarios: [../../etc/x.yaml]\n");
  EXPECT_EQ(e.rfind("job.yaml:4: scenarios: '../../etc/x.yaml' is outside the allowed roots", 0), 0u)
      << e;
  const std::string abs = Error("boards: tx2\nmethods: enavi\nseeds: 1\nscenarios: [/etc/hosts.yaml]\n");
  EXPECT_NE(abs.find("outside the allowed roots"), std::string::npos) << abs;
  const std::string missing =
      Error("boards: tx2\nmethods: enavi\nseeds: 1\nscenarios: [worlds/none.yaml]\n");
  EXPECT_EQ(missing, "job.yaml:4: scenarios: 'worlds/none.yaml': no such file");
}

TEST_F(JobSpecTest, ObjWorldWithoutStartAndGoalIsRejected) {
  EXPECT_EQ(Error("boards: tx2\nmethods: enavi\nseeds: 1\nscenarios: [worlds/yard.obj]\n"),
            "job.yaml:4: scenarios: 'worlds/yard.obj' is a mesh or SDF world: give start and goal");
}

TEST_F(JobSpecTest, UnknownKeysAreRejectedWithTheirLine) {
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: enavi\nseeds: 1\nseed: 4\n")
                .rfind("job.yaml:5: seed: unknown key (allowed: name, boards,", 0),
            0u);
  EXPECT_EQ(Error(R"(boards: tx2
scenarios: s1
methods: enavi
seeds: 1
episode_overrides:
  - match: {boards: tx2}
)")
                .rfind("job.yaml:6: episode_overrides[0].match.boards: unknown key", 0),
            0u);
}

TEST_F(JobSpecTest, MissingRequiredFieldAndMalformedYamlAreRejected) {
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: enavi\n"),
            "job.yaml:1: seeds: missing (required)");
  EXPECT_EQ(Error("boards: [tx2\nscenarios: s1\n").rfind("job.yaml:", 0), 0u);
  EXPECT_NE(Error("boards: [tx2\nscenarios: s1\n").find(": yaml: "), std::string::npos);
  EXPECT_EQ(Error("- just\n- a list\n"), "job.yaml:1: job: expected a YAML map of name, boards, scenarios, ...");
}

TEST_F(JobSpecTest, OutOfRangeNumbersNameTheRange) {
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: enavi\nseeds: 1\ntimeout_s: -5\n"),
            "job.yaml:5: timeout_s: must be >= 0.0 (got -5)");
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: enavi\nseeds: 1\ndilation: .inf\n"),
            "job.yaml:5: dilation: expected a finite number (got .inf)");
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: enavi\nseeds: 1\ndilation: 500\n"),
            "job.yaml:5: dilation: must be <= 100.0 (got 500)");
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: enavi\nseeds: 1\noverrides: {F_PER: 2}\n"),
            "job.yaml:5: overrides.F_PER: tunable names are lower_case identifiers");
}

TEST_F(JobSpecTest, DuplicatesInListsAreRejected) {
  EXPECT_EQ(Error("boards: [tx2, tx2]\nscenarios: s1\nmethods: enavi\nseeds: 1\n"),
            "job.yaml:1: boards: 'tx2' listed twice");
}

TEST_F(JobSpecTest, LoadJobSpecNamesTheFile) {
  const fs::path file = root_ / "bad.yaml";
  std::ofstream(file) << "boards: [tx2]\nscenarios: [s9]\nmethods: [enavi]\nseeds: 1\n";
  try {
    LoadJobSpec(file, options_);
    FAIL() << "accepted";
  } catch (const JobSpecError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(file.string() + ":2: scenarios: unknown scenario 's9'", 0), 0u)
        << e.what();
  }
  EXPECT_THROW(LoadJobSpec(root_ / "absent.yaml", options_), std::invalid_argument);
}

TEST_F(JobSpecTest, OverridesAreCheckedAgainstEveryMethodTheyApplyTo) {
  const std::string head = "boards: tx2\nscenarios: s1\nmethods: [baseline, enavi]\nseeds: 1\n";
  // A tunable E-Navi has and the baseline does not: refused for the whole job, with the line.
  const std::string e = Error(head + "overrides: {strategy.f_adapt: 10}\n");
  EXPECT_EQ(e.rfind("job.yaml:5: overrides.strategy.f_adapt: not a tunable of method baseline (known: ", 0), 0u) << e;
  // ... but fine where the override is narrowed to E-Navi.
  const JobSpec job = Parse(head + "episode_overrides:\n  - match: {method: enavi}\n    overrides: {strategy.f_adapt: 10}\n");
  EXPECT_EQ(job.episode_overrides.at(0).overrides.at("strategy.f_adapt"), 10.0);
  // Out of range, and not an integer, name the method and the range.
  EXPECT_EQ(Error(head + "overrides: {planner.v_max: 99}\n"),
            "job.yaml:5: overrides.planner.v_max: method baseline: 99 is outside [0.2, 10]");
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: baseline\nseeds: 1\noverrides: {ego.emergency_stop: 0.5}\n"),
            "job.yaml:5: overrides.ego.emergency_stop: method baseline: 0.5 is outside [0, 1] or not an integer");
  EXPECT_EQ(Error(head + "overrides: {f_per_max: 20}\n").rfind("job.yaml:5: overrides.f_per_max: not a tunable", 0), 0u);
}

TEST_F(JobSpecTest, UncheckedPrefixesPassForOtherEpisodeCommands) {
  options_.catalog.unchecked_prefixes = {"fake."};
  const JobSpec job = Parse("boards: tx2\nscenarios: s1\nmethods: fixed\nseeds: 1\noverrides: {fake.hang: 1}\n");
  EXPECT_EQ(job.overrides.at("fake.hang"), 1.0);
}

TEST_F(JobSpecTest, MethodsComeFromTheCatalog) {
  EXPECT_EQ(Error("boards: tx2\nscenarios: s1\nmethods: rrt\nseeds: 1\n"),
            "job.yaml:3: methods: unknown method 'rrt' (known: baseline, fixed, enavi)");
  options_.catalog.methods.clear();
  EXPECT_THROW(Parse("boards: tx2\nscenarios: s1\nmethods: fixed\nseeds: 1\n"), std::logic_error);
}

}  // namespace
}  // namespace enavi::api
