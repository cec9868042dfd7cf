#include "navstack/rl/decision_port.h"

#include <stdexcept>
#include <string>

namespace enavi::navstack::rl {

void DecisionPort::Supply(int action) {
  if (state_ != State::kPending) throw std::logic_error("decision port: no decision waits for an action");
  if (action < 0 || action >= static_cast<int>(mask_.size()) || !mask_[static_cast<std::size_t>(action)])
    throw std::invalid_argument("action " + std::to_string(action) + " is not feasible (see the decision's mask)");
  action_ = action;
  state_ = State::kSupplied;
}

void DecisionPort::Open(const Eigen::VectorXd& obs, std::span<const std::uint8_t> mask) {
  if (state_ != State::kIdle) throw std::logic_error("decision port: a decision is still open");
  obs_ = obs;
  mask_.assign(mask.begin(), mask.end());
  action_ = -1;
  state_ = State::kPending;
  ++decisions_;
}

int DecisionPort::Take() {
  if (state_ != State::kSupplied) throw std::logic_error("decision port: the stack went on without the decision's action");
  state_ = State::kIdle;
  return action_;
}

}  // namespace enavi::navstack::rl
