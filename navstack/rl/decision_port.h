#pragma once
// Decisions of the frequency adapter taken outside the stack, one at a time (the Python
// environment, python/env_core.h, steps E-Navi's frequency adaptation this way). Attached
// explicitly to one stack (StrategyOptions::decisions); with it, each sampled decision is left
// pending here: the adapter job's code has run as it would have (its work, the network's own
// sample, the rollout's numbers), the virtual executor stops at that instant before the job's
// commit (JobOutput::awaits_decision), and the commit takes the action supplied meanwhile. An
// episode given the same actions so flies exactly as if each had been chosen at once.

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace enavi::navstack::rl {

class DecisionPort {
 public:
  /// A decision waits for its action.
  bool pending() const { return state_ == State::kPending; }
  /// Its observation (the policy state) and feasible-action mask. @pre pending().
  const Eigen::VectorXd& observation() const { return obs_; }
  const std::vector<std::uint8_t>& mask() const { return mask_; }
  /// Decisions left pending so far (the index of the next one).
  std::int64_t decisions() const { return decisions_; }

  /// The action for the pending decision.
  /// @throws std::logic_error when no decision is pending, std::invalid_argument for an action
  ///   outside the mask (the decision stays pending).
  void Supply(int action);

  // The adapter's side.
  /// Leaves a decision pending. @throws std::logic_error while another one is not yet taken.
  void Open(const Eigen::VectorXd& obs, std::span<const std::uint8_t> mask);
  /// The action supplied for the open decision, which closes it.
  /// @throws std::logic_error when none was supplied (the stack went on without it).
  int Take();

 private:
  enum class State { kIdle, kPending, kSupplied };
  State state_ = State::kIdle;
  Eigen::VectorXd obs_;
  std::vector<std::uint8_t> mask_;
  int action_ = -1;
  std::int64_t decisions_ = 0;
};

}  // namespace enavi::navstack::rl
