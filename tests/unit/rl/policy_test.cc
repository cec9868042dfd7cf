// Actor-critic policy: masked categorical sampling and greedy choice, MLP passes, normaliser.

#include "navstack/rl/policy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace enavi::navstack::rl {
namespace {

// A small net with spread-out logits (output gain 3 instead of PPO's near-uniform 0.01).
ActorCritic SpreadNet(int obs_dim, int num_actions, std::uint64_t seed) {
  ActorCritic net({obs_dim, num_actions, {32, 32}});
  Rng rng(seed);
  net.actor().InitOrthogonal(&rng, 3.0);
  net.critic().InitOrthogonal(&rng, 1.0);
  return net;
}

Eigen::VectorXd RandomObs(int dim, Rng* rng) {
  Eigen::VectorXd x(dim);
  for (int i = 0; i < dim; ++i) x[i] = rng->Normal();
  return x;
}

std::vector<std::uint8_t> RandomMask(int n, Rng* rng) {
  std::vector<std::uint8_t> m(static_cast<std::size_t>(n));
  do {
    for (auto& v : m) v = rng->Uniform01() < 0.4 ? 1 : 0;
  } while (std::count(m.begin(), m.end(), 1) == 0);
  return m;
}

TEST(MaskedPolicyTest, MaskedActionsAreNeverSampledAndFeasibleOnesFollowTheirProbabilities) {
  const ActorCritic net = SpreadNet(6, 12, 7);
  ActorCritic::Workspace ws = net.MakeWorkspace();
  Rng data_rng(11), sample_rng(12);
  const Eigen::VectorXd obs = RandomObs(6, &data_rng);
  std::vector<std::uint8_t> mask(12, 0);
  for (int i : {0, 3, 4, 9, 11}) mask[static_cast<std::size_t>(i)] = 1;

  Eigen::VectorXd normalised(6), logits(12), log_probs(12);
  Mlp::Workspace aws = net.actor().MakeWorkspace();
  net.normaliser().Normalise(obs, normalised);
  net.actor().Forward(normalised, &aws, logits);
  MaskedLogSoftmax(logits, mask, log_probs);

  constexpr int kDraws = 40000;
  std::vector<int> counts(12, 0);
  for (int k = 0; k < kDraws; ++k) {
    const PolicyOutput out = net.Act(obs, mask, ActMode::kSample, &sample_rng, &ws);
    ++counts[static_cast<std::size_t>(out.action)];
    ASSERT_NEAR(out.log_prob, log_probs[out.action], 1e-12);
  }
  for (int i = 0; i < 12; ++i) {
    if (!mask[static_cast<std::size_t>(i)]) {
      EXPECT_EQ(counts[static_cast<std::size_t>(i)], 0) << "masked action " << i << " was sampled";
      continue;
    }
    // Binomial: the empirical share within 5 standard deviations of p.
    const double p = std::exp(log_probs[i]);
    const double sd = std::sqrt(p * (1 - p) / kDraws);
    EXPECT_NEAR(counts[static_cast<std::size_t>(i)] / double(kDraws), p, 5 * sd + 1e-4)
        << "action " << i;
  }
}

TEST(MaskedPolicyTest, ManyRandomMasksNeverYieldAMaskedAction) {
  const ActorCritic net = SpreadNet(5, 40, 3);
  ActorCritic::Workspace ws = net.MakeWorkspace();
  Rng rng(99);
  for (int k = 0; k < 5000; ++k) {
    const Eigen::VectorXd obs = RandomObs(5, &rng);
    const std::vector<std::uint8_t> mask = RandomMask(40, &rng);
    const PolicyOutput out = net.Act(obs, mask, ActMode::kSample, &rng, &ws);
    ASSERT_TRUE(mask[static_cast<std::size_t>(out.action)]) << "draw " << k;
  }
}

TEST(MaskedPolicyTest, GreedyIsTheArgmaxOverFeasibleActions) {
  const ActorCritic net = SpreadNet(5, 40, 5);
  ActorCritic::Workspace ws = net.MakeWorkspace();
  Mlp::Workspace aws = net.actor().MakeWorkspace();
  Rng rng(17);
  int differs_from_unmasked = 0;
  for (int k = 0; k < 500; ++k) {
    const Eigen::VectorXd obs = RandomObs(5, &rng);
    const std::vector<std::uint8_t> mask = RandomMask(40, &rng);
    Eigen::VectorXd logits(40);
    net.actor().Forward(obs, &aws, logits);
    int best = -1;
    for (int i = 0; i < 40; ++i) {
      if (mask[static_cast<std::size_t>(i)] && (best < 0 || logits[i] > logits[best])) best = i;
    }
    Eigen::Index unmasked;
    logits.maxCoeff(&unmasked);
    differs_from_unmasked += best != unmasked ? 1 : 0;
    const PolicyOutput out = net.Act(obs, mask, ActMode::kGreedy, nullptr, &ws);
    ASSERT_EQ(out.action, best) << "case " << k;
  }
  EXPECT_GT(differs_from_unmasked, 100) << "the masks must actually hide the global argmax often";
}

TEST(MaskedPolicyTest, LogSoftmaxIsNormalisedOverFeasibleActions) {
  Eigen::VectorXd logits(5);
  logits << 1.0, 1000.0, -2.0, 0.5, 3.0;  // the huge one is masked: no overflow, no influence
  const std::vector<std::uint8_t> mask = {1, 0, 1, 1, 0};
  Eigen::VectorXd lp(5);
  MaskedLogSoftmax(logits, mask, lp);
  EXPECT_EQ(lp[1], -std::numeric_limits<double>::infinity());
  EXPECT_EQ(lp[4], -std::numeric_limits<double>::infinity());
  EXPECT_NEAR(std::exp(lp[0]) + std::exp(lp[2]) + std::exp(lp[3]), 1.0, 1e-15);
  EXPECT_NEAR(lp[0] - lp[3], 0.5, 1e-15);
}

TEST(MaskedPolicyTest, RefusesEmptyOrMisSizedMasks) {
  const ActorCritic net = SpreadNet(3, 4, 1);
  ActorCritic::Workspace ws = net.MakeWorkspace();
  const Eigen::VectorXd obs = Eigen::VectorXd::Zero(3);
  const std::vector<std::uint8_t> none(4, 0), short_mask(3, 1);
  Rng rng(1);
  EXPECT_THROW(net.Act(obs, none, ActMode::kGreedy, nullptr, &ws), std::invalid_argument);
  EXPECT_THROW(net.Act(obs, none, ActMode::kSample, &rng, &ws), std::invalid_argument);
  EXPECT_THROW(net.Act(obs, short_mask, ActMode::kGreedy, nullptr, &ws), std::invalid_argument);
  EXPECT_THROW(net.Act(Eigen::VectorXd::Zero(2), std::vector<std::uint8_t>(4, 1), ActMode::kGreedy,
                       nullptr, &ws),
               std::invalid_argument);
}

TEST(MaskedPolicyTest, SamplingIsDeterministicForASeed) {
  const ActorCritic net = SpreadNet(4, 10, 2);
  ActorCritic::Workspace ws = net.MakeWorkspace();
  const std::vector<std::uint8_t> mask(10, 1);
  const Eigen::VectorXd obs = Eigen::VectorXd::Constant(4, 0.3);
  Rng a(42), b(42);
  for (int k = 0; k < 200; ++k) {
    ASSERT_EQ(net.Act(obs, mask, ActMode::kSample, &a, &ws).action,
              net.Act(obs, mask, ActMode::kSample, &b, &ws).action);
  }
}

TEST(MlpTest, BatchForwardMatchesSingleSampleForward) {
  Mlp mlp({4, 9, 7, 3});
  Rng rng(8);
  mlp.InitOrthogonal(&rng, 1.0);
  mlp.params() += 0.1 * Eigen::VectorXd::Ones(mlp.num_params());  // non-zero biases too
  Eigen::MatrixXd X(4, 6);
  for (int j = 0; j < 6; ++j) X.col(j) = RandomObs(4, &rng);
  Mlp::BatchCache cache;
  Eigen::MatrixXd Y;
  mlp.ForwardBatch(X, &cache, &Y);
  Mlp::Workspace ws = mlp.MakeWorkspace();
  Eigen::VectorXd y(3);
  for (int j = 0; j < 6; ++j) {
    mlp.Forward(X.col(j), &ws, y);
    EXPECT_LT((y - Y.col(j)).norm(), 1e-12) << "column " << j;
  }
  EXPECT_EQ(mlp.MacsPerSample(), 4 * 9 + 9 * 7 + 7 * 3);
}

TEST(MlpTest, OrthogonalInitHasOrthonormalRowsOrColumns) {
  Mlp mlp({16, 150, 150, 189});
  Rng rng(1);
  mlp.InitOrthogonal(&rng, 1.0);
  const Eigen::MatrixXd w0 = mlp.W(0) / std::sqrt(2.0);  // 150 x 16: orthonormal columns
  EXPECT_LT((w0.transpose() * w0 - Eigen::MatrixXd::Identity(16, 16)).norm(), 1e-10);
  const Eigen::MatrixXd w2 = mlp.W(2);  // 189 x 150 with gain 1
  EXPECT_LT((w2.transpose() * w2 - Eigen::MatrixXd::Identity(150, 150)).norm(), 1e-10);
}

TEST(ActorCriticTest, PaperArchitectureCostsAreAsDocumented) {
  const ActorCritic net({16, 189, {150, 150}});
  EXPECT_EQ(net.MacsPerDecision(false), 16 * 150 + 150 * 150 + 150 * 189);
  EXPECT_EQ(net.MacsPerDecision(true), 2 * (16 * 150 + 150 * 150) + 150 * 189 + 150);
}

// Factored head: 6 actions = 2 x 3 levels; an action's logit is the sum of its levels' outputs.
TEST(ActorCriticTest, FactoredLogitsAreSumsOfLevelOutputsAndTheGradientIsTheTranspose) {
  ActorCriticConfig config{4, 6, {8}};
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 3; ++j) config.action_terms.push_back({i, 2 + j});
  }
  config.head_outputs = 5;
  ActorCritic net(config);
  Rng rng(9);
  net.actor().InitOrthogonal(&rng, 3.0);
  const Eigen::VectorXd obs = RandomObs(4, &rng);
  Eigen::MatrixXd head, logits(6, 1);
  Mlp::BatchCache cache;
  net.actor().ForwardBatch(net.normaliser().NormaliseBatch(obs), &cache, &head);
  net.Logits(head, logits);
  ASSERT_EQ(logits.rows(), 6);
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 3; ++j) EXPECT_DOUBLE_EQ(logits(3 * i + j, 0), head(i, 0) + head(2 + j, 0));
  }
  // Act() composes the same logits: greedy picks their argmax, log-probs are their softmax.
  ActorCritic::Workspace ws = net.MakeWorkspace();
  const std::vector<std::uint8_t> all(6, 1);
  const PolicyOutput out = net.Act(obs, all, ActMode::kGreedy, nullptr, &ws);
  Eigen::Index best = 0;
  logits.col(0).maxCoeff(&best);
  EXPECT_EQ(out.action, best);
  Eigen::VectorXd lp(6);
  MaskedLogSoftmax(logits.col(0), all, lp);
  EXPECT_NEAR(out.log_prob, lp[best], 1e-12);
  // <d_logits, Logits(h)> = <HeadGradient(d_logits), h> for any h, d_logits.
  const Eigen::MatrixXd h = Eigen::MatrixXd::Random(5, 3), d = Eigen::MatrixXd::Random(6, 3);
  Eigen::MatrixXd lh(6, 3), dh;
  net.Logits(h, lh);
  net.HeadGradient(d, &dh);
  EXPECT_NEAR((d.array() * lh.array()).sum(), (dh.array() * h.array()).sum(), 1e-12);
  EXPECT_EQ(net.MacsPerDecision(false), 4 * 8 + 8 * 5 + 6 * 2) << "the actor plus one add per term";
  // Terms must name actor outputs, one list per action.
  ActorCriticConfig bad = config;
  bad.action_terms[2] = {0, 5};
  EXPECT_THROW(ActorCritic{bad}, std::invalid_argument);
  bad = config;
  bad.action_terms.pop_back();
  EXPECT_THROW(ActorCritic{bad}, std::invalid_argument);
}

TEST(ObservationNormaliserTest, MergedStatisticsEqualThoseOfTheWholeData) {
  Rng rng(4);
  Eigen::MatrixXd X(3, 50);
  for (int j = 0; j < 50; ++j) X.col(j) = RandomObs(3, &rng) * 2.0 + Eigen::Vector3d(1, -2, 5);
  ObservationNormaliser n(3);
  n.Update(X.leftCols(20));
  n.Update(X.rightCols(30));
  const Eigen::VectorXd mean = X.rowwise().mean();
  const Eigen::VectorXd var = (X.colwise() - mean).array().square().rowwise().mean();
  EXPECT_LT((n.mean - mean).norm(), 1e-12);
  EXPECT_LT((n.var - var).norm(), 1e-12);
  EXPECT_EQ(n.count, 50.0);
  Eigen::VectorXd z(3);
  n.Normalise(X.col(0), z);
  const Eigen::MatrixXd zb = n.NormaliseBatch(X);
  EXPECT_LT((z - zb.col(0)).norm(), 1e-15);
}

}  // namespace
}  // namespace enavi::navstack::rl
