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

}  // namespace
}  // namespace enavi::server
