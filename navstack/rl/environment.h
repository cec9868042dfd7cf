#pragma once
// A minimal environment interface and an episode collector, for in-process training (tests, small
// tasks). The farm does not need it: its workers build Rollouts themselves from flight episodes.

#include <cstdint>
#include <span>

#include <Eigen/Core>

#include "navstack/rl/policy.h"
#include "navstack/rl/rollout.h"

namespace enavi::navstack::rl {

class Environment {
 public:
  virtual ~Environment() = default;
  virtual int obs_dim() const = 0;
  virtual int num_actions() const = 0;
  /// Starts an episode; everything random in it derives from `seed`.
  virtual void Reset(std::uint64_t seed) = 0;
  /// The current observation and feasible-action mask (at least one entry non-zero).
  virtual void Observe(Eigen::Ref<Eigen::VectorXd> obs, std::span<std::uint8_t> mask) const = 0;

  struct StepResult {
    double reward = 0.0;
    bool terminated = false;  ///< true terminal (no value beyond)
  };
  virtual StepResult Step(int action) = 0;
};

/// Runs one episode of at most `max_steps` decisions with `net` (sampling actions with an RNG
/// seeded from `seed`, or greedy). A time-out bootstraps with V of the last observation.
Rollout CollectEpisode(Environment* env, const ActorCritic& net, std::uint64_t seed, ActMode mode,
                       int max_steps, std::int64_t policy_iteration = -1);

}  // namespace enavi::navstack::rl
