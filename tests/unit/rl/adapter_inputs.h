#pragma once
// Example inputs of one frequency-adapter decision, shared by its tests and bench_adapt.

#include "navstack/adapt/frequency_constraints.h"
#include "navstack/adapt/policy_state.h"

namespace enavi::navstack::rl::testing {

/// Two busy cores of four, a 4 s trajectory, running (10, 5, 5).
inline ConstraintInputs ExampleBoard() {
  ConstraintInputs c;
  c.f_sen = 30;
  c.trajectory_duration = 4.0;
  c.wcet = {0.03, 0.2, 0.01, 0.004};
  c.num_cores = 4;
  c.u_cur = 2.0;
  c.current = {10, 5, 5};
  return c;
}

/// Cruising at 1 m/s towards a goal 20 m ahead, eci 0.5, on a 0.2 m map.
inline FlightContext ExampleFlight() {
  FlightContext f;
  f.eci = 0.5;
  f.d_eci = 0.02;
  f.resolution = 0.2;
  f.v_WB = {1, 0, 0};
  f.p_goal_W = {20, 0, 1};
  return f;
}

}  // namespace enavi::navstack::rl::testing
