// `enavi eval`'s flags become a job spec, checked and expanded like a submitted one.
#include "server/eval/eval.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

namespace enavi::server {
namespace {

api::JobSpecOptions Options() {
  api::JobSpecOptions o;
  const api::TunableRange v_max{"planner.v_max", 0.2, 10.0, false};
  o.catalog.methods = {{"baseline", "", {v_max, {"ego.occupancy_hz", 1.0, 60.0, false}}},
                       {"enavi", "", {v_max, {"strategy.least_load", 0, 1, true}}}};
  o.catalog.boards = {"tx2"};
  o.catalog.scenarios = {"s1"};
  o.catalog.clocks = {"virtual"};
  return o;
}

// --set NAME=VALUE reaches every method's episodes, METHOD:NAME=VALUE only that method's, and a
// value reads back as the same double.
TEST(EvalJobYamlTest, OverridesReachTheEpisodesTheyName) {
  EvalOptions o;
  o.boards = {"tx2"};
  o.scenarios = {"s1"};
  o.methods = {"baseline", "enavi"};
  o.overrides = {{"planner.v_max", 0.1 + 0.2}};
  o.method_overrides = {{"enavi", {{"strategy.least_load", 1}}}, {"baseline", {{"ego.occupancy_hz", 12.5}}}};
  const std::string yaml = EvalJobYaml(o);
  const std::vector<api::EpisodeSpec> episodes =
      api::ExpandJob(api::ParseJobSpec(yaml, "enavi eval flags", Options()));
  ASSERT_EQ(episodes.size(), 2u) << yaml;
  for (const api::EpisodeSpec& e : episodes) {
    EXPECT_EQ(e.overrides.at("planner.v_max"), 0.1 + 0.2) << yaml;
    if (e.method == "enavi") {
      EXPECT_EQ(e.overrides.at("strategy.least_load"), 1.0);
      EXPECT_EQ(e.overrides.count("ego.occupancy_hz"), 0u);
    } else {
      EXPECT_EQ(e.overrides.at("ego.occupancy_hz"), 12.5);
      EXPECT_EQ(e.overrides.count("strategy.least_load"), 0u);
    }
  }
}

// Flag values that YAML would read otherwise (quotes, backslashes, control characters, a
// colon) come back unchanged: the policy path and the labels.
TEST(EvalJobYamlTest, PolicyAndLabelsComeBackAsGiven) {
  const std::filesystem::path root = std::filesystem::temp_directory_path() / ("eval_job_test-" + std::to_string(getpid()));
  std::filesystem::create_directories(root);
  const std::filesystem::path policy = root / "odd \"name\": \\ #1.json";
  std::ofstream(policy) << "{}";
  api::JobSpecOptions options = Options();
  options.allowed_roots = {root};
  EvalOptions o;
  o.methods = {"enavi"};
  o.policy = policy.string();
  o.labels = {{"variant", "enavi:least_load"}, {"branch", "main"}};
  const api::JobSpec job = api::ParseJobSpec(EvalJobYaml(o), "enavi eval flags", options);
  EXPECT_EQ(job.policy, std::filesystem::weakly_canonical(policy).string());
  EXPECT_EQ(job.labels, o.labels);
  o.labels = {{"note", "a\tb"}};
  try {
    api::ParseJobSpec(EvalJobYaml(o), "enavi eval flags", options);
    FAIL() << "a label with a tab was accepted";
  } catch (const api::JobSpecError& e) {
    EXPECT_NE(std::string(e.what()).find("labels.note"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(root);
}

// A tunable one of the methods lacks is refused by the job's check, naming the field.
TEST(EvalJobYamlTest, AnOverrideEveryMethodCannotTakeIsRefusedByName) {
  EvalOptions o;
  o.methods = {"baseline", "enavi"};
  o.overrides = {{"strategy.least_load", 1}};
  try {
    api::ParseJobSpec(EvalJobYaml(o), "enavi eval flags", Options());
    FAIL() << "accepted";
  } catch (const api::JobSpecError& e) {
    EXPECT_NE(std::string(e.what()).find("overrides.strategy.least_load: not a tunable of method baseline"),
              std::string::npos)
        << e.what();
  }
  o.overrides.clear();
  o.method_overrides = {{"enavi", {{"strategy.least_load", 2}}}};
  try {
    api::ParseJobSpec(EvalJobYaml(o), "enavi eval flags", Options());
    FAIL() << "accepted";
  } catch (const api::JobSpecError& e) {
    EXPECT_NE(std::string(e.what()).find("episode_overrides[0].overrides.strategy.least_load"), std::string::npos)
        << e.what();
  }
}

// `enavi eval` reports a bad flag as the flag its user typed, never as a line of the YAML it
// wrote for them ("enavi eval flags:8").
TEST(EvalJobYamlTest, ErrorsNameTheFlagAsTypedNotTheGeneratedYaml) {
  auto refused = [](const EvalOptions& o) {
    try {
      ParseEvalJob(o, EvalJobYaml(o));
    } catch (const api::JobSpecError&) {
      return std::string("a JobSpecError, the YAML's own");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EvalOptions o;
  o.job_spec = Options();
  o.overrides = {{"planner.v_maxx", 1.0}};
  std::string message = refused(o);
  EXPECT_EQ(message.rfind("--set planner.v_maxx: not a tunable of method baseline", 0), 0u) << message;
  EXPECT_EQ(message.find("eval flags"), std::string::npos) << message;
  o.overrides.clear();
  o.method_overrides = {{"enavi", {{"strategy.least_load", 2}}}};
  message = refused(o);
  EXPECT_EQ(message.rfind("--set enavi:strategy.least_load: ", 0), 0u) << message;
  o.method_overrides.clear();
  o.scenarios = {"s1", "s9"};
  message = refused(o);
  EXPECT_EQ(message.rfind("--scenarios s1,s9: ", 0), 0u) << message;
  EXPECT_NE(message.find("'s9'"), std::string::npos) << message;
  o.scenarios = {"s1"};
  o.name = "";
  EXPECT_EQ(refused(o), "--name : 1..128 characters");
  o.name = "before";
  EXPECT_EQ(ParseEvalJob(o, EvalJobYaml(o)).name, "before") << "--name names the job";
}

}  // namespace
}  // namespace enavi::server
