#include "navstack/control/mixer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/LU>

namespace enavi::navstack {
namespace {

using Vector4 = Eigen::Vector4d;

// Demands this close to the feasible range count as inside (round-off of the allocation).
constexpr double kSlack = 1e-9;

void RequirePositive(double value, const char* field) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string("VehicleParams.") + field + " = " +
                                std::to_string(value) + ": must be a finite number > 0");
  }
}

// Range of the scalar s for which every rotor thrust base + s * dir stays in [0, f_max].
// The range contains 0 when base is itself feasible.
void FeasibleRange(const Vector4& base, const Vector4& dir, double f_max, double* lo,
                   double* hi) {
  *lo = -std::numeric_limits<double>::infinity();
  *hi = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 4; ++i) {
    if (std::abs(dir[i]) < 1e-15) continue;  // this rotor does not depend on s
    const double a = (0.0 - base[i]) / dir[i];
    const double b = (f_max - base[i]) / dir[i];
    *lo = std::max(*lo, std::min(a, b));
    *hi = std::min(*hi, std::max(a, b));
  }
}

// Range of the collective thrust T for which a yaw torque y in [y_lo, y_hi] exists with every
// rotor thrust f_rp + T c_t + y c_y in [0, f_max]. Each constraint bounds y below or above by a
// line a + b T; a y exists iff every lower line <= every upper line, and each such pair is a
// linear inequality in T. (The projection of a convex polygon onto the T axis.)
void ThrustRangeAllowingYaw(const Vector4& f_rp, const Vector4& c_t, const Vector4& c_y,
                            double f_max, double y_lo, double y_hi, double* lo, double* hi) {
  struct Line {
    double a, b;  // a + b T
  };
  std::vector<Line> lower{{y_lo, 0.0}}, upper{{y_hi, 0.0}};
  *lo = -std::numeric_limits<double>::infinity();
  *hi = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 4; ++i) {
    if (std::abs(c_y[i]) < 1e-15) {
      // A rotor that yaw does not move bounds the thrust directly.
      double t_lo = 0.0, t_hi = 0.0;
      FeasibleRange(Vector4::Constant(f_rp[i]), Vector4::Constant(c_t[i]), f_max, &t_lo, &t_hi);
      *lo = std::max(*lo, t_lo);
      *hi = std::min(*hi, t_hi);
      continue;
    }
    // y = (bound - f_rp_i - T c_t_i) / c_y_i at the rotor bounds 0 and f_max.
    const Line at_zero{-f_rp[i] / c_y[i], -c_t[i] / c_y[i]};
    const Line at_max{(f_max - f_rp[i]) / c_y[i], -c_t[i] / c_y[i]};
    lower.push_back(c_y[i] > 0 ? at_zero : at_max);
    upper.push_back(c_y[i] > 0 ? at_max : at_zero);
  }
  for (const Line& l : lower) {
    for (const Line& u : upper) {
      // l.a + l.b T <= u.a + u.b T  <=>  (l.b - u.b) T <= u.a - l.a.
      const double k = l.b - u.b;
      const double r = u.a - l.a;
      if (k > 1e-15) *hi = std::min(*hi, r / k);
      if (k < -1e-15) *lo = std::max(*lo, r / k);
    }
  }
}

}  // namespace

Mixer::Mixer(const VehicleParams& vehicle) : vehicle_(vehicle) {
  RequirePositive(vehicle_.thrust_coeff, "thrust_coeff");
  RequirePositive(vehicle_.moment_coeff, "moment_coeff");
  RequirePositive(vehicle_.omega_max, "omega_max");
  RequirePositive(vehicle_.arm_length, "arm_length");
  f_max_ = vehicle_.MaxThrustPerRotor();

  // Rows: thrust, tau_x, tau_y, tau_z. Rotor i at r_i pushes f_i e_z: r_i x f_i e_z =
  // (y_i f_i, -x_i f_i, 0); its drag reaction about z is -spin_i * k_m * f_i.
  const auto rotors = vehicle_.RotorPositions();
  for (int i = 0; i < 4; ++i) {
    A_(0, i) = 1.0;
    A_(1, i) = rotors[i].y();
    A_(2, i) = -rotors[i].x();
    A_(3, i) = -VehicleParams::kSpin[i] * vehicle_.moment_coeff;
  }
  Eigen::FullPivLU<Eigen::Matrix4d> lu(A_);
  if (!lu.isInvertible()) {
    throw std::invalid_argument(
        "VehicleParams: rotor geometry and spin directions give a singular allocation matrix");
  }
  A_inv_ = lu.inverse();
}

std::array<double, 4> Mixer::AllocateUnconstrained(const Wrench& wrench) const {
  const Vector4 w(wrench.thrust, wrench.torque_B.x(), wrench.torque_B.y(), wrench.torque_B.z());
  const Vector4 f = A_inv_ * w;
  return {f[0], f[1], f[2], f[3]};
}

MixResult Mixer::Mix(const Wrench& wrench) const {
  if (!std::isfinite(wrench.thrust) || !wrench.torque_B.allFinite()) {
    throw std::domain_error("Mixer::Mix: non-finite wrench demand");
  }
  MixResult out;
  const Vector4 per_thrust = A_inv_.col(0);
  const Vector4 per_yaw = A_inv_.col(3);

  // 1. Roll/pitch first: the zero-sum differential thrust must fit in the rotors' range;
  //    otherwise scale the roll/pitch torque vector down, keeping its direction.
  double tau_x = wrench.torque_B.x();
  double tau_y = wrench.torque_B.y();
  Vector4 f_rp = A_inv_.col(1) * tau_x + A_inv_.col(2) * tau_y;
  const double spread = f_rp.maxCoeff() - f_rp.minCoeff();
  if (spread > f_max_) {
    const double s = f_max_ / spread;
    tau_x *= s;
    tau_y *= s;
    f_rp *= s;
    out.roll_pitch_scaled = true;
  }

  // 2. Collective thrust: clamp into the range for which some yaw torque between zero and the
  //    demand leaves every rotor in range: thrust never gives way to yaw, and yaw may shrink
  //    but never reverses to make room for thrust.
  const double yaw_demand = wrench.torque_B.z();
  double lo = 0.0, hi = 0.0;
  ThrustRangeAllowingYaw(f_rp, per_thrust, per_yaw, f_max_, std::min(0.0, yaw_demand),
                         std::max(0.0, yaw_demand), &lo, &hi);
  double thrust = wrench.thrust;
  if (thrust < lo - kSlack || thrust > hi + kSlack) out.thrust_clipped = true;
  thrust = std::clamp(thrust, lo, std::max(lo, hi));
  const Vector4 f_base = f_rp + per_thrust * thrust;

  // 3. Yaw last: whatever headroom the rotors have left.
  FeasibleRange(f_base, per_yaw, f_max_, &lo, &hi);
  double tau_z = wrench.torque_B.z();
  if (tau_z < lo - kSlack || tau_z > hi + kSlack) out.yaw_clipped = true;
  tau_z = std::clamp(tau_z, lo, std::max(lo, hi));
  tau_z = std::clamp(tau_z, std::min(0.0, yaw_demand), std::max(0.0, yaw_demand));  // round-off
  const Vector4 f = f_base + per_yaw * tau_z;

  // Thrust -> speed; clamping here only removes round-off.
  for (int i = 0; i < 4; ++i) {
    out.thrust[i] = std::clamp(f[i], 0.0, f_max_);
    out.command.omega[i] = SpeedForThrust(out.thrust[i]);
  }
  out.achieved = WrenchFromThrusts(out.thrust);
  return out;
}

Wrench Mixer::WrenchFromThrusts(const std::array<double, 4>& thrust) const {
  const Vector4 w = A_ * Vector4(thrust[0], thrust[1], thrust[2], thrust[3]);
  Wrench out;
  out.thrust = w[0];
  out.torque_B = w.tail<3>();
  return out;
}

Wrench Mixer::WrenchFromSpeeds(const RotorCommand& command) const {
  std::array<double, 4> f{};
  for (int i = 0; i < 4; ++i) f[i] = vehicle_.thrust_coeff * command.omega[i] * command.omega[i];
  return WrenchFromThrusts(f);
}

double Mixer::SpeedForThrust(double f) const {
  return std::sqrt(std::clamp(f, 0.0, f_max_) / vehicle_.thrust_coeff);
}

}  // namespace enavi::navstack
