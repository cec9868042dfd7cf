#pragma once
// Decisions taken outside the stack: the Python environment (python/) steps E-Navi's frequency
// adaptation one decision at a time. While a hook is installed on a thread, the frequency adapter
// on that thread asks it for each sampled decision's action (among the feasible mask) and the
// strategy controller reports each action's reward to it. Thread-local, so episodes on other
// threads (and every production flight) never see it.

#include <cstdint>
#include <span>

#include <Eigen/Core>

namespace enavi::navstack::rl {

class DecisionHook {
 public:
  virtual ~DecisionHook() = default;
  /// The action for this decision. @return an index with mask[index] != 0.
  virtual int Choose(const Eigen::VectorXd& obs, std::span<const std::uint8_t> mask) = 0;
  /// The reward of the previous action, known at the next decision or at the episode's end.
  virtual void Reward(double reward) = 0;
};

/// The hook installed on this thread, or null.
DecisionHook* CurrentDecisionHook();

/// Installs `hook` on this thread for its lifetime.
class ScopedDecisionHook {
 public:
  explicit ScopedDecisionHook(DecisionHook* hook);
  ~ScopedDecisionHook();
  ScopedDecisionHook(const ScopedDecisionHook&) = delete;
  ScopedDecisionHook& operator=(const ScopedDecisionHook&) = delete;

 private:
  DecisionHook* previous_;
};

}  // namespace enavi::navstack::rl
