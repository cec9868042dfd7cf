#include "navstack/adapt/reaction_constraint.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "navstack/adapt/frequency_constraints.h"

namespace enavi::navstack {
namespace {

constexpr double kStill = 0.01;  // m/s: below this there is no motion to stop

void Validate(const ReactionInputs& in) {
  if (std::isnan(in.d0) || !(in.d0 > 0.0)) {
    throw std::domain_error("reaction constraint: d0 = " + std::to_string(in.d0) + " must be > 0");
  }
  if (!(in.speed >= 0.0) || std::isinf(in.speed)) {
    throw std::domain_error("reaction constraint: speed must be finite and >= 0");
  }
  if (!(in.a_brake > 0.0) || std::isinf(in.a_brake)) {
    throw std::domain_error("reaction constraint: a_brake must be finite and > 0");
  }
  if (!(in.margin >= 0.0) || std::isinf(in.margin)) {
    throw std::domain_error("reaction constraint: margin must be finite and >= 0");
  }
}

}  // namespace

double ReactionTime(const TaskFrequencies& f, const TaskWcets& wcet, double f_sen) {
  if (!(f.f_per > 0.0) || !(f.f_col > 0.0)) return std::numeric_limits<double>::infinity();
  return 1.0 / f_sen + 1.0 / f.f_per + wcet.per + 1.0 / f.f_col + wcet.col + wcet.plan;
}

ReactionStatus CheckReaction(const ReactionInputs& in, const TaskFrequencies& f, const TaskWcets& wcet,
                             double f_sen) {
  Validate(in);
  ReactionStatus s;
  s.t_react = ReactionTime(f, wcet, f_sen);
  if (in.speed < kStill || std::isinf(in.d0)) return s;
  // (2): 2 T_react + v / a <= 2 (d0 - margin) / v.
  s.lhs = 2.0 * s.t_react + in.speed / in.a_brake;
  s.budget = 2.0 * (in.d0 - in.margin) / in.speed;
  s.holds = s.lhs <= s.budget;
  return s;
}

double SafeSpeed(double d0, double margin, double a_brake, double t_react) {
  if (std::isinf(d0)) return std::numeric_limits<double>::infinity();
  const double d = d0 - margin;
  if (!(d > 0.0) || std::isinf(t_react)) return 0.0;
  // Positive root of v^2 / (2a) + T v - d = 0.
  return a_brake * (std::sqrt(t_react * t_react + 2.0 * d / a_brake) - t_react);
}

}  // namespace enavi::navstack
