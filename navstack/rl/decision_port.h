#pragma once
// Decisions of a method taken outside it, one at a time: E-Navi's frequency adapter (the Python
// environment python/env_core.h steps it this way; a discrete action under a mask) and the
// learned navigation method (python/nav_env_core.h; a vector of continuous actions). Attached
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
  /// A continuous decision (opened with OpenContinuous): it takes a vector of `action_size()`.
  bool continuous() const { return action_size_ > 0; }
  int action_size() const { return action_size_; }

  /// The action for the pending decision.
  /// @throws std::logic_error when no decision is pending, std::invalid_argument for an action
  ///   outside the mask (the decision stays pending).
  void Supply(int action);
  /// The action of a pending continuous decision. @throws std::logic_error when none is pending,
  ///   std::invalid_argument for a wrong size or a value that is not finite.
  void Supply(const Eigen::VectorXd& action);

  // The adapter's side.
  /// Leaves a decision pending. @throws std::logic_error while another one is not yet taken.
  void Open(const Eigen::VectorXd& obs, std::span<const std::uint8_t> mask);
  /// The action supplied for the open decision, which closes it.
  /// @throws std::logic_error when none was supplied (the stack went on without it).
  int Take();
  /// Leaves a continuous decision pending. @throws std::logic_error while another one is open.
  void OpenContinuous(const Eigen::VectorXd& obs, int action_size);
  /// The vector supplied for the open continuous decision, which closes it. @throws as Take().
  Eigen::VectorXd TakeVector();

 private:
  enum class State { kIdle, kPending, kSupplied };
  State state_ = State::kIdle;
  Eigen::VectorXd obs_;
  std::vector<std::uint8_t> mask_;
  int action_ = -1;
  int action_size_ = 0;  ///< > 0: a continuous decision
  Eigen::VectorXd action_vector_;
  std::int64_t decisions_ = 0;
};

}  // namespace enavi::navstack::rl
