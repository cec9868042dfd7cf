#pragma once
// Observation of the frequency adapter policy (paper Sec. V.C "Implementation": eci, |d eci|,
// constraint status, task frequencies, UAV motion, workload utilisation, target).
//
// Feature vector (kPolicyStateDim = 16), every entry bounded, most in [0, 1]:
//   0  eci            eci as computed (already normalised to [0, 1], docs/design.md, "Our reading of the paper")
//   1  abs_d_eci      tanh(|d eci| / d_eci_scale): per-frame change, squashed to [0, 1)
//   2  c1_holds       1 if C1 holds for the running configuration, else 0
//   3  c2_holds       same for C2
//   4  c3_holds       same for C3
//   5  c4_holds       same for C4
//   6  f_per          running f_per / f_sen, [0, 1] while C1 holds (clamped to [0, 2])
//   7  f_col          running f_col / f_sen, same range
//   8  f_dif          running f_dif / f_sen, same range
//   9  resolution     map resolution / resolution_ref, (0, 1] for the default ladder
//  10  speed          |v_WB| / speed_ref, clamped to [0, 2]
//  11  utilisation    U_cur / U_total, clamped to [0, 2] (> 1 = overload)
//  12  goal_dir_x     unit vector to the goal in the heading frame H (yaw-only body frame:
//  13  goal_dir_y       x forward, y left, z up; roll and pitch removed so attitude jitter of the
//  14  goal_dir_z       quadrotor does not move the feature); zero vector when at the goal
//  15  goal_distance  d / (d + distance_ref), [0, 1): squashed so far goals do not dominate
//
// The policy file stores the feature names; a policy trained on another layout is refused.

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/adapt/action_grid.h"

namespace enavi::navstack {

inline constexpr int kPolicyStateDim = 16;

/// Names of the features, in order (stored in the policy file).
const std::vector<std::string>& PolicyStateFeatureNames();

/// Everything the observation is built from, plain values.
struct PolicyStateInputs {
  double eci = 0.0;
  double d_eci = 0.0;                    ///< eci(t) - eci(t - 1 frame); the sign is dropped
  std::array<bool, 4> constraints_hold{};///< ConstraintStatus::holds of the running configuration
  TaskFrequencies current;               ///< running frequencies, Hz
  double f_sen = 30.0;                   ///< Hz, > 0
  double resolution = 0.1;               ///< current map resolution, m
  double u_cur = 0.0;                    ///< cores
  double u_total = 1.0;                  ///< cores, > 0
  Eigen::Vector3d p_WB = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_WB = Eigen::Vector3d::Zero();   ///< expressed in W
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_goal_W = Eigen::Vector3d::Zero();
};

/// Normalisation scales (named, with ranges; all > 0).
struct PolicyStateOptions {
  double d_eci_scale = 0.1;     ///< |d eci| giving tanh(1) = 0.76
  double speed_ref = 3.0;       ///< m/s mapped to 1
  double resolution_ref = 0.5;  ///< m mapped to 1 (coarsest default ladder level)
  double distance_ref = 10.0;   ///< m giving 0.5
};

/// Writes the 16 features into `out`, no allocation.
/// @pre out.size() == kPolicyStateDim.
/// @throws std::domain_error when an input is NaN or f_sen, u_total, resolution <= 0, or an
///   option is not > 0.
void BuildPolicyState(const PolicyStateInputs& in, const PolicyStateOptions& options,
                      Eigen::Ref<Eigen::VectorXd> out);

/// Allocating convenience form.
Eigen::VectorXd BuildPolicyState(const PolicyStateInputs& in, const PolicyStateOptions& options = {});

}  // namespace enavi::navstack
