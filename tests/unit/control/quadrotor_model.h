#pragma once
// A small rigid-body quadrotor for closed-loop controller tests: RK4, the rotor model of
// VehicleParams (f = k_f w^2 along body z, yaw reaction -spin k_m f), first-order motor lag
// with separate up/down time constants, and linear drag in body axes. Independent of the
// simulator in workers/sim on purpose: the controller is tested against the plain equations.

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/state.h"
#include "navstack/control/controller.h"
#include "navstack/control/vehicle.h"

namespace enavi::navstack::testing {

struct RigidBodyState {
  Eigen::Vector3d p_WB = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_WB = Eigen::Vector3d::Zero();
  Eigen::Vector4d q_WB{1, 0, 0, 0};  // w, x, y, z
  Eigen::Vector3d w_WB_B = Eigen::Vector3d::Zero();
  Eigen::Vector4d omega = Eigen::Vector4d::Zero();  // rotor speeds, rad/s

  RigidBodyState operator+(const RigidBodyState& o) const {
    RigidBodyState r;
    r.p_WB = p_WB + o.p_WB;
    r.v_WB = v_WB + o.v_WB;
    r.q_WB = q_WB + o.q_WB;
    r.w_WB_B = w_WB_B + o.w_WB_B;
    r.omega = omega + o.omega;
    return r;
  }
  RigidBodyState operator*(double s) const {
    RigidBodyState r;
    r.p_WB = p_WB * s;
    r.v_WB = v_WB * s;
    r.q_WB = q_WB * s;
    r.w_WB_B = w_WB_B * s;
    r.omega = omega * s;
    return r;
  }
  Eigen::Quaterniond Quaternion() const {
    return Eigen::Quaterniond(q_WB[0], q_WB[1], q_WB[2], q_WB[3]).normalized();
  }
};

class QuadrotorModel {
 public:
  explicit QuadrotorModel(const VehicleParams& truth) : p_(truth) {}

  /// Starts at rest at p with the given attitude and rotors spinning at hover speed.
  void ResetAt(const Eigen::Vector3d& p, const Eigen::Quaterniond& q =
                                             Eigen::Quaterniond::Identity()) {
    x_ = {};
    x_.p_WB = p;
    const Eigen::Quaterniond qn = q.normalized();
    x_.q_WB << qn.w(), qn.x(), qn.y(), qn.z();
    x_.omega.setConstant(std::sqrt(p_.mass * p_.Gravity() / (4.0 * p_.thrust_coeff)));
    t_ = 0.0;
  }

  /// One RK4 step with the rotor speed command held.
  void Step(const RotorCommand& cmd, double dt) {
    const RigidBodyState k1 = Derivative(x_, cmd);
    const RigidBodyState k2 = Derivative(x_ + k1 * (dt / 2), cmd);
    const RigidBodyState k3 = Derivative(x_ + k2 * (dt / 2), cmd);
    const RigidBodyState k4 = Derivative(x_ + k3 * dt, cmd);
    x_ = x_ + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0);
    x_.q_WB.normalize();
    t_ += dt;
  }

  VehicleState State() const {
    VehicleState s;
    s.t = t_;
    s.p_WB = x_.p_WB;
    s.v_WB = x_.v_WB;
    s.q_WB = x_.Quaternion();
    s.w_WB_B = x_.w_WB_B;
    return s;
  }
  RigidBodyState& mutable_state() { return x_; }
  double time() const { return t_; }

 private:
  RigidBodyState Derivative(const RigidBodyState& x, const RotorCommand& cmd) const {
    RigidBodyState d;
    const Eigen::Quaterniond q = x.Quaternion();
    const Eigen::Matrix3d R = q.toRotationMatrix();
    const auto rotors = p_.RotorPositions();

    // Rotor forces and torques in B.
    double thrust = 0.0;
    Eigen::Vector3d tau = Eigen::Vector3d::Zero();
    for (int i = 0; i < 4; ++i) {
      const double w = std::max(0.0, x.omega[i]);
      const double f = p_.thrust_coeff * w * w;
      thrust += f;
      tau += rotors[i].cross(Eigen::Vector3d(0, 0, f));
      tau.z() += -VehicleParams::kSpin[i] * p_.moment_coeff * f;
    }
    const Eigen::Vector3d drag_W =
        -R * p_.linear_drag.cwiseProduct(R.transpose() * x.v_WB);

    d.p_WB = x.v_WB;
    d.v_WB = (R * Eigen::Vector3d(0, 0, thrust) + drag_W) / p_.mass -
             Eigen::Vector3d(0, 0, p_.Gravity());
    // q_dot = 1/2 q (x) (0, w).
    const Eigen::Quaterniond qd =
        Eigen::Quaterniond(x.q_WB[0], x.q_WB[1], x.q_WB[2], x.q_WB[3]) *
        Eigen::Quaterniond(0, x.w_WB_B.x(), x.w_WB_B.y(), x.w_WB_B.z());
    d.q_WB << 0.5 * qd.w(), 0.5 * qd.x(), 0.5 * qd.y(), 0.5 * qd.z();
    const Eigen::Vector3d J = p_.inertia_diag;
    const Eigen::Vector3d Jw = J.cwiseProduct(x.w_WB_B);
    d.w_WB_B = (tau - x.w_WB_B.cross(Jw)).cwiseQuotient(J);
    // First-order motor lag, faster spinning up than down.
    for (int i = 0; i < 4; ++i) {
      const double target = std::clamp(cmd.omega[i], 0.0, p_.omega_max);
      const double tc =
          target > x.omega[i] ? p_.motor_time_constant_up : p_.motor_time_constant_down;
      d.omega[i] = (target - x.omega[i]) / tc;
    }
    return d;
  }

  VehicleParams p_;
  RigidBodyState x_;
  double t_ = 0.0;
};

/// One recorded controller step.
struct TraceSample {
  double t = 0.0;
  VehicleState state;
  TrajectorySample reference;
  ControlOutput output;
  MixResult mix;
};

/// Closed loop: controller at its rate (zero-order hold), physics at `physics_substeps` RK4
/// steps per control period.
inline std::vector<TraceSample> Fly(Controller* controller, QuadrotorModel* model,
                                    const std::function<TrajectorySample(double)>& reference,
                                    double duration, int physics_substeps = 5) {
  std::vector<TraceSample> trace;
  const double dt = controller->period();
  const int steps = static_cast<int>(std::lround(duration / dt));
  for (int k = 0; k < steps; ++k) {
    const double t = k * dt;
    TraceSample s;
    s.t = t;
    s.state = model->State();
    s.reference = reference(t);
    const RotorCommand cmd = controller->Update(s.state, s.reference);
    s.output = controller->last_output();
    s.mix = controller->last_mix();
    trace.push_back(s);
    for (int i = 0; i < physics_substeps; ++i) model->Step(cmd, dt / physics_substeps);
  }
  return trace;
}

inline double YawOf(const Eigen::Quaterniond& q) {
  const Eigen::Matrix3d R = q.toRotationMatrix();
  return std::atan2(R(1, 0), R(0, 0));
}

inline double TiltDegOf(const Eigen::Quaterniond& q) {
  const double c = std::clamp(q.toRotationMatrix()(2, 2), -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

inline double WrapAngle(double a) { return std::remainder(a, 2.0 * M_PI); }

/// Smooth speed profile: 0 -> rate over ramp_s (quintic smootherstep on the rate, so
/// acceleration and jerk are continuous), then constant. Returns {s, s', s'', s'''}.
inline std::array<double, 4> RampedProgress(double t, double rate, double ramp_s) {
  if (t <= 0.0) return {0, 0, 0, 0};
  if (t >= ramp_s) return {rate * (0.5 * ramp_s + (t - ramp_s)), rate, 0, 0};
  const double u = t / ramp_s;
  const double u2 = u * u, u3 = u2 * u, u4 = u3 * u;
  const double integral = u4 * u2 - 3 * u4 * u + 2.5 * u4;    // int_0^u S
  const double S = 6 * u4 * u - 15 * u4 + 10 * u3;           // smootherstep
  const double dS = 30 * u4 - 60 * u3 + 30 * u2;
  const double ddS = 120 * u3 - 180 * u2 + 60 * u;
  return {rate * ramp_s * integral, rate * S, rate * dS / ramp_s, rate * ddS / (ramp_s * ramp_s)};
}

}  // namespace enavi::navstack::testing
