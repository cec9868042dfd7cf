#pragma once
// Actor-critic policy of the frequency adapter (paper Sec. V.C "Implementation": policy and value
// networks, each two fully connected hidden layers of 150 tanh units), with a masked categorical
// over a discrete action set: infeasible actions get logit -inf before the softmax, so they have
// probability exactly zero and are never chosen.
//
// Two heads. Joint: one actor output per action, the output is the action's logit. Factored: the
// actions are tuples of levels (E-Navi's (f_per, f_col, f_dif)), the actor outputs one logit per
// level of each component, and an action's logit is the sum of its levels' logits; the mask still
// acts on whole actions (the constraints couple the components). Why factored: what a level costs
// (a perception rate's CPU) is then learned from every sample that used the level. With 98 joint
// logits a 12-flight batch of ~1,700 decisions shows each triple ~17 times; the 4 perception
// levels ~400 times each. (Action branching: Tavakoli et al., AAAI 2018.)

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
  /// Factored head: action_terms[a] lists the actor outputs summed into action a's logit, each in
  /// [0, head_outputs). Empty: the joint head (num_actions outputs, output a is a's logit).
  std::vector<std::vector<int>> action_terms = {};
  int head_outputs = 0;  ///< actor outputs of a factored head, >= 1

  bool factored() const { return !action_terms.empty(); }
  int actor_outputs() const { return factored() ? head_outputs : num_actions; }
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
  /// Zero weights, identity normaliser. @throws std::invalid_argument for sizes < 1, or a
  ///   factored head whose terms are not one list per action of indices in [0, head_outputs).
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
    Eigen::VectorXd head;  ///< actor outputs (the logits themselves for a joint head)
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

  /// Multiply-adds of one decision: the actor pass (and a factored head's sums), plus the critic
  /// pass when `with_value`.
  std::int64_t MacsPerDecision(bool with_value = false) const;

  /// Action logits from the actor's outputs, one sample per column (the identity for a joint
  /// head). @pre logits is num_actions() x head.cols(); it is written, never resized.
  void Logits(const Eigen::Ref<const Eigen::MatrixXd>& head, Eigen::Ref<Eigen::MatrixXd> logits) const;
  /// dLoss/d(actor outputs) from dLoss/d(logits): the transpose of Logits().
  void HeadGradient(const Eigen::Ref<const Eigen::MatrixXd>& d_logits, Eigen::MatrixXd* d_head) const;

 private:
  ActorCriticConfig config_;
  Mlp actor_;
  Mlp critic_;
  ObservationNormaliser normaliser_;
};

}  // namespace enavi::navstack::rl
