#pragma once
// Rollouts: what a worker sends to the trainer. One Rollout is one segment of experience collected
// with one policy version, usually one whole episode. Two forms: JSON (files, tests) and a compact
// binary form the farm ships over DDS and stores.

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

namespace enavi::navstack::rl {

/// One decision and its consequence.
struct RolloutStep {
  Eigen::VectorXd obs;             ///< raw observation (the policy normalises it itself)
  int action = -1;
  std::vector<std::uint8_t> mask;  ///< feasible actions at this step (1 = allowed)
  double log_prob = 0.0;           ///< log pi_old(action | obs) under the mask, at collection
  double value = 0.0;              ///< V_old(obs) at collection
  double reward = 0.0;             ///< reward received after the action
  /// The episode terminated after this step (goal, collision: a true terminal, value 0 beyond).
  /// Time-outs are not terminals: end the segment there and set bootstrap_value instead.
  bool done = false;
};

/// A segment of consecutive steps. Terminals may occur inside (GAE restarts after them).
struct Rollout {
  std::vector<RolloutStep> steps;
  /// V(s_T) of the observation after the last step, used when the last step is not done
  /// (time-out or a segment cut short); ignored otherwise.
  double bootstrap_value = 0.0;
  /// Trainer iteration of the policy that collected it (-1: not checked by the trainer).
  std::int64_t policy_iteration = -1;
  std::string id;                         ///< e.g. episode id, for logs
  std::map<std::string, double> info;     ///< episode metrics (success, flight time, ...)

  double Return() const;  ///< undiscounted sum of rewards
};

/// Generalised advantage estimation (Schulman et al. 2016) over one rollout:
/// delta_t = r_t + gamma V(s_{t+1}) (1 - done_t) - V(s_t); A_t = delta_t + gamma lambda (1 - done_t) A_{t+1};
/// returns R_t = A_t + V(s_t). V(s_T) after the last step is bootstrap_value (0 if it is done).
/// @pre advantages.size() == returns.size() == rollout.steps.size().
void ComputeGae(const Rollout& rollout, double gamma, double lambda,
                Eigen::Ref<Eigen::VectorXd> advantages, Eigen::Ref<Eigen::VectorXd> returns);

/// JSON form: {"format": "enavi-rollout", "version": 1, "obs_dim", "num_actions", "id",
/// "policy_iteration", "bootstrap_value", "info": {..}, "steps": [{"obs": [..], "action",
/// "mask": "0110..", "log_prob", "value", "reward", "done"}]}. Doubles round-trip exactly.
nlohmann::json RolloutToJson(const Rollout& rollout);
/// @throws std::invalid_argument naming `source` and the field on any malformed, inconsistent
///   (shape, action outside the mask) or non-finite content.
Rollout RolloutFromJson(const nlohmann::json& j, const std::string& source);

/// Text forms of the above (compact JSON).
std::string SerializeRollout(const Rollout& rollout);
Rollout DeserializeRollout(const std::string& text, const std::string& source);

/// Binary form (little-endian): "ENR1", u32 obs_dim, u32 num_actions, u32 steps, f64
/// bootstrap_value, i64 policy_iteration, u32 + id bytes, u32 info count + (u32 + key, f64) each;
/// then per step obs (obs_dim f64), i32 action, mask (ceil(num_actions / 8) bytes, bit i of byte
/// i / 8 = action i), f64 log_prob, value, reward, u8 done. Doubles are exact; 170 bytes a step
/// for E-Navi (16 features, 98 actions) against ~450 bytes of JSON.
std::string EncodeRollout(const Rollout& rollout);
/// @throws std::invalid_argument naming `source` on a truncated, oversized or inconsistent blob
///   (the same checks as RolloutFromJson).
Rollout DecodeRollout(std::string_view bytes, const std::string& source);

}  // namespace enavi::navstack::rl
