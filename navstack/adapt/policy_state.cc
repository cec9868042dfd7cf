#include "navstack/adapt/policy_state.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace enavi::navstack {

const std::vector<std::string>& PolicyStateFeatureNames() {
  static const std::vector<std::string> names = {
      "eci",         "abs_d_eci", "c1_holds",   "c2_holds",   "c3_holds",   "c4_holds",
      "f_per",       "f_col",     "f_dif",      "resolution", "speed",      "utilisation",
      "goal_dir_x",  "goal_dir_y", "goal_dir_z", "goal_distance"};
  return names;
}

void BuildPolicyState(const PolicyStateInputs& in, const PolicyStateOptions& options,
                      Eigen::Ref<Eigen::VectorXd> out) {
  if (out.size() != kPolicyStateDim) {
    throw std::logic_error("BuildPolicyState: output has size " + std::to_string(out.size()) +
                           ", expected " + std::to_string(kPolicyStateDim));
  }
  const bool numbers_ok = !std::isnan(in.eci) && !std::isnan(in.d_eci) && in.f_sen > 0.0 &&
                          in.resolution > 0.0 && in.u_total > 0.0 && !std::isnan(in.u_cur) &&
                          !std::isnan(in.current.f_per) && !std::isnan(in.current.f_col) &&
                          !std::isnan(in.current.f_dif) && in.p_WB.allFinite() &&
                          in.v_WB.allFinite() && in.p_goal_W.allFinite() &&
                          in.q_WB.coeffs().allFinite();
  if (!numbers_ok) {
    throw std::domain_error(
        "BuildPolicyState: inputs must be numbers with f_sen, resolution, u_total > 0");
  }
  if (!(options.d_eci_scale > 0.0 && options.speed_ref > 0.0 && options.resolution_ref > 0.0 &&
        options.distance_ref > 0.0)) {
    throw std::domain_error("BuildPolicyState: every PolicyStateOptions scale must be > 0");
  }

  out[0] = std::clamp(in.eci, 0.0, 1.0);
  out[1] = std::tanh(std::abs(in.d_eci) / options.d_eci_scale);
  for (int k = 0; k < 4; ++k) out[2 + k] = in.constraints_hold[static_cast<std::size_t>(k)] ? 1.0 : 0.0;
  out[6] = std::clamp(in.current.f_per / in.f_sen, 0.0, 2.0);
  out[7] = std::clamp(in.current.f_col / in.f_sen, 0.0, 2.0);
  out[8] = std::clamp(in.current.f_dif / in.f_sen, 0.0, 2.0);
  out[9] = in.resolution / options.resolution_ref;
  out[10] = std::clamp(in.v_WB.norm() / options.speed_ref, 0.0, 2.0);
  out[11] = std::clamp(in.u_cur / in.u_total, 0.0, 2.0);

  // Goal direction in the heading frame H: rotate the world offset by -yaw of the body x axis.
  const Eigen::Vector3d x_B_W = in.q_WB.normalized() * Eigen::Vector3d::UnitX();
  const double yaw = std::atan2(x_B_W.y(), x_B_W.x());
  const Eigen::Vector3d d_W = in.p_goal_W - in.p_WB;
  const double dist = d_W.norm();
  Eigen::Vector3d dir_H = Eigen::Vector3d::Zero();
  if (dist > 1e-9) {
    const double c = std::cos(yaw), s = std::sin(yaw);
    dir_H << c * d_W.x() + s * d_W.y(), -s * d_W.x() + c * d_W.y(), d_W.z();
    dir_H /= dist;
  }
  out.segment<3>(12) = dir_H;
  out[15] = dist / (dist + options.distance_ref);
}

Eigen::VectorXd BuildPolicyState(const PolicyStateInputs& in, const PolicyStateOptions& options) {
  Eigen::VectorXd out(kPolicyStateDim);
  BuildPolicyState(in, options, out);
  return out;
}

}  // namespace enavi::navstack
