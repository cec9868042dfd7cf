#pragma once
// Reaction constraint (ours, next to the paper's C1-C4): the task periods must let the vehicle
// stop before the nearest obstacle it sees, and a speed limit for when no period can.
//
// C1-C4 bound the task rates by the trajectory length and the CPU; nothing in them ties the map
// and check periods to how close the nearest obstacle is. An obstacle that comes into view
// (round a building corner, say) is acted on only after
//
//   T_react(f) = 1/f_sen            the frame that shows it is captured,
//              + 1/f_per + C_per    the next map update has released and finished,
//              + 1/f_col + C_col    the next collision check has released and finished,
//              + C_plan             the replan it triggers has landed or failed,
//
// and from then an emergency stop at deceleration a needs v/a s and v^2/(2a) m. Flying on at
// the current speed v, the vehicle stops in time when
//
//   v T_react + v^2 / (2 a) <= d0 - margin                                     (1)
//
// with d0 the range of the nearest obstacle ahead and margin what the body needs (its radius,
// plus half a map cell: on a coarse map an obstacle may be that much nearer than its cell says).
// In the paper's own time, t0 = 2 d0 / v (Eq. eci-d0, the time to stop over d0 at constant
// deceleration), (1) times 2/v reads
//
//   2 T_react + v / a <= t0 - 2 margin / v,                                    (2)
//
// which is what CheckReaction compares.
//
// Which d0: the eci's own d0 is the nearest return anywhere in the view. In a street canyon that
// is a side wall the vehicle flies past, and at 1.5 m altitude the ground; with it, (2) masked
// the slow rates all along the street and the speed limit held the vehicle back (canyon, 5
// boards: E-Navi's CPU +50 %, flight time +10 %) for walls it was never going to reach. The
// stack passes EciResult::d_ahead instead: a lower bound of the nearest return in the eci's
// centre zone, the one aligned with the velocity (about 29 x 19 deg on the farm's camera).
// Blind, like the eci, to what the camera does not see.

#include <limits>

#include "navstack/adapt/action_grid.h"

namespace enavi::navstack {

struct TaskWcets;  // frequency_constraints.h

/// What the reaction constraint looks at, apart from the candidate rates.
struct ReactionInputs {
  /// d0, m: range of the nearest obstacle ahead in the latest depth frame (the stack passes
  /// EciResult::d_ahead). +infinity (the default) when not measured: the constraint then holds
  /// for every candidate.
  double d0 = std::numeric_limits<double>::infinity();
  double speed = 0.0;    ///< v, m/s: the vehicle's speed
  double a_brake = 3.0;  ///< a, m/s^2: deceleration of an emergency stop (the planner's a_max)
  double margin = 0.3;   ///< m: robot radius + half a map cell
};

/// The two sides of (2) for one candidate.
struct ReactionStatus {
  bool holds = true;
  double t_react = 0.0;   ///< T_react, s
  double lhs = 0.0;       ///< 2 T_react + v / a, s
  double budget = std::numeric_limits<double>::infinity();  ///< t0 - 2 margin / v, s
};

/// T_react of `f` (see the header comment); +infinity when f_per or f_col is 0 (never checked).
double ReactionTime(const TaskFrequencies& f, const TaskWcets& wcet, double f_sen);

/// Checks (2). Holds when the vehicle is (nearly) still: below 1 cm/s there is nothing to stop.
/// @throws std::domain_error when d0 is NaN or <= 0, speed or margin NaN or negative, a_brake <= 0.
ReactionStatus CheckReaction(const ReactionInputs& in, const TaskFrequencies& f, const TaskWcets& wcet,
                             double f_sen);

/// The largest speed v for which (1) holds with reaction time `t_react`:
/// v = a (sqrt(T^2 + 2 (d0 - margin) / a) - T), 0 when d0 <= margin; +infinity when d0 is.
double SafeSpeed(double d0, double margin, double a_brake, double t_react);

}  // namespace enavi::navstack
