#include "navstack/rl/decision_port.h"

#include <stdexcept>
#include <string>

namespace enavi::navstack::rl {

void DecisionPort::Supply(int action) {
  if (state_ != State::kPending) throw std::logic_error("decision port: no decision waits for an action");
  if (continuous()) throw std::invalid_argument("the decision takes a vector of " + std::to_string(action_size_) + " values");
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
  action_size_ = 0;
  state_ = State::kPending;
  ++decisions_;
}

void DecisionPort::Supply(const Eigen::VectorXd& action) {
  if (state_ != State::kPending) throw std::logic_error("decision port: no decision waits for an action");
  if (!continuous()) throw std::invalid_argument("the decision takes one action index (see the decision's mask)");
  if (action.size() != action_size_)
    throw std::invalid_argument("action: expected " + std::to_string(action_size_) + " values, got " + std::to_string(action.size()));
  if (!action.allFinite()) throw std::invalid_argument("action: every value must be finite");
  action_vector_ = action;
  state_ = State::kSupplied;
}

void DecisionPort::OpenContinuous(const Eigen::VectorXd& obs, int action_size) {
  Open(obs, {});
  action_size_ = action_size;
}

Eigen::VectorXd DecisionPort::TakeVector() {
  if (!continuous()) throw std::logic_error("decision port: a discrete decision is taken with Take()");
  if (state_ != State::kSupplied) throw std::logic_error("decision port: the method went on without the decision's action");
  state_ = State::kIdle;
  return action_vector_;
}

int DecisionPort::Take() {
  if (continuous()) throw std::logic_error("decision port: a continuous decision is taken with TakeVector()");
  if (state_ != State::kSupplied) throw std::logic_error("decision port: the stack went on without the decision's action");
  state_ = State::kIdle;
  return action_;
}

}  // namespace enavi::navstack::rl
