#include "navstack/control/geometric_controller.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "navstack/common/argument_check.h"

namespace enavi::navstack {
namespace {

Eigen::Matrix3d Hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d m;
  m << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return m;
}

constexpr ArgumentCheck kOptions("GeometricControllerOptions");
constexpr ArgumentCheck kVehicle("VehicleParams");

// Each component finite and >= 0 (or > 0 when `positive`), named field[i].
void RequireComponents(const ArgumentCheck& check, const Eigen::Vector3d& v, const std::string& field,
                       bool positive) {
  for (int i = 0; i < 3; ++i) {
    const bool ok = std::isfinite(v[i]) && (positive ? v[i] > 0.0 : v[i] >= 0.0);
    check.Range(ok, (field + "[" + std::to_string(i) + "]").c_str(), v[i], positive ? "(0, inf)" : "[0, inf)");
  }
}

}  // namespace

GeometricController::GeometricController(const VehicleParams& vehicle,
                                         const GeometricControllerOptions& options)
    : vehicle_(vehicle), options_(options) {
  const auto& o = options_;
  kOptions.Range(o.rate_hz > 0.0 && std::isfinite(o.rate_hz), "rate_hz", o.rate_hz, "(0, inf)");
  RequireComponents(kOptions, o.k_position, "k_position", true);
  RequireComponents(kOptions, o.k_velocity, "k_velocity", true);
  RequireComponents(kOptions, o.k_integral, "k_integral", false);
  RequireComponents(kOptions, o.k_attitude, "k_attitude", true);
  RequireComponents(kOptions, o.k_rate, "k_rate", true);
  kOptions.Range(o.integral_limit >= 0.0 && std::isfinite(o.integral_limit), "integral_limit", o.integral_limit,
                 "[0, inf)");
  kOptions.Range(o.integral_error_limit >= 0.0, "integral_error_limit", o.integral_error_limit, "[0, inf]");
  kOptions.Range(o.integral_max_speed_error >= 0.0, "integral_max_speed_error", o.integral_max_speed_error,
                 "[0, inf]");
  kOptions.Range(o.max_tilt_deg > 0.0 && o.max_tilt_deg < 80.0, "max_tilt_deg", o.max_tilt_deg, "(0, 80)");
  kVehicle.Range(vehicle_.mass > 0.0, "mass", vehicle_.mass, "(0, inf)");
  const double weight = vehicle_.mass * vehicle_.Gravity();
  const double ceiling = 4.0 * vehicle_.MaxThrustPerRotor();
  const std::string thrust_range = "(" + std::to_string(weight) + ", " + std::to_string(ceiling) +
                                   "] N (above the weight, at most 4 x the rotor maximum)";
  kOptions.Range(o.max_thrust > weight && o.max_thrust <= ceiling, "max_thrust", o.max_thrust, thrust_range.c_str());
  const std::string min_range = "[0, " + std::to_string(weight) + ") N";
  kOptions.Range(o.min_thrust >= 0.0 && o.min_thrust < weight, "min_thrust", o.min_thrust, min_range.c_str());
  RequireComponents(kVehicle, vehicle_.inertia_diag, "inertia_diag", true);
}

void GeometricController::Reset() { integral_W_.setZero(); }

ControlOutput GeometricController::Compute(const VehicleState& state,
                                           const TrajectorySample& ref) {
  if (!state.p_WB.allFinite() || !state.v_WB.allFinite() || !state.q_WB.coeffs().allFinite() ||
      !state.w_WB_B.allFinite()) {
    throw std::domain_error("GeometricController::Compute: non-finite vehicle state");
  }
  if (!ref.p.allFinite() || !ref.v.allFinite() || !ref.a.allFinite() || !ref.j.allFinite() ||
      !std::isfinite(ref.yaw) || !std::isfinite(ref.yaw_rate)) {
    throw std::domain_error("GeometricController::Compute: non-finite trajectory sample");
  }
  const auto& o = options_;
  const double m = vehicle_.mass;
  const double g = vehicle_.Gravity();
  const Eigen::Vector3d e_z = Eigen::Vector3d::UnitZ();
  const Eigen::Matrix3d R_WB = state.q_WB.normalized().toRotationMatrix();
  const Eigen::Vector3d& w_B = state.w_WB_B;
  const Eigen::Matrix3d J = vehicle_.inertia_diag.asDiagonal();

  ControlOutput out;
  out.e_p_W = state.p_WB - ref.p;
  out.e_v_W = state.v_WB - ref.v;

  // Desired force: PID on translation plus gravity, acceleration and drag feed-forward.
  Eigen::Vector3d F_W = -o.k_position.cwiseProduct(out.e_p_W) -
                        o.k_velocity.cwiseProduct(out.e_v_W) + integral_W_ + m * (ref.a + g * e_z);
  if (o.drag_feedforward) {
    F_W += R_WB * vehicle_.linear_drag.cwiseProduct(R_WB.transpose() * ref.v);
  }

  // Limits. Vertical force first (floor keeps rotors spinning, ceiling is the thrust limit),
  // then the horizontal force gets what the tilt and thrust limits leave.
  const double tan_tilt = std::tan(o.max_tilt_deg * std::numbers::pi / 180.0);
  const double cos_tilt = std::cos(o.max_tilt_deg * std::numbers::pi / 180.0);
  double F_z = std::clamp(F_W.z(), o.min_thrust * cos_tilt, o.max_thrust);
  if (F_z != F_W.z()) out.thrust_limited = true;
  Eigen::Vector2d F_xy = F_W.head<2>();
  double F_xy_max = F_z * tan_tilt;
  if (F_xy.norm() > F_xy_max) out.tilt_limited = true;
  const double F_xy_thrust = std::sqrt(std::max(0.0, o.max_thrust * o.max_thrust - F_z * F_z));
  if (F_xy_thrust < F_xy_max) {
    F_xy_max = F_xy_thrust;
    if (F_xy.norm() > F_xy_max) out.thrust_limited = true;
  }
  if (F_xy.norm() > F_xy_max) F_xy *= F_xy_max / F_xy.norm();
  F_W << F_xy, F_z;
  out.F_W = F_W;

  // Integral with conditional integration (anti-windup): frozen while a limit is active, and
  // per axis only near steady state (small velocity error), so manoeuvres are left to the PD
  // part.
  if (!out.tilt_limited && !out.thrust_limited) {
    const double dt = 1.0 / o.rate_hz;
    for (int i = 0; i < 3; ++i) {
      if (std::abs(out.e_v_W[i]) >= o.integral_max_speed_error) continue;
      const double e = std::clamp(out.e_p_W[i], -o.integral_error_limit, o.integral_error_limit);
      integral_W_[i] = std::clamp(integral_W_[i] - o.k_integral[i] * e * dt,
                                  -o.integral_limit, o.integral_limit);
    }
  }

  // Desired attitude: body z along F, heading from yaw (b2 = b3 x b1c, b1 = b2 x b3).
  const double F_norm = F_W.norm();
  const Eigen::Vector3d b3 = F_W / F_norm;
  const Eigen::Vector3d b1c(std::cos(ref.yaw), std::sin(ref.yaw), 0.0);
  const Eigen::Vector3d y_c(-std::sin(ref.yaw), std::cos(ref.yaw), 0.0);
  const Eigen::Vector3d b2 = b3.cross(b1c).normalized();  // b3 is never horizontal (tilt < 80)
  const Eigen::Vector3d b1 = b2.cross(b3);
  out.R_WD.col(0) = b1;
  out.R_WD.col(1) = b2;
  out.R_WD.col(2) = b3;

  // Desired angular velocity from differential flatness: b3_dot = (m/f)(j - (b3.j) b3)
  // = w_y b1 - w_x b2, and d/dt(b2 . b1c) = 0 gives w_z from the yaw rate.
  if (o.jerk_feedforward) {
    const Eigen::Vector3d h = (m / F_norm) * (ref.j - b3.dot(ref.j) * b3);
    const double w_x = -h.dot(b2);
    const double w_y = h.dot(b1);
    const double w_z = (w_x * b3.dot(b1c) + ref.yaw_rate * b2.dot(y_c)) / b1.dot(b1c);
    out.w_WD_D = Eigen::Vector3d(w_x, w_y, w_z);
  }

  // Attitude error: the rotation from the body to the desired attitude (q_BD, hemisphere w >= 0)
  // split into a tilt part that turns body z onto desired z and a yaw part about z after it
  // (Faessler, Fontana, Forster, Scaramuzza, "Automatic re-initialization and failure recovery
  // for aggressive flight with a monocular vision-based quadrotor", ICRA 2015; PX4's
  // mc_att_control AttitudeControl.cpp aligns the thrust axis first for the same reason). Each
  // part enters as 2 sin(angle / 2) times its axis. The whole error's vector part (the paper's
  // eq. 10 and its quaternion form) mixes the two: at a 150 deg yaw error a tilt error appears
  // mostly about the perpendicular axis, and a vehicle in s3 that lagged its turning reference
  // by 110-150 deg was tilted to 86 deg and fell into furniture. For a pure tilt or a pure yaw
  // error the split equals the whole error, so the gains are unchanged.
  const Eigen::Matrix3d R_BD = R_WB.transpose() * out.R_WD;
  Eigen::Quaterniond q_BD(R_BD);
  if (q_BD.w() < 0.0) q_BD.coeffs() = -q_BD.coeffs();
  const double qw = q_BD.w(), qx = q_BD.x(), qy = q_BD.y(), qz = q_BD.z();
  const double n = std::hypot(qw, qz);
  if (n > 1e-6) {
    // q_BD = q_tilt * q_yaw with q_tilt = (n, (qw qx - qy qz) / n, (qw qy + qx qz) / n, 0) and
    // q_yaw = (qw, 0, 0, qz) / n. The sign turns it into the body-from-desired error of eq. 10.
    out.e_R = -2.0 * Eigen::Vector3d((qw * qx - qy * qz) / n, (qw * qy + qx * qz) / n, qz / n);
  } else {
    // Body z opposite to desired z: no yaw is defined; the whole error turns the vehicle over.
    out.e_R = -2.0 * q_BD.vec();
  }
  const Eigen::Vector3d w_ref_B = R_BD * out.w_WD_D;
  out.e_w_B = w_B - w_ref_B;
  out.wrench.torque_B = -o.k_attitude.cwiseProduct(out.e_R) - o.k_rate.cwiseProduct(out.e_w_B) +
                        w_B.cross(J * w_B) - J * (Hat(w_B) * w_ref_B);

  // Collective thrust: the desired force projected on the current body z.
  const double f = F_W.dot(R_WB * e_z);
  out.wrench.thrust = std::clamp(f, o.min_thrust, o.max_thrust);
  if (out.wrench.thrust != f) out.thrust_limited = true;
  return out;
}

}  // namespace enavi::navstack
