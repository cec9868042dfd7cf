#pragma once
// Proximal Policy Optimisation (Schulman et al. 2017) for the masked-categorical actor-critic:
// GAE advantages, advantage normalisation, clipped surrogate objective, value loss, entropy bonus,
// Adam, minibatch epochs, manual backpropagation with Eigen.
//
// Environment-agnostic: rollouts in, one update out. The trainer's whole state (policy, observation
// normaliser, Adam moments, iteration, RNG) checkpoints to JSON; resuming from a checkpoint gives a
// bit-identical next iteration.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "navstack/rl/policy.h"
#include "navstack/rl/policy_io.h"
#include "navstack/rl/random.h"
#include "navstack/rl/rollout.h"

namespace enavi::navstack::rl {

/// PPO hyperparameters (named, with ranges; Validate() refuses a bad value naming the field).
struct PpoOptions {
  double gamma = 0.99;           ///< discount, [0, 1]
  double lambda = 0.95;          ///< GAE lambda, [0, 1]
  double clip = 0.2;             ///< surrogate clip epsilon, (0, 1)
  double value_coef = 0.5;       ///< c_v: weight of 0.5 (V - R)^2, [0, 100]
  double entropy_coef = 0.01;    ///< c_e: weight of the entropy bonus, [0, 10]
  double learning_rate = 3e-4;   ///< Adam step size, (0, 1]
  double adam_beta1 = 0.9;       ///< [0, 1)
  double adam_beta2 = 0.999;     ///< [0, 1)
  double adam_epsilon = 1e-8;    ///< (0, 1]
  int epochs = 4;                ///< passes over the batch per update, [1, 1000]
  int minibatch_size = 64;       ///< [1, 1e6]; the last minibatch of an epoch may be smaller
  double max_grad_norm = 0.5;    ///< global gradient-norm clip (actor + critic); 0 disables, >= 0
  bool normalise_advantages = true;  ///< zero mean, unit std over the whole batch
  double target_kl = 0.0;        ///< stop the epochs when a minibatch's approx. KL > 1.5 x this; 0 off
  bool update_obs_normaliser = true;  ///< merge the batch's raw observations after the update

  /// @throws std::invalid_argument "ppo option <field> = <value> must be in <range>".
  void Validate() const;
};

nlohmann::json PpoOptionsToJson(const PpoOptions& o);
/// @throws std::invalid_argument naming `source` and the field.
PpoOptions PpoOptionsFromJson(const nlohmann::json& j, const std::string& source);

/// A flattened, ready-to-train batch.
struct PpoBatch {
  Eigen::MatrixXd obs;               ///< normalised observations, obs_dim x n
  std::vector<int> actions;          ///< n
  std::vector<std::uint8_t> masks;   ///< n x num_actions, row-major (sample i at i * num_actions)
  Eigen::VectorXd old_log_probs;     ///< n
  Eigen::VectorXd advantages;        ///< n (normalised if requested)
  Eigen::VectorXd returns;           ///< n, value targets
  int num_actions = 0;

  int size() const { return static_cast<int>(actions.size()); }
  std::span<const std::uint8_t> mask(int i) const {
    return {masks.data() + static_cast<std::size_t>(i) * static_cast<std::size_t>(num_actions),
            static_cast<std::size_t>(num_actions)};
  }
  /// The samples at `indices`, in that order.
  PpoBatch Select(std::span<const int> indices) const;
};

/// Flattens rollouts: observations normalised with `net`'s normaliser, GAE advantages and returns,
/// optional advantage normalisation.
/// @throws std::invalid_argument when a rollout does not fit the network (obs size, mask size,
///   action outside its mask, non-finite numbers), naming the rollout and step.
PpoBatch MakePpoBatch(const ActorCritic& net, const std::vector<Rollout>& rollouts,
                      const PpoOptions& options);

/// Loss terms of one batch (means over the batch).
struct PpoLossTerms {
  double total = 0.0;          ///< policy + value_coef * value - entropy_coef * entropy
  double policy = 0.0;         ///< -mean(min(r A, clip(r, 1 - eps, 1 + eps) A))
  double value = 0.0;          ///< mean(0.5 (V - R)^2)
  double entropy = 0.0;        ///< mean entropy of the masked categorical
  double approx_kl = 0.0;      ///< mean((r - 1) - log r), r = pi / pi_old
  double clip_fraction = 0.0;  ///< share of samples with |r - 1| > eps
};

/// Gradients of PpoLossTerms::total with respect to the flat parameters.
struct PpoGradients {
  Eigen::VectorXd actor;
  Eigen::VectorXd critic;
};

/// The PPO loss of `net` on `batch`, and its exact gradient when `grads` is not null (manual
/// backpropagation; at the clip kinks the unclipped branch's gradient is used).
PpoLossTerms ComputePpoLoss(const ActorCritic& net, const PpoBatch& batch, const PpoOptions& options,
                            PpoGradients* grads);

/// Adam first / second moments and step count of one parameter vector.
struct AdamState {
  Eigen::VectorXd m;
  Eigen::VectorXd v;
  std::int64_t t = 0;
};

/// One bias-corrected Adam step (Kingma & Ba 2015) on `params`.
void AdamStep(const PpoOptions& options, const Eigen::Ref<const Eigen::VectorXd>& grad,
              Eigen::Ref<Eigen::VectorXd> params, AdamState* state);

/// What one update did.
struct PpoUpdateStats {
  std::int64_t iteration = 0;      ///< iteration number of this update (before incrementing)
  int num_rollouts = 0;
  int num_steps = 0;
  double mean_rollout_return = 0.0;  ///< mean of the rollouts' undiscounted returns
  double mean_step_reward = 0.0;
  PpoLossTerms loss;               ///< averaged over the minibatches of the last epoch
  double explained_variance = 0.0; ///< 1 - Var(R - V_old) / Var(R)
  double grad_norm = 0.0;          ///< mean pre-clip global gradient norm
  int minibatch_updates = 0;
  int epochs_done = 0;
  bool stopped_early = false;      ///< target_kl reached
};

/// PPO trainer: owns the policy being trained and the optimiser state.
class PpoTrainer {
 public:
  /// @throws std::invalid_argument from PpoOptions::Validate().
  PpoTrainer(PolicyFile policy, const PpoOptions& options, std::uint64_t seed);

  /// One iteration: a PPO update on rollouts collected with the current policy. Rollouts with
  /// policy_iteration >= 0 must match iteration() (stale data is refused).
  /// @throws std::invalid_argument for malformed or stale rollouts (nothing is changed then).
  PpoUpdateStats Update(const std::vector<Rollout>& rollouts);

  const PolicyFile& policy() const { return policy_; }
  const ActorCritic& net() const { return policy_.net; }
  std::int64_t iteration() const { return iteration_; }
  const PpoOptions& options() const { return options_; }
  const AdamState& actor_adam() const { return adam_actor_; }
  const AdamState& critic_adam() const { return adam_critic_; }
  const Rng& rng() const { return rng_; }

  /// {"format": "enavi-ppo-checkpoint", "version": 1, "iteration", "rng", "options",
  ///  "policy": <policy file JSON>, "adam": {"actor": {"t", "m", "v"}, "critic": {...}}}
  nlohmann::json CheckpointToJson() const;
  /// @throws std::invalid_argument naming `source` and the field.
  static PpoTrainer FromCheckpointJson(const nlohmann::json& j, const std::string& source);
  /// Atomic write. @throws std::runtime_error on I/O failure.
  void SaveCheckpoint(const std::string& path) const;
  /// @throws std::invalid_argument naming the file (missing, truncated, corrupt).
  static PpoTrainer LoadCheckpoint(const std::string& path);

 private:
  PolicyFile policy_;
  PpoOptions options_;
  Rng rng_;
  AdamState adam_actor_;
  AdamState adam_critic_;
  std::int64_t iteration_ = 0;
};

}  // namespace enavi::navstack::rl
