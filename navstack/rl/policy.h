#pragma once
// Actor-critic policy of the frequency adapter (paper Sec. V.C "Implementation": policy and value
// networks, each two fully connected hidden layers of 150 tanh units), with a masked categorical
// over a discrete action set: infeasible actions get logit -inf before the softmax, so they have
// probability exactly zero and are never chosen.

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "navstack/rl/mlp.h"
#include "navstack/rl/random.h"

namespace enavi::navstack::rl {

/// Running mean / variance of raw observations (parallel Welford). Normalise() maps x to
/// clip((x - mean) / sqrt(var + epsilon), -clip, +clip). Starts as the identity (mean 0, var 1).
struct ObservationNormaliser {
  Eigen::VectorXd mean;
  Eigen::VectorXd var;
  double count = 0.0;   ///< samples merged so far (a double: it may exceed 2^31 on a farm)
  double clip = 5.0;
  double epsilon = 1e-8;

  ObservationNormaliser() = default;
  explicit ObservationNormaliser(int dim)
      : mean(Eigen::VectorXd::Zero(dim)), var(Eigen::VectorXd::Ones(dim)) {}

  /// Merges a batch of raw observations (one per column) into the statistics.
  void Update(const Eigen::Ref<const Eigen::MatrixXd>& X);
  void Normalise(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> out) const;
  Eigen::MatrixXd NormaliseBatch(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
};

/// Shape of an actor-critic.
struct ActorCriticConfig {
  int obs_dim = 1;
  int num_actions = 1;
  std::vector<int> hidden = {150, 150};  ///< paper: two layers of 150 tanh units
};

enum class ActMode {
  kGreedy,  ///< argmax of the logits over feasible actions (evaluation, deployment)
  kSample,  ///< draw from the masked categorical (training rollouts)
};

/// One decision.
struct PolicyOutput {
  int action = -1;
  double log_prob = 0.0;  ///< log pi(action | obs) under the mask (0 if not requested)
  double value = 0.0;     ///< critic's V(obs) (0 if not requested)
};

/// Log-softmax of `logits` restricted to mask[i] != 0; masked entries get -infinity.
/// @throws std::invalid_argument when the mask is empty of feasible actions or has the wrong size.
void MaskedLogSoftmax(const Eigen::Ref<const Eigen::VectorXd>& logits,
                      std::span<const std::uint8_t> mask, Eigen::Ref<Eigen::VectorXd> log_probs);

class ActorCritic {
 public:
  /// Zero weights, identity normaliser. @throws std::invalid_argument for sizes < 1.
  explicit ActorCritic(const ActorCriticConfig& config = {});

  /// Orthogonal initialisation: actor output gain 0.01 (near-uniform initial policy), critic 1.
  void InitializeWeights(Rng* rng);

  const ActorCriticConfig& config() const { return config_; }
  int obs_dim() const { return config_.obs_dim; }
  int num_actions() const { return config_.num_actions; }

  const Mlp& actor() const { return actor_; }
  Mlp& actor() { return actor_; }
  const Mlp& critic() const { return critic_; }
  Mlp& critic() { return critic_; }
  const ObservationNormaliser& normaliser() const { return normaliser_; }
  ObservationNormaliser& normaliser() { return normaliser_; }

  /// Scratch for Act(); one per thread.
  struct Workspace {
    Eigen::VectorXd obs;
    Eigen::VectorXd logits;
    Eigen::VectorXd log_probs;
    Eigen::VectorXd value;
    Mlp::Workspace actor;
    Mlp::Workspace critic;
  };
  Workspace MakeWorkspace() const;

  /// Chooses an action for a raw (unnormalised) observation. Greedy mode needs no rng; sample
  /// mode draws one uniform from `rng` and inverts the CDF over feasible actions in index order.
  /// log_prob and value cost a softmax / a critic pass and are computed only when asked.
  /// @pre obs.size() == obs_dim(); mask.size() == num_actions() with at least one non-zero entry
  ///   (else std::invalid_argument); rng != nullptr in sample mode.
  PolicyOutput Act(const Eigen::Ref<const Eigen::VectorXd>& obs, std::span<const std::uint8_t> mask,
                   ActMode mode, Rng* rng, Workspace* ws, bool want_log_prob = true,
                   bool want_value = true) const;

  /// Multiply-adds of one decision: the actor pass, plus the critic pass when `with_value`.
  std::int64_t MacsPerDecision(bool with_value = false) const;

 private:
  ActorCriticConfig config_;
  Mlp actor_;
  Mlp critic_;
  ObservationNormaliser normaliser_;
};

}  // namespace enavi::navstack::rl
