// Finite-difference check of the full PPO loss gradient (clipped surrogate + value loss + entropy
// bonus) with respect to every parameter block of actor and critic.

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "navstack/rl/ppo.h"

namespace enavi::navstack::rl {
namespace {

// A batch whose ratios sit clearly inside or outside the clip interval (never within 1e-3 of a
// kink), with random masks, advantages of both signs and arbitrary value targets.
PpoBatch MakeBatch(const ActorCritic& net, int n, std::uint64_t seed) {
  Rng rng(seed);
  PpoBatch b;
  b.num_actions = net.num_actions();
  b.obs.resize(net.obs_dim(), n);
  b.old_log_probs.resize(n);
  b.advantages.resize(n);
  b.returns.resize(n);
  Eigen::MatrixXd head, logits(net.num_actions(), n);
  Mlp::BatchCache cache;
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < net.obs_dim(); ++k) b.obs(k, i) = rng.Normal();
  }
  net.actor().ForwardBatch(b.obs, &cache, &head);
  net.Logits(head, logits);
  const double offsets[] = {-0.5, -0.05, 0.05, 0.5};  // ratios 1.65, 1.05, 0.95, 0.61
  Eigen::VectorXd lp(net.num_actions());
  for (int i = 0; i < n; ++i) {
    std::vector<std::uint8_t> mask(static_cast<std::size_t>(net.num_actions()));
    do {
      for (auto& m : mask) m = rng.Uniform01() < 0.5 ? 1 : 0;
    } while (std::count(mask.begin(), mask.end(), 1) < 2);
    std::vector<int> feasible;
    for (int a = 0; a < net.num_actions(); ++a) {
      if (mask[static_cast<std::size_t>(a)]) feasible.push_back(a);
    }
    const int action = feasible[rng.UniformIndex(feasible.size())];
    b.masks.insert(b.masks.end(), mask.begin(), mask.end());
    b.actions.push_back(action);
    MaskedLogSoftmax(logits.col(i), mask, lp);
    b.old_log_probs[i] = lp[action] + offsets[i % 4];
    b.advantages[i] = (i % 3 == 0 ? -1.0 : 1.0) * (0.5 + rng.Uniform01());
    b.returns[i] = 2.0 * rng.Normal();
  }
  return b;
}

PpoOptions LossOptions() {
  PpoOptions o;
  o.clip = 0.2;
  o.value_coef = 0.7;
  o.entropy_coef = 0.03;
  return o;
}

struct BlockError {
  double max_rel = 0.0;
  int checked = 0;
};

// Central differences on the entries [begin, end) of one network's flat parameters, either all of
// them or `samples` random ones.
BlockError CheckBlock(ActorCritic* net, bool actor, Eigen::Index begin, Eigen::Index end,
                      const Eigen::VectorXd& analytic, const PpoBatch& batch, const PpoOptions& opt,
                      int samples, Rng* rng) {
  Eigen::VectorXd& params = actor ? net->actor().params() : net->critic().params();
  std::vector<Eigen::Index> idx;
  if (samples <= 0 || samples >= end - begin) {
    for (Eigen::Index i = begin; i < end; ++i) idx.push_back(i);
  } else {
    for (int s = 0; s < samples; ++s) {
      idx.push_back(begin + static_cast<Eigen::Index>(rng->UniformIndex(static_cast<std::uint64_t>(end - begin))));
    }
  }
  // h = 1e-5 balances truncation (h^2) against round-off (1e-16 |L| / h ~ 1e-11); entries below
  // 1e-4 are compared at the 1e-4 scale so that round-off does not pass for a relative error.
  constexpr double h = 1e-5;
  BlockError e;
  for (Eigen::Index i : idx) {
    const double saved = params[i];
    params[i] = saved + h;
    const double up = ComputePpoLoss(*net, batch, opt, nullptr).total;
    params[i] = saved - h;
    const double down = ComputePpoLoss(*net, batch, opt, nullptr).total;
    params[i] = saved;
    const double fd = (up - down) / (2 * h);
    const double rel = std::abs(fd - analytic[i]) / std::max({std::abs(fd), std::abs(analytic[i]), 1e-4});
    e.max_rel = std::max(e.max_rel, rel);
    ++e.checked;
  }
  return e;
}

void CheckAllBlocks(ActorCritic* net, const PpoBatch& batch, const PpoOptions& opt, int samples) {
  PpoGradients g;
  const PpoLossTerms terms = ComputePpoLoss(*net, batch, opt, &g);
  ASSERT_GT(terms.clip_fraction, 0.0) << "the batch must exercise the clipped branch";
  ASSERT_LT(terms.clip_fraction, 1.0) << "... and the unclipped one";
  ASSERT_GT(terms.entropy, 0.0);
  Rng rng(5);
  for (bool actor : {true, false}) {
    const Mlp& mlp = actor ? net->actor() : net->critic();
    for (int l = 0; l < mlp.num_layers(); ++l) {
      const Eigen::Index w0 = mlp.offset(l);
      const Eigen::Index b0 = w0 + mlp.W(l).size();
      const Eigen::Index b1 = b0 + mlp.b(l).size();
      const Eigen::VectorXd& grad = actor ? g.actor : g.critic;
      const BlockError ew = CheckBlock(net, actor, w0, b0, grad, batch, opt, samples, &rng);
      const BlockError eb = CheckBlock(net, actor, b0, b1, grad, batch, opt, samples, &rng);
      const char* which = actor ? "actor" : "critic";
      EXPECT_LT(ew.max_rel, 1e-6) << which << " W" << l << " (" << ew.checked << " entries)";
      EXPECT_LT(eb.max_rel, 1e-6) << which << " b" << l << " (" << eb.checked << " entries)";
    }
  }
}

TEST(PpoGradientTest, SmallNetworkEveryParameterMatchesFiniteDifferences) {
  ActorCritic net({5, 6, {7, 6}});
  Rng rng(21);
  net.actor().InitOrthogonal(&rng, 1.0);
  net.critic().InitOrthogonal(&rng, 1.0);
  const PpoBatch batch = MakeBatch(net, 16, 3);
  CheckAllBlocks(&net, batch, LossOptions(), /*samples=*/0);
}

// A factored head: 6 actions = 2 levels of one component x 3 of another, each action's logit the
// sum of its two levels' outputs (5 actor outputs).
TEST(PpoGradientTest, FactoredHeadEveryParameterMatchesFiniteDifferences) {
  ActorCriticConfig config{5, 6, {7, 6}};
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 3; ++j) config.action_terms.push_back({i, 2 + j});
  }
  config.head_outputs = 5;
  ActorCritic net(config);
  ASSERT_EQ(net.actor().output_size(), 5);
  Rng rng(23);
  net.actor().InitOrthogonal(&rng, 1.0);
  net.critic().InitOrthogonal(&rng, 1.0);
  const PpoBatch batch = MakeBatch(net, 16, 5);
  CheckAllBlocks(&net, batch, LossOptions(), /*samples=*/0);
}

TEST(PpoGradientTest, PaperSizedNetworkSampledParametersMatchFiniteDifferences) {
  ActorCritic net({16, 189, {150, 150}});
  Rng rng(22);
  net.actor().InitOrthogonal(&rng, 1.0);
  net.critic().InitOrthogonal(&rng, 1.0);
  const PpoBatch batch = MakeBatch(net, 8, 4);
  CheckAllBlocks(&net, batch, LossOptions(), /*samples=*/25);
}

TEST(PpoGradientTest, LossTermsCombineAsDocumented) {
  ActorCritic net({4, 5, {8, 8}});
  Rng rng(2);
  net.InitializeWeights(&rng);
  const PpoBatch batch = MakeBatch(net, 10, 9);
  const PpoOptions o = LossOptions();
  const PpoLossTerms t = ComputePpoLoss(net, batch, o, nullptr);
  EXPECT_NEAR(t.total, t.policy + o.value_coef * t.value - o.entropy_coef * t.entropy, 1e-14);
  EXPECT_NEAR(t.clip_fraction, 0.5, 1e-12) << "half the offsets put the ratio outside [0.8, 1.2]";
}

}  // namespace
}  // namespace enavi::navstack::rl
