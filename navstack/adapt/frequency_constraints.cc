#include "navstack/adapt/frequency_constraints.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "navstack/common/argument_check.h"

namespace enavi::navstack {
namespace {

constexpr ArgumentCheck kCheck("frequency constraints");

void ValidateFrequencies(const TaskFrequencies& f, const char* name) {
  const std::string n(name);
  kCheck.NonNegative(f.f_per, (n + ".f_per").c_str());
  kCheck.NonNegative(f.f_col, (n + ".f_col").c_str());
  kCheck.NonNegative(f.f_dif, (n + ".f_dif").c_str());
}

void Validate(const ConstraintInputs& in, const ConstraintOptions& opt) {
  if (!(in.f_sen > 0.0) || std::isinf(in.f_sen)) {
    throw std::domain_error("frequency constraints: f_sen must be finite and > 0");
  }
  if (!(in.trajectory_duration > 0.0)) {
    throw std::domain_error("frequency constraints: trajectory_duration (C_L) = " +
                            std::to_string(in.trajectory_duration) +
                            " must be > 0 (+infinity when there is no trajectory)");
  }
  kCheck.NonNegative(in.wcet.per, "wcet.per");
  kCheck.NonNegative(in.wcet.plan, "wcet.plan");
  kCheck.NonNegative(in.wcet.col, "wcet.col");
  kCheck.NonNegative(in.wcet.dif, "wcet.dif");
  if (in.num_cores < 1) throw std::domain_error("frequency constraints: num_cores must be >= 1");
  kCheck.NonNegative(in.u_cur, "u_cur");
  ValidateFrequencies(in.current, "current");
  if (!(opt.capacity_fraction > 0.0 && opt.capacity_fraction <= 1.0)) {
    throw std::domain_error("frequency constraints: capacity_fraction must be in (0, 1]");
  }
  kCheck.NonNegative(opt.tolerance, "tolerance");
  // The reaction inputs are validated by CheckReaction; check them once here for the grid loop.
  (void)CheckReaction(in.reaction, in.current, in.wcet, in.f_sen);
}

double UTotal(const ConstraintInputs& in, const ConstraintOptions& opt) {
  return opt.capacity_fraction * static_cast<double>(in.num_cores);
}

// C1's lower bound and C3's planning term: both vanish without a trajectory (C_L = +inf).
double PerceptionFloor(const ConstraintInputs& in) {
  return std::isinf(in.trajectory_duration) ? 0.0 : 1.0 / in.trajectory_duration;
}
double PlanningLoad(const ConstraintInputs& in) {
  return std::isinf(in.trajectory_duration) ? 0.0 : in.wcet.plan / in.trajectory_duration;
}

double ScalableLoad(const TaskFrequencies& f, const TaskWcets& c) {
  return f.f_per * c.per + f.f_col * c.col + f.f_dif * c.dif;
}

// The check without validation, for the grid loop (inputs validated once).
ConstraintStatus CheckUnchecked(const ConstraintInputs& in, const TaskFrequencies& f,
                                const ConstraintOptions& opt, double f_per_min, double u_total) {
  const double tol = opt.tolerance;
  ConstraintStatus s;
  s.f_per_min = f_per_min;
  s.u_total = u_total;
  // C1: perceive at least once per trajectory, never faster than the sensor.
  s.holds[0] = f.f_per + tol >= f_per_min && f.f_per <= in.f_sen + tol;
  // C2: collision checks need a fresh map; difference detection needs a fresh frame.
  s.holds[1] = f.f_col >= 0.0 && f.f_col <= f.f_per + tol && f.f_dif >= 0.0 &&
               f.f_dif <= in.f_sen + tol;
  // C3: execution time within the flight-time budget C_L x N, divided by C_L.
  s.c3_load = ScalableLoad(f, in.wcet) + PlanningLoad(in);
  s.holds[2] = s.c3_load <= u_total + tol;
  // C4: measured utilisation plus the change this reconfiguration causes.
  s.u_after = in.u_cur + (f.f_per - in.current.f_per) * in.wcet.per +
              (f.f_col - in.current.f_col) * in.wcet.col +
              (f.f_dif - in.current.f_dif) * in.wcet.dif;
  s.holds[3] = s.u_after <= u_total + tol;
  s.reaction = CheckReaction(in.reaction, f, in.wcet, in.f_sen);
  return s;
}

}  // namespace

ConstraintStatus CheckConstraints(const ConstraintInputs& inputs, const TaskFrequencies& candidate,
                                  const ConstraintOptions& options) {
  Validate(inputs, options);
  ValidateFrequencies(candidate, "candidate");
  return CheckUnchecked(inputs, candidate, options, PerceptionFloor(inputs), UTotal(inputs, options));
}

FeasibleSet ComputeFeasibleSet(const ActionGrid& grid, const ConstraintInputs& inputs,
                               const ConstraintOptions& options) {
  Validate(inputs, options);
  const double f_per_min = PerceptionFloor(inputs);
  const double u_total = UTotal(inputs, options);

  FeasibleSet out;
  out.mask.assign(static_cast<std::size_t>(grid.size()), 0);
  // Fallback candidates tracked in the same pass: cheapest structurally valid that reacts in
  // time, quickest structurally valid, cheapest overall.
  int best_safe = -1, best_quick = -1, best_any = -1;
  double cost_safe = std::numeric_limits<double>::infinity();
  double cost_any = std::numeric_limits<double>::infinity();
  double quickest = std::numeric_limits<double>::infinity(), cost_quick = cost_any;
  double cost_feasible = std::numeric_limits<double>::infinity();
  bool any_reacts = false;
  for (int i = 0; i < grid.size(); ++i) {
    const ConstraintStatus s = CheckUnchecked(inputs, grid.At(i), options, f_per_min, u_total);
    any_reacts = any_reacts || s.reaction.holds;
    if (s.AllHold()) {
      out.mask[static_cast<std::size_t>(i)] = 1;
      ++out.num_feasible;
      if (s.c3_load < cost_feasible) {
        cost_feasible = s.c3_load;
        out.least_load_action = i;
      }
    }
    if (s.c3_load < cost_any) {
      cost_any = s.c3_load;
      best_any = i;
    }
    if (!s.holds[0] || !s.holds[1]) continue;
    if (s.reaction.holds && s.c3_load < cost_safe) {
      cost_safe = s.c3_load;
      best_safe = i;
    }
    const double t = s.reaction.t_react;
    if (t < quickest - options.tolerance || (t <= quickest + options.tolerance && s.c3_load < cost_quick)) {
      quickest = t;
      cost_quick = s.c3_load;
      best_quick = i;
    }
  }
  out.reaction_infeasible = !any_reacts;
  if (out.num_feasible == 0) {
    out.fallback_used = true;
    out.fallback_action = best_safe >= 0 ? best_safe : (best_quick >= 0 ? best_quick : best_any);
    out.mask[static_cast<std::size_t>(out.fallback_action)] = 1;
    out.least_load_action = out.fallback_action;
  }
  return out;
}

ScaledFrequencies ScaleToCapacity(const ConstraintInputs& inputs, const ConstraintOptions& options) {
  Validate(inputs, options);
  const double u_total = UTotal(inputs, options);
  const TaskFrequencies& cur = inputs.current;
  ScaledFrequencies out;
  out.f = cur;
  out.u_predicted = inputs.u_cur;
  const double u_s = ScalableLoad(cur, inputs.wcet);
  if (inputs.u_cur <= u_total + options.tolerance || u_s <= 0.0) return out;

  // Remove the excess from the scalable load (planning is triggered, not periodic).
  const double k = std::clamp(1.0 - (inputs.u_cur - u_total) / u_s, 0.0, 1.0);
  const double f_per_min = PerceptionFloor(inputs);
  double f_per = k * cur.f_per;
  double k_rest = k;
  if (f_per < f_per_min && cur.f_per > f_per) {
    // Hold perception at C1's floor (never raise it) and take the difference from col / dif.
    const double floored = std::min(cur.f_per, f_per_min);
    const double extra = (floored - f_per) * inputs.wcet.per;
    const double rest = cur.f_col * inputs.wcet.col + cur.f_dif * inputs.wcet.dif;
    k_rest = rest > 0.0 ? std::max(0.0, (k * rest - extra) / rest) : 0.0;
    k_rest = std::min(k_rest, k);
    f_per = floored;
    out.f_per_floored = true;
  }
  out.f = {f_per, k_rest * cur.f_col, k_rest * cur.f_dif};
  out.scale = k_rest;
  out.scaled = true;
  out.u_predicted = inputs.u_cur - (u_s - ScalableLoad(out.f, inputs.wcet));
  return out;
}

OverloadMonitor::OverloadMonitor(const OverloadMonitorOptions& options) : options_(options) {
  const auto bad = [](const std::string& field, const std::string& range) {
    throw std::invalid_argument("overload monitor: " + field + " must be in " + range);
  };
  if (!(options.overload_fraction > 0.0 && options.overload_fraction <= 2.0)) {
    bad("overload_fraction", "(0, 2]");
  }
  if (!(options.max_overload_duration >= 0.0) || std::isinf(options.max_overload_duration)) {
    bad("max_overload_duration", "[0, inf)");
  }
  if (options.max_consecutive_overloaded < 0) bad("max_consecutive_overloaded", "[0, inf)");
  if (options.max_overload_duration <= 0.0 && options.max_consecutive_overloaded == 0) {
    throw std::invalid_argument(
        "overload monitor: max_overload_duration and max_consecutive_overloaded are both disabled; "
        "enable at least one");
  }
  if (!(options.recovery_fraction > 0.0 && options.recovery_fraction <= options.overload_fraction)) {
    bad("recovery_fraction", "(0, overload_fraction]");
  }
  if (!(options.recovery_duration >= 0.0) || std::isinf(options.recovery_duration)) {
    bad("recovery_duration", "[0, inf)");
  }
}

void OverloadMonitor::Reset() {
  mode_ = Mode::kNominal;
  has_last_ = false;
  last_t_ = -1.0;
  consecutive_ = 0;
  recovering_ = false;
}

OverloadMonitor::Update OverloadMonitor::Observe(double t, double u_cur, double u_total) {
  if (std::isnan(t) || std::isnan(u_cur) || !(u_total > 0.0) || u_cur < 0.0) {
    throw std::domain_error("overload monitor: t, u_cur must be numbers, u_cur >= 0, u_total > 0");
  }
  if (has_last_ && t < last_t_) {
    throw std::domain_error("overload monitor: time went backwards (" + std::to_string(t) + " < " +
                            std::to_string(last_t_) + ")");
  }
  has_last_ = true;
  last_t_ = t;
  // Sim times are sums of periods: allow rounding when comparing against a duration.
  constexpr double kTimeSlack = 1e-9;

  Update up;
  up.overloaded = u_cur > options_.overload_fraction * u_total;
  if (up.overloaded) {
    if (consecutive_ == 0) overload_since_ = t;
    ++consecutive_;
  } else {
    consecutive_ = 0;
  }
  up.consecutive_overloaded = consecutive_;
  up.overload_duration = consecutive_ > 0 ? t - overload_since_ : 0.0;

  if (mode_ == Mode::kFailSafe) {
    // Leave the hover only after utilisation has stayed clearly below capacity for a while.
    if (u_cur <= options_.recovery_fraction * u_total) {
      if (!recovering_) {
        recovering_ = true;
        recovery_since_ = t;
      }
      if (t - recovery_since_ + kTimeSlack >= options_.recovery_duration) {
        mode_ = Mode::kNominal;
        recovering_ = false;
        consecutive_ = 0;
        up.recovered = true;
      }
    } else {
      recovering_ = false;
    }
  } else if (up.overloaded) {
    const bool too_long = options_.max_overload_duration > 0.0 &&
                          up.overload_duration + kTimeSlack >= options_.max_overload_duration;
    const bool too_many = options_.max_consecutive_overloaded > 0 &&
                          consecutive_ >= options_.max_consecutive_overloaded;
    if (too_long || too_many) {
      mode_ = Mode::kFailSafe;
      recovering_ = false;
      up.entered_failsafe = true;
    } else {
      mode_ = Mode::kOverloaded;
    }
  } else {
    mode_ = Mode::kNominal;
  }
  up.mode = mode_;
  return up;
}

const char* ToString(OverloadMonitor::Mode mode) {
  switch (mode) {
    case OverloadMonitor::Mode::kNominal: return "nominal";
    case OverloadMonitor::Mode::kOverloaded: return "overloaded";
    case OverloadMonitor::Mode::kFailSafe: return "failsafe";
  }
  return "unknown";
}

}  // namespace enavi::navstack
