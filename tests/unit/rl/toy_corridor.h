#pragma once
// Test environment: a corridor of cells 0..6, start in the middle, the goal at one end chosen per
// episode and shown in the observation. The best action depends on the observation (left or
// right); moves off the corridor are masked. Reward -0.1 per step, +1 on reaching the goal
// (terminal); a time-out after max_steps is not a terminal.
//
//   cell:   0   1   2   3   4   5   6
//           G?          S           G?

#include <cmath>
#include <cstdint>

#include "navstack/rl/environment.h"

namespace enavi::navstack::rl::testing {

class ToyCorridor : public Environment {
 public:
  static constexpr int kCells = 7;
  enum Action { kLeft = 0, kRight = 1, kStay = 2, kJumpHome = 3 };

  int obs_dim() const override { return 4; }
  int num_actions() const override { return 4; }

  void Reset(std::uint64_t seed) override {
    Rng rng(seed);
    goal_right_ = rng.Uniform01() < 0.5;
    x_ = 3;
  }

  // obs: position in [-1, 1], goal side (+1 right, -1 left), distance to goal / 6, bias.
  void Observe(Eigen::Ref<Eigen::VectorXd> obs, std::span<std::uint8_t> mask) const override {
    const int goal = goal_right_ ? kCells - 1 : 0;
    obs << (x_ - 3) / 3.0, goal_right_ ? 1.0 : -1.0, std::abs(goal - x_) / 6.0, 1.0;
    mask[kLeft] = x_ > 0;
    mask[kRight] = x_ < kCells - 1;
    mask[kStay] = 1;
    mask[kJumpHome] = 0;  // never allowed: a permanently masked action
  }

  StepResult Step(int action) override {
    if (action == kLeft) --x_;
    if (action == kRight) ++x_;
    const int goal = goal_right_ ? kCells - 1 : 0;
    StepResult r;
    r.reward = -0.1;
    if (x_ == goal) {
      r.reward += 1.0;
      r.terminated = true;
    }
    return r;
  }

 private:
  bool goal_right_ = true;
  int x_ = 3;
};

}  // namespace enavi::navstack::rl::testing
