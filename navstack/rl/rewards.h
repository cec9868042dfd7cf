#pragma once
// Rewards of the frequency adapter (paper Sec. V.C): R = R_c + R_f, computed once per decision
// epoch e (the interval between two adapter decisions, dt seconds long).
//
// Computing-resource reward (paper Eq. framework-r-comput penalises utilisation over capacity):
//   R_c = -w_util * (U / U_total) * dt  -  w_over * max(0, U / U_total - 1) * dt
//   U = U_per + U_plan + U_col + U_dif, the navigation utilisation measured over the epoch (cores).
//   The paper writes R_c = U - U_total and adds it to the reward; read literally that would reward
//   overload, so we negate it, keep the over-capacity part as a steep hinge, and add a mild linear
//   term so that using less CPU is worth something even below capacity (the paper's stated goal:
//   "low CPU utilization"). Both are rates (per second), so the decision frequency does not
//   change how much an episode's CPU costs.
//
// Flight-performance reward (paper Eq. framework-r-fli: target distance, path growth, collision):
//   R_f =  w_progress * (d_{e-1} - d_e) / |Lbar|          progress toward the goal
//        + w_path * clamp(1 - |L_e| / |L_{e-1}|, -1, 1)   paper's w_s term: path growth is negative
//        - w_collision * I_col                            collision (episode ends)
//        + w_goal * I_goal                                goal reached (episode ends)
//        - w_time * dt                                    flight time
//        - w_stop * n_stop                                emergency stops, fail-safe hovers, scans
//   d = distance to the goal, |Lbar| = straight-line start -> goal distance of the episode, and
//   |L_e| = flown length + remaining planned length at epoch e (the expected total path), so a
//   replan that lengthens the route is penalised and one that shortens it is rewarded. The paper's
//   w_a ||P - P_e|| term is a distance penalty; we use its difference between epochs (progress),
//   which telescopes to w_progress * (d_0 - d_T) / |Lbar| over an episode and so does not depend
//   on how many decisions were taken or how long the flight lasted.
//
// Flight performance depends on how the stack uses the board: rates too slow for what is ahead
// cost speed (the reaction constraint's limit), detours (path growth) and emergency stops (a
// check that found the wall late). The stop term counts each stop the epoch began (n_stop); the
// time and path terms see the rest. Progress telescopes, so two successful flights differ in R_f
// only by time, path growth and stops.
//
// Default weights: a goal (+10) and a collision (-20) dominate; a full flight's progress is worth
// +10; CPU costs 2 per second at a fully loaded board (e.g. -7.5 for a 30 s flight using one of
// four cores at 50 %), overload 20 per second per unit over capacity. A second of flight costs
// 0.5, as much as one core of a four-core board busy for that second (w_util / 4), so that a
// second saved in the air is worth a core-second saved on the board; an emergency stop costs 2:
// the seconds it loses (braking, hovering, accelerating again) and the margin it used up.

#include <nlohmann/json.hpp>

namespace enavi::navstack::rl {

/// Reward weights (all >= 0; the signs are fixed by the formulas above). Range [0, 1000] each.
struct RewardWeights {
  double w_util = 2.0;
  double w_over = 20.0;
  double w_progress = 10.0;
  double w_path = 2.0;
  double w_collision = 20.0;
  double w_goal = 10.0;
  double w_time = 0.5;
  double w_stop = 2.0;

  /// @throws std::invalid_argument "reward weight <field> = <v> must be in [0, 1000]".
  void Validate() const;
};

nlohmann::json RewardWeightsToJson(const RewardWeights& w);

/// What happened during one decision epoch.
struct RewardInputs {
  double dt = 0.0;               ///< s, length of the epoch, >= 0
  double u_nav = 0.0;            ///< cores, measured navigation utilisation over the epoch, >= 0
  double u_total = 1.0;          ///< cores, U_total = N, > 0
  double dist_prev = 0.0;        ///< m, distance to goal at the start of the epoch
  double dist = 0.0;             ///< m, distance to goal at the end
  double straight_length = 1.0;  ///< m, |Lbar| of the episode, > 0
  double path_prev = 0.0;        ///< m, |L_{e-1}|; <= 0 when unknown (no path yet): term 0
  double path = 0.0;             ///< m, |L_e|; <= 0 when unknown: term 0
  int stops = 0;                 ///< emergency stops, fail-safe hovers and scans begun in the epoch, >= 0
  bool collided = false;
  bool reached_goal = false;
};

/// Every term, for logging and plots; total = r_c + r_f.
struct RewardTerms {
  double utilisation = 0.0;
  double overload = 0.0;
  double r_c = 0.0;
  double progress = 0.0;
  double path_growth = 0.0;
  double collision = 0.0;
  double goal = 0.0;
  double time = 0.0;
  double stops = 0.0;
  double r_f = 0.0;
  double total = 0.0;
};

/// @throws std::domain_error for NaN or out-of-range inputs (see RewardInputs).
RewardTerms ComputeReward(const RewardInputs& in, const RewardWeights& weights = {});

}  // namespace enavi::navstack::rl
