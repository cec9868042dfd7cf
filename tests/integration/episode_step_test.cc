// An episode as a model and its state, stepped one physics step at a time (sim::Episode), and
// E-Navi's sampled decisions taken outside the stack through a DecisionPort (what the Python
// environment does): the flight is the one whose decisions were taken inside, to the byte.
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "navstack/rl/decision_port.h"
#include "navstack/rl/rollout.h"
#include "tests/integration/loop_test_util.h"
#include "workers/sim/episode.h"

namespace enavi::integration {
namespace {

std::shared_ptr<const sim::PreparedWorld> Prepare(const api::EpisodeSpec& spec) {
  return sim::PrepareSpecWorld(spec);
}

// E-Navi sampling its decisions (as in training) on s1 for 8 s: some 40 decisions.
api::EpisodeSpec SampledEnavi() {
  api::EpisodeSpec spec = Spec("s1", 3);
  spec.method = "enavi";
  spec.board = "tx2";
  spec.timeout_s = 8.0;
  spec.overrides["strategy.explore"] = 1;
  return spec;
}

TEST(EpisodeStepTest, SteppingAnEpisodeToItsEndGivesRunEpisodesResult) {
  api::EpisodeSpec spec = Spec("s3", 2);
  spec.timeout_s = 3.0;
  const auto world = Prepare(spec);
  sim::Episode episode(spec, *world);
  EXPECT_EQ(episode.model().timeout_s, 3.0);
  EXPECT_EQ(episode.model().threads, 1) << "the baseline's one spinner thread";
  long steps = 0;
  sim::StepStatus status;
  while ((status = episode.Step()) == sim::StepStatus::kRunning) ++steps;
  ASSERT_EQ(status, sim::StepStatus::kEnded);
  ASSERT_TRUE(episode.end().has_value());
  EXPECT_EQ(episode.end()->reason, "timeout");
  EXPECT_EQ(steps, 3000) << "1 kHz up to the timeout";
  EXPECT_THROW(episode.Step(), std::logic_error) << "a step after the end";
  const api::EpisodeResult stepped = episode.Finish();
  EXPECT_THROW(episode.Finish(), std::logic_error) << "results are written once";
  EXPECT_EQ(nlohmann::json(stepped).dump(), nlohmann::json(sim::RunEpisode(spec, *world)).dump());
}

TEST(EpisodeStepTest, DecisionsTakenOutsideFlyTheFlightOfTheSameDecisionsTakenInside) {
  const api::EpisodeSpec spec = SampledEnavi();
  const auto world = Prepare(spec);
  // Inside: the network samples each action.
  navstack::rl::Rollout inside;
  sim::EpisodeOptions options;
  options.rollout = &inside;
  const api::EpisodeResult a = sim::RunEpisode(spec, *world, options);
  ASSERT_GT(inside.steps.size(), 20u) << Describe(a);

  // Outside: each decision waits in the port, and gets the action the network took inside.
  navstack::rl::DecisionPort port;
  navstack::rl::Rollout outside;
  options.rollout = &outside;
  options.decisions = &port;
  sim::Episode episode(spec, *world, options);
  std::size_t decisions = 0;
  sim::StepStatus status;
  while ((status = episode.Step()) != sim::StepStatus::kEnded) {
    if (status != sim::StepStatus::kAwaitingDecision) continue;
    ASSERT_TRUE(port.pending());
    ASSERT_LT(decisions, inside.steps.size());
    const navstack::rl::RolloutStep& taken = inside.steps[decisions];
    EXPECT_EQ(port.observation(), taken.obs) << "decision " << decisions;
    EXPECT_EQ(port.mask(), taken.mask) << "decision " << decisions;
    if (decisions == 0) {
      EXPECT_THROW(episode.Step(), std::logic_error) << "no action supplied yet";
      int blocked = 0;
      while (blocked < static_cast<int>(taken.mask.size()) && taken.mask[blocked]) ++blocked;
      if (blocked < static_cast<int>(taken.mask.size())) {
        EXPECT_THROW(port.Supply(blocked), std::invalid_argument) << "an infeasible action";
      }
    }
    port.Supply(taken.action);
    ++decisions;
  }
  EXPECT_EQ(decisions, inside.steps.size());
  const api::EpisodeResult b = episode.Finish();
  EXPECT_EQ(nlohmann::json(a).dump(), nlohmann::json(b).dump());
  ASSERT_EQ(outside.steps.size(), inside.steps.size());
  for (std::size_t i = 0; i < inside.steps.size(); ++i) {
    EXPECT_EQ(outside.steps[i].action, inside.steps[i].action) << i;
    EXPECT_EQ(outside.steps[i].reward, inside.steps[i].reward) << i;
    EXPECT_EQ(outside.steps[i].log_prob, inside.steps[i].log_prob) << i;
  }
}

TEST(EpisodeStepTest, ALoopThatCannotTakeDecisionsRefusesAPortAndAMethodWithoutDecisionsToo) {
  const api::EpisodeSpec spec = SampledEnavi();
  const auto world = Prepare(spec);
  navstack::rl::DecisionPort port;
  sim::EpisodeOptions options;
  options.decisions = &port;
  EXPECT_THROW(sim::RunEpisode(spec, *world, options), std::logic_error);
  api::EpisodeSpec baseline = spec;
  baseline.method = "baseline";
  baseline.overrides.clear();
  EXPECT_THROW(sim::Episode(baseline, *world, options), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::integration
