// A short PPO run on a toy task improves the mean return (fixed seeds); checkpoints resume
// bit-identically; GAE and the batch builder behave as documented.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "navstack/rl/ppo.h"
#include "tests/unit/rl/toy_corridor.h"

namespace enavi::navstack::rl {
namespace {

using testing::ToyCorridor;

constexpr int kMaxSteps = 12;
constexpr int kEpisodesPerIteration = 16;

// Paper-sized hidden layers on the toy task's 4 inputs and 4 actions.
PolicyFile ToyPolicy(std::uint64_t seed) {
  PolicyFile p{ActorCritic({4, 4, {150, 150}}), {"x", "goal_side", "goal_distance", "bias"},
               std::nullopt, nlohmann::json::object()};
  Rng rng(seed);
  p.net.InitializeWeights(&rng);
  return p;
}

PpoOptions ToyOptions() {
  PpoOptions o;
  o.learning_rate = 1e-3;
  o.minibatch_size = 32;
  o.epochs = 4;
  return o;
}

// Rollouts of one iteration: episode seeds derive from (seed, iteration, episode), so a resumed
// trainer collects exactly the same data.
std::vector<Rollout> Collect(const PpoTrainer& trainer, std::uint64_t seed) {
  ToyCorridor env;
  std::vector<Rollout> out;
  for (int e = 0; e < kEpisodesPerIteration; ++e) {
    const std::uint64_t s = DeriveSeed(seed, static_cast<std::uint64_t>(trainer.iteration()),
                                       static_cast<std::uint64_t>(e));
    out.push_back(CollectEpisode(&env, trainer.net(), s, ActMode::kSample, kMaxSteps,
                                 trainer.iteration()));
  }
  return out;
}

// Mean return of the stochastic policy over 200 fixed episodes.
double Evaluate(const ActorCritic& net) {
  ToyCorridor env;
  double sum = 0.0;
  for (int e = 0; e < 200; ++e) {
    sum += CollectEpisode(&env, net, DeriveSeed(777, 0, static_cast<std::uint64_t>(e)),
                          ActMode::kSample, kMaxSteps)
               .Return();
  }
  return sum / 200.0;
}

TEST(PpoTrainingTest, ShortRunOnToyCorridorImprovesTheMeanReturn) {
  PpoTrainer trainer(ToyPolicy(1), ToyOptions(), 2);
  const double before = Evaluate(trainer.net());
  for (int it = 0; it < 25; ++it) {
    const PpoUpdateStats stats = trainer.Update(Collect(trainer, 3));
    ASSERT_EQ(stats.iteration, it);
    ASSERT_TRUE(std::isfinite(stats.loss.total));
  }
  const double after = Evaluate(trainer.net());
  RecordProperty("mean_return_before", std::to_string(before));
  RecordProperty("mean_return_after", std::to_string(after));
  // Uniform play scores about -0.5 here; the optimum is 0.7 (three steps to the goal).
  EXPECT_GT(after, before + 0.6) << "before " << before << ", after " << after;
  EXPECT_GT(after, 0.5) << "close to the optimum of 0.7";
}

TEST(PpoTrainingTest, CheckpointResumeGivesABitIdenticalNextIteration) {
  PpoTrainer a(ToyPolicy(4), ToyOptions(), 5);
  for (int it = 0; it < 2; ++it) a.Update(Collect(a, 6));
  const std::string path =
      (std::filesystem::path(::testing::TempDir()) / "ppo_checkpoint_test.json").string();
  a.SaveCheckpoint(path);
  PpoTrainer b = PpoTrainer::LoadCheckpoint(path);
  std::remove(path.c_str());

  ASSERT_EQ(b.iteration(), 2);
  ASSERT_TRUE(b.rng() == a.rng());
  const PpoUpdateStats sa = a.Update(Collect(a, 6));
  const PpoUpdateStats sb = b.Update(Collect(b, 6));
  EXPECT_EQ(sa.loss.total, sb.loss.total);
  EXPECT_EQ(sa.mean_rollout_return, sb.mean_rollout_return);
  EXPECT_TRUE(a.net().actor().params() == b.net().actor().params()) << "bitwise";
  EXPECT_TRUE(a.net().critic().params() == b.net().critic().params());
  EXPECT_TRUE(a.net().normaliser().mean == b.net().normaliser().mean);
  EXPECT_TRUE(a.net().normaliser().var == b.net().normaliser().var);
  EXPECT_TRUE(a.actor_adam().m == b.actor_adam().m);
  EXPECT_TRUE(a.critic_adam().v == b.critic_adam().v);
  EXPECT_EQ(a.actor_adam().t, b.actor_adam().t);
  EXPECT_TRUE(a.rng() == b.rng());
}

TEST(PpoTrainingTest, CorruptCheckpointIsAClearError) {
  PpoTrainer a(ToyPolicy(4), ToyOptions(), 5);
  const std::string path =
      (std::filesystem::path(::testing::TempDir()) / "ppo_checkpoint_corrupt.json").string();
  a.SaveCheckpoint(path);
  std::string text;
  {
    std::ifstream in(path);
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  {
    std::ofstream out(path, std::ios::trunc);
    out << text.substr(0, text.size() / 2);
  }
  try {
    PpoTrainer::LoadCheckpoint(path);
    ADD_FAILURE() << "a truncated checkpoint loaded";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
  EXPECT_THROW(PpoTrainer::LoadCheckpoint(path), std::invalid_argument) << "missing file";
}

TEST(PpoTrainingTest, StaleOrMalformedRolloutsAreRefusedWithoutChangingTheTrainer) {
  PpoTrainer t(ToyPolicy(4), ToyOptions(), 5);
  std::vector<Rollout> rollouts = Collect(t, 6);
  const Eigen::VectorXd before = t.net().actor().params();
  std::vector<Rollout> stale = rollouts;
  stale[3].policy_iteration = 7;
  EXPECT_THROW(t.Update(stale), std::invalid_argument);
  std::vector<Rollout> bad = rollouts;
  bad[0].steps[0].mask[static_cast<std::size_t>(bad[0].steps[0].action)] = 0;
  EXPECT_THROW(t.Update(bad), std::invalid_argument);
  EXPECT_THROW(t.Update({}), std::invalid_argument);
  EXPECT_TRUE(t.net().actor().params() == before);
  EXPECT_EQ(t.iteration(), 0);
}

TEST(GaeTest, MatchesAHandComputedExample) {
  // Three steps, no terminal, bootstrap V = 0.5. gamma 0.9, lambda 0.8.
  Rollout r;
  const double rewards[] = {1.0, 0.0, 2.0};
  const double values[] = {0.2, 0.4, 0.1};
  for (int t = 0; t < 3; ++t) r.steps.push_back({Eigen::VectorXd::Zero(1), 0, {1}, 0.0, values[t], rewards[t], false});
  r.bootstrap_value = 0.5;
  Eigen::VectorXd adv(3), ret(3);
  ComputeGae(r, 0.9, 0.8, adv, ret);
  const double d2 = 2.0 + 0.9 * 0.5 - 0.1;
  const double d1 = 0.0 + 0.9 * 0.1 - 0.4;
  const double d0 = 1.0 + 0.9 * 0.4 - 0.2;
  EXPECT_NEAR(adv[2], d2, 1e-15);
  EXPECT_NEAR(adv[1], d1 + 0.72 * d2, 1e-15);
  EXPECT_NEAR(adv[0], d0 + 0.72 * (d1 + 0.72 * d2), 1e-15);
  EXPECT_NEAR(ret[0], adv[0] + 0.2, 1e-15);
  // A terminal at step 1 cuts both the bootstrap and the advantage chain.
  r.steps[1].done = true;
  ComputeGae(r, 0.9, 0.8, adv, ret);
  EXPECT_NEAR(adv[1], 0.0 - 0.4, 1e-15);
  EXPECT_NEAR(adv[0], d0 + 0.72 * (0.0 - 0.4), 1e-15);
  EXPECT_NEAR(adv[2], d2, 1e-15) << "after the terminal a new episode starts";
}

TEST(PpoOptionsTest, OutOfRangeValuesNameTheField) {
  PpoOptions o;
  o.clip = 1.5;
  try {
    o.Validate();
    ADD_FAILURE() << "clip 1.5 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("clip"), std::string::npos) << e.what();
  }
  o = PpoOptions{};
  o.minibatch_size = 0;
  EXPECT_THROW(o.Validate(), std::invalid_argument);
  EXPECT_THROW(PpoTrainer(ToyPolicy(1), o, 1), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack::rl
