// Collection jobs and explicit episode lists in job specs.
#include <gtest/gtest.h>

#include "api/job_spec.h"

namespace enavi::api {
namespace {

const std::string kHashRef = "sha256:" + std::string(64, 'c');

// A catalog of the registry's shape: E-Navi with its sampling switch.
JobSpecOptions Options() {
  JobSpecOptions o;
  o.catalog.methods = {{"baseline", "", {}},
                       {"enavi", "", {{"strategy.explore", 0, 1, true}, {"strategy.least_load", 0, 1, true}}},
                       {"learned", "", {{"learned.explore", 0, 1, true}}}};
  o.catalog.boards = {"pi4b", "tx2"};
  o.catalog.scenarios = {"s1", "s2", "empty"};
  o.catalog.clocks = {"virtual", "emulated"};
  return o;
}

JobSpec Parse(const std::string& yaml) { return ParseJobSpec(yaml, "job.yaml", Options()); }

std::string Error(const std::string& yaml) {
  try {
    Parse(yaml);
  } catch (const JobSpecError& e) {
    return e.what();
  }
  ADD_FAILURE() << "spec was accepted:\n" << yaml;
  return "";
}

TEST(JobSpecCollectTest, CollectionJobSamplesWithThePolicyByHash) {
  const JobSpec job = Parse("boards: [tx2]\nscenarios: [empty]\nmethods: [enavi]\nseeds: 3\n"
                            "collect: rollouts\nsample: true\npolicy: \"" + kHashRef + "\"\n");
  ASSERT_TRUE(job.collect.has_value());
  EXPECT_TRUE(job.collect->sample);
  const auto episodes = ExpandJob(job);
  ASSERT_EQ(episodes.size(), 3u);
  for (const auto& e : episodes) {
    EXPECT_EQ(e.policy, kHashRef);
    EXPECT_EQ(e.overrides.at("strategy.explore"), 1.0);
  }
}

TEST(JobSpecCollectTest, LearnedCollectionSamplesWithItsOwnSwitch) {
  const JobSpec job = Parse("boards: [tx2]\nscenarios: [empty]\nmethods: [learned]\nseeds: 2\n"
                            "collect: rollouts\nsample: true\npolicy: \"" + kHashRef + "\"\n");
  for (const auto& e : ExpandJob(job)) {
    EXPECT_EQ(e.method, "learned");
    EXPECT_EQ(e.overrides.at("learned.explore"), 1.0);
    EXPECT_FALSE(e.overrides.contains("strategy.explore")) << "not a tunable of learned";
  }
}

TEST(JobSpecCollectTest, ExplicitEpisodeListExpandsInOrder) {
  const JobSpec job = Parse(
      "methods: [enavi]\ncollect: rollouts\npolicy: \"" + kHashRef + "\"\nepisodes:\n"
      "  - {board: tx2, scenario: s2, seed: 104}\n  - {board: pi4b, scenario: empty, seed: 7}\n");
  EXPECT_FALSE(job.collect->sample) << "greedy unless asked";
  const auto episodes = ExpandJob(job);
  ASSERT_EQ(episodes.size(), 2u);
  EXPECT_EQ(episodes[0].board, "tx2");
  EXPECT_EQ(episodes[0].world, "s2");
  EXPECT_EQ(episodes[0].seed, 104u);
  EXPECT_EQ(episodes[1].board, "pi4b");
  EXPECT_EQ(episodes[1].seed, 7u);
  EXPECT_EQ(episodes[1].overrides.at("strategy.explore"), 0.0);
}

TEST(JobSpecCollectTest, ACollectionJobCannotFlyTheLeastLoadRule) {
  const std::string job = "boards: [tx2]\nscenarios: [empty]\nseeds: 1\nmethods: [enavi]\ncollect: rollouts\n"
                          "policy: \"" + kHashRef + "\"\n";
  EXPECT_NE(Error(job + "overrides: {strategy.least_load: 1}\n")
                .find("job.yaml:7: overrides.strategy.least_load: a collection job records the policy's decisions"),
            std::string::npos);
  EXPECT_NE(Error(job + "episode_overrides:\n  - match: {seed: 1}\n    overrides: {strategy.least_load: 1}\n")
                .find("episode_overrides[0].overrides.strategy.least_load"),
            std::string::npos);
  // Off, or in a job that collects nothing, it is an ordinary tunable.
  EXPECT_NO_THROW(Parse(job + "overrides: {strategy.least_load: 0}\n"));
  const JobSpec ablation = Parse("boards: [tx2]\nscenarios: [empty]\nseeds: 1\nmethods: [enavi]\n"
                                 "overrides: {strategy.least_load: 1}\n");
  EXPECT_EQ(ExpandJob(ablation).at(0).overrides.at("strategy.least_load"), 1.0);
}

TEST(JobSpecCollectTest, BadCollectionSpecsNameLineAndField) {
  const std::string base = "boards: [tx2]\nscenarios: [empty]\nseeds: 1\n";
  EXPECT_NE(Error(base + "methods: [baseline]\ncollect: rollouts\npolicy: \"" + kHashRef + "\"\n")
                .find("job.yaml:4: methods: a collection job flies one method that records rollouts: [enavi]"),
            std::string::npos);
  EXPECT_NE(Error(base + "methods: [enavi, learned]\ncollect: rollouts\npolicy: \"" + kHashRef + "\"\n")
                .find("methods: a collection job flies one method"),
            std::string::npos);
  EXPECT_NE(Error(base + "methods: [enavi]\ncollect: rollouts\n").find("policy: a collection job names its policy"),
            std::string::npos);
  EXPECT_NE(Error(base + "methods: [enavi]\ncollect: images\n").find("collect: the only collection is 'rollouts'"),
            std::string::npos);
  EXPECT_NE(Error(base + "methods: [enavi]\nsample: true\n").find("sample: only with collect: rollouts"),
            std::string::npos);
  EXPECT_NE(Error(base + "methods: [enavi]\ncollect: rollouts\nsample: yes please\npolicy: \"" + kHashRef + "\"\n")
                .find("sample: expected true or false"),
            std::string::npos);
  EXPECT_NE(Error(base + "methods: [enavi]\npolicy: sha256:abc\n").find("policy: expected sha256: and 64"),
            std::string::npos);
  EXPECT_NE(Error("methods: [enavi]\nboards: [tx2]\nepisodes:\n  - {board: tx2, scenario: s1, seed: 1}\n")
                .find("boards: not with episodes:"),
            std::string::npos);
  EXPECT_NE(Error("methods: [enavi]\nepisodes:\n  - {board: tx2, scenario: s1}\n").find("episodes.seed: missing"),
            std::string::npos);
}

}  // namespace
}  // namespace enavi::api
