// Geometric SE(3) tracking controller, open loop: what it asks for in known situations.

#include "navstack/control/geometric_controller.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "tests/unit/control/quadrotor_model.h"

namespace enavi::navstack {
namespace {

using testing::RampedProgress;

TEST(GeometricControllerTest, AtHoverReferenceAsksForWeightAndNoTorque) {
  const VehicleParams vehicle;
  GeometricController controller(vehicle);
  VehicleState state;
  state.p_WB = {1, 2, 3};
  TrajectorySample ref;
  ref.p = state.p_WB;
  const ControlOutput out = controller.Compute(state, ref);
  EXPECT_NEAR(out.wrench.thrust, vehicle.mass * vehicle.Gravity(), 1e-12);
  EXPECT_LT(out.wrench.torque_B.norm(), 1e-12);
  EXPECT_LT((out.R_WD - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_FALSE(out.tilt_limited || out.thrust_limited);
}

TEST(GeometricControllerTest, DesiredTiltNeverExceedsTheLimit) {
  GeometricControllerOptions options;
  options.max_tilt_deg = 35.0;
  GeometricController controller({}, options);
  VehicleState state;
  for (const Eigen::Vector3d& error : {Eigen::Vector3d(100, 0, 0), Eigen::Vector3d(-30, 40, -5),
                                       Eigen::Vector3d(0, 7, 50), Eigen::Vector3d(3, 3, -80)}) {
    TrajectorySample ref;
    ref.p = error;
    const ControlOutput out = controller.Compute(state, ref);
    const double tilt = std::acos(out.R_WD(2, 2)) * 180.0 / std::numbers::pi;
    EXPECT_LE(tilt, 35.0 + 1e-9) << "position error " << error.transpose();
    EXPECT_TRUE(out.tilt_limited || out.thrust_limited) << "error " << error.transpose();
    EXPECT_LE(out.wrench.thrust, options.max_thrust);
    EXPECT_GE(out.wrench.thrust, options.min_thrust);
    // The horizontal force never points away from the target (it may vanish when the
    // vertical demand takes the whole thrust).
    EXPECT_GE(out.F_W.head<2>().dot(error.head<2>()), 0.0) << "error " << error.transpose();
  }
}

// Heading convention (Lee et al.): the desired body x lies in the plane of the desired body z
// and the yaw direction b1c = (cos yaw, sin yaw, 0), on b1c's side; so body y is orthogonal to
// b1c, and in level flight body x is exactly b1c.
TEST(GeometricControllerTest, DesiredHeadingFollowsYawIncludingWrapAround) {
  GeometricController controller;
  VehicleState state;
  for (double yaw : {0.0, 1.0, -2.5, 3.1, 7.0}) {
    const Eigen::Vector3d b1c(std::cos(yaw), std::sin(yaw), 0.0);
    TrajectorySample ref;
    ref.yaw = yaw;
    ref.a = {2.0, -1.0, 0.5};  // tilted desired attitude
    ControlOutput out = controller.Compute(state, ref);
    EXPECT_NEAR(out.R_WD.col(1).dot(b1c), 0.0, 1e-12) << "yaw " << yaw;
    EXPECT_GT(out.R_WD.col(0).dot(b1c), 0.8) << "yaw " << yaw;
    EXPECT_NEAR(out.R_WD.determinant(), 1.0, 1e-12);
    EXPECT_LT((out.R_WD.transpose() * out.R_WD - Eigen::Matrix3d::Identity()).norm(), 1e-12);

    ref.a.setZero();  // level: body x is the yaw direction
    out = controller.Compute(state, ref);
    EXPECT_LT((out.R_WD.col(0) - b1c).norm(), 1e-12) << "yaw " << yaw;
  }
}

// The attitude error is the tilt that turns body z onto desired z, then the yaw about z: its
// x-y part is that tilt's axis in the body frame, whatever the yaw error, and its z part the yaw
// error alone (2 sin(angle / 2) each).
TEST(GeometricControllerTest, AttitudeErrorSeparatesTiltFromYaw) {
  GeometricController controller;
  TrajectorySample ref;  // level, yaw 0
  for (double yaw_deg : {0.0, 30.0, 150.0, -170.0}) {
    const double yaw = yaw_deg * std::numbers::pi / 180.0, roll = 20.0 * std::numbers::pi / 180.0;
    VehicleState state;
    state.q_WB = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
    const ControlOutput out = controller.Compute(state, ref);
    // Body rolled about its own x by 20 deg: the tilt error is about body x, of size 2 sin(10 deg).
    EXPECT_NEAR(out.e_R.x(), 2.0 * std::sin(roll / 2.0), 1e-9) << "yaw " << yaw_deg;
    EXPECT_NEAR(out.e_R.y(), 0.0, 1e-9) << "yaw " << yaw_deg;
    EXPECT_NEAR(out.e_R.z(), 2.0 * std::sin(yaw / 2.0), 1e-9) << "yaw " << yaw_deg;
  }
}

// The desired angular velocity from jerk and yaw rate must be the true rate of change of the
// desired attitude: compare against a finite difference along a smooth 3D reference.
TEST(GeometricControllerTest, FeedForwardRateMatchesFiniteDifferenceOfDesiredAttitude) {
  GeometricControllerOptions options;
  options.drag_feedforward = false;  // the formula differentiates m (a + g e_z) only
  options.k_integral.setZero();
  GeometricController controller({}, options);
  const auto reference = [](double t) {
    // Circle of radius 3 at up to 1.5 m/s with a vertical oscillation and heading along it.
    const auto s = RampedProgress(t, 0.5, 3.0);
    TrajectorySample r;
    const double c = std::cos(s[0]), sn = std::sin(s[0]);
    const Eigen::Vector3d u(-sn, c, 0), n(c, sn, 0);
    r.p = 3.0 * n + Eigen::Vector3d(0, 0, 0.3 * std::sin(t));
    r.v = 3.0 * s[1] * u + Eigen::Vector3d(0, 0, 0.3 * std::cos(t));
    r.a = 3.0 * (s[2] * u - s[1] * s[1] * n) + Eigen::Vector3d(0, 0, -0.3 * std::sin(t));
    r.j = 3.0 * (s[3] * u - 3 * s[1] * s[2] * n - s[1] * s[1] * s[1] * u) +
          Eigen::Vector3d(0, 0, -0.3 * std::cos(t));
    r.yaw = s[0] + 0.5 * std::sin(2 * t);
    r.yaw_rate = s[1] + std::cos(2 * t);
    return r;
  };
  const double h = 1e-5;
  for (double t : {0.7, 1.5, 2.2, 4.0, 6.3}) {
    VehicleState state;  // zero error: state on the reference
    TrajectorySample r0 = reference(t), r1 = reference(t + h);
    state.p_WB = r0.p;
    state.v_WB = r0.v;
    const ControlOutput out0 = controller.Compute(state, r0);
    state.p_WB = r1.p;
    state.v_WB = r1.v;
    const ControlOutput out1 = controller.Compute(state, r1);
    const Eigen::Matrix3d dR = (out0.R_WD.transpose() * out1.R_WD - Eigen::Matrix3d::Identity()) / h;
    const Eigen::Vector3d w_fd(dR(2, 1), dR(0, 2), dR(1, 0));
    EXPECT_LT((w_fd - out0.w_WD_D).norm(), 1e-4)
        << "t = " << t << ": finite difference " << w_fd.transpose() << " vs feed-forward "
        << out0.w_WD_D.transpose();
  }
}

TEST(GeometricControllerTest, BadOptionsAreRefusedNamingFieldAndRange) {
  const auto expect_refused = [](GeometricControllerOptions o, const std::string& field) {
    try {
      GeometricController controller({}, o);
      ADD_FAILURE() << field << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("is out of range"), std::string::npos) << e.what();
    }
  };
  GeometricControllerOptions o;
  o.max_tilt_deg = 95;
  expect_refused(o, "max_tilt_deg");
  o = {};
  o.max_thrust = 100;  // above 4 x rotor maximum (34.2 N)
  expect_refused(o, "max_thrust");
  o = {};
  o.k_attitude.y() = -1;
  expect_refused(o, "k_attitude[1]");
  o = {};
  o.rate_hz = 0;
  expect_refused(o, "rate_hz");
}

TEST(GeometricControllerTest, NonFiniteInputIsAContractViolation) {
  GeometricController controller;
  VehicleState state;
  TrajectorySample ref;
  ref.p.x() = std::nan("");
  EXPECT_THROW(controller.Compute(state, ref), std::domain_error);
}

TEST(GeometricControllerTest, IntegralIsFrozenWhileTiltLimited) {
  GeometricController controller;
  VehicleState state;
  TrajectorySample far;
  far.p = {50, 0, 0};
  for (int i = 0; i < 400; ++i) controller.Compute(state, far);
  EXPECT_LT(controller.integral_W().norm(), 1e-12) << "no windup while saturated";
  TrajectorySample near;
  near.p = {0.1, 0, 0};
  for (int i = 0; i < 400; ++i) controller.Compute(state, near);
  EXPECT_GT(controller.integral_W().x(), 0.0) << "integrates toward the target when unsaturated";
  controller.Reset();
  EXPECT_EQ(controller.integral_W().norm(), 0.0);
}

}  // namespace
}  // namespace enavi::navstack
