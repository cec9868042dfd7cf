// Controller + mixer flying the RK4 quadrotor of quadrotor_model.h (motor lag, linear drag):
// hover, steps, a straight line, a circle, yaw steps, tilt limit, model mismatch, recovery.
// Measured figures are printed as "[ measured ]" lines and recorded as test properties.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "navstack/control/controller.h"
#include "tests/unit/control/quadrotor_model.h"

namespace enavi::navstack {
namespace {

using testing::Fly;
using testing::QuadrotorModel;
using testing::RampedProgress;
using testing::TiltDegOf;
using testing::TraceSample;
using testing::WrapAngle;
using testing::YawOf;

constexpr double kDeg = 180.0 / std::numbers::pi;

void Measured(const std::string& key, double value) {
  std::printf("[ measured ] %s = %.4f\n", key.c_str(), value);
  ::testing::Test::RecordProperty(key, std::to_string(value));
}

double PositionError(const TraceSample& s) { return (s.state.p_WB - s.reference.p).norm(); }

// Max and RMS position error over samples with t in [t0, t1].
struct ErrorStats {
  double max = 0.0;
  double rms = 0.0;
};
ErrorStats PositionErrorStats(const std::vector<TraceSample>& trace, double t0, double t1) {
  ErrorStats e;
  int n = 0;
  for (const auto& s : trace) {
    if (s.t < t0 || s.t > t1) continue;
    const double err = PositionError(s);
    e.max = std::max(e.max, err);
    e.rms += err * err;
    ++n;
  }
  e.rms = n > 0 ? std::sqrt(e.rms / n) : 0.0;
  return e;
}

TrajectorySample Hold(const Eigen::Vector3d& p, double yaw = 0.0) {
  TrajectorySample r;
  r.p = p;
  r.yaw = yaw;
  return r;
}

TEST(ClosedLoopTest, HoverHoldsPositionWithinTwoCentimetres) {
  const VehicleParams vehicle;
  Controller controller(vehicle);
  QuadrotorModel model(vehicle);
  const Eigen::Vector3d p_ref(0.5, -1.0, 2.0);
  // Start 1 cm off with a small rate disturbance so the loop has something to do.
  model.ResetAt(p_ref + Eigen::Vector3d(0.01, 0.0, -0.005));
  model.mutable_state().w_WB_B = Eigen::Vector3d(0.2, -0.1, 0.05);
  const auto trace = Fly(&controller, &model, [&](double) { return Hold(p_ref); }, 10.0);
  const ErrorStats e = PositionErrorStats(trace, 0.0, 10.0);
  Measured("hover_max_error_m", e.max);
  EXPECT_LT(e.max, 0.02) << "hover must stay within 2 cm";
  EXPECT_LT(PositionError(trace.back()), 1e-3) << "and settle to the reference";
}

TEST(ClosedLoopTest, HoverWithWrongMassRecoversWithinTwoCentimetres) {
  // The controller believes 1.5 kg; the vehicle is 10 % heavier or 15 % lighter.
  for (double mass_factor : {1.10, 0.85}) {
    VehicleParams truth;
    truth.mass *= mass_factor;
    Controller controller(VehicleParams{});
    QuadrotorModel model(truth);
    const Eigen::Vector3d p_ref(0, 0, 1.5);
    model.ResetAt(p_ref);
    const auto trace = Fly(&controller, &model, [&](double) { return Hold(p_ref); }, 12.0);
    const ErrorStats transient = PositionErrorStats(trace, 0.0, 12.0);
    const ErrorStats settled = PositionErrorStats(trace, 6.0, 12.0);
    const std::string name = "mass_x" + std::to_string(mass_factor).substr(0, 4);
    Measured(name + "_peak_error_m", transient.max);
    Measured(name + "_settled_max_error_m", settled.max);
    EXPECT_LT(transient.max, 0.25) << name << ": offset before the integral term catches up";
    EXPECT_LT(settled.max, 0.02) << name << ": integral action removes the steady offset";
  }
}

// Steps along x, z, -y and the diagonal; repeated with motors three times slower than the
// controller assumes, to show the default gains are not tuned to the model's exact lag.
TEST(ClosedLoopTest, OneMetreStepConvergesWithinThreeSecondsWithBoundedOvershoot) {
  for (double lag_factor : {1.0, 3.0}) {
    VehicleParams truth;
    truth.motor_time_constant_up *= lag_factor;
    truth.motor_time_constant_down *= lag_factor;
    for (const Eigen::Vector3d& step :
         {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, -1, 0),
          Eigen::Vector3d(1, 1, 1).normalized()}) {
      Controller controller(VehicleParams{});
      QuadrotorModel model(truth);
      const Eigen::Vector3d p0(0, 0, 2);
      model.ResetAt(p0);
      const Eigen::Vector3d p_ref = p0 + step;
      const auto trace = Fly(&controller, &model, [&](double) { return Hold(p_ref); }, 6.0);
      // Overshoot: progress along the step direction beyond 1 m.
      double overshoot = 0.0, settle_time = 0.0;
      for (const auto& s : trace) {
        overshoot = std::max(overshoot, (s.state.p_WB - p0).dot(step) - 1.0);
        if (PositionError(s) > 0.05) settle_time = s.t;
      }
      char name[64];
      std::snprintf(name, sizeof(name), "step_%+.2f_%+.2f_%+.2f_lag_x%.0f", step.x(), step.y(),
                    step.z(), lag_factor);
      const ErrorStats after = PositionErrorStats(trace, 3.0, 6.0);
      Measured(std::string(name) + "_overshoot_m", overshoot);
      Measured(std::string(name) + "_settle_time_5cm_s", settle_time);
      Measured(std::string(name) + "_max_error_after_3s_m", after.max);
      EXPECT_LT(overshoot, 0.05) << name << ": overshoot below 5 %";
      EXPECT_LT(settle_time, 3.0) << name << ": within 5 cm by 3 s";
      EXPECT_LT(after.max, 0.05) << name;
    }
  }
}

TEST(ClosedLoopTest, StraightLineAtTwoMetresPerSecondIsTrackedClosely) {
  const VehicleParams vehicle;
  Controller controller(vehicle);
  QuadrotorModel model(vehicle);
  const Eigen::Vector3d p0(0, 0, 1.5);
  const Eigen::Vector3d dir = Eigen::Vector3d(1.0, 0.6, 0.15).normalized();
  model.ResetAt(p0);
  // Ramp to 2 m/s in 2 s (smooth acceleration and jerk), then cruise for 10 s.
  const auto reference = [&](double t) {
    const auto s = RampedProgress(t, 2.0, 2.0);
    TrajectorySample r;
    r.p = p0 + s[0] * dir;
    r.v = s[1] * dir;
    r.a = s[2] * dir;
    r.j = s[3] * dir;
    r.yaw = std::atan2(dir.y(), dir.x());
    return r;
  };
  const auto trace = Fly(&controller, &model, reference, 12.0);
  const ErrorStats all = PositionErrorStats(trace, 0.0, 12.0);
  const ErrorStats cruise = PositionErrorStats(trace, 3.0, 12.0);
  double speed_error = 0.0;
  for (const auto& s : trace) {
    if (s.t >= 3.0) speed_error = std::max(speed_error, (s.state.v_WB - s.reference.v).norm());
  }
  Measured("line_max_error_m", all.max);
  Measured("line_rms_error_m", all.rms);
  Measured("line_cruise_max_error_m", cruise.max);
  Measured("line_cruise_max_speed_error_mps", speed_error);
  EXPECT_LT(all.max, 0.025) << "including the acceleration phase";
  EXPECT_LT(cruise.max, 0.01) << "steady cruise at 2 m/s";
  EXPECT_LT(speed_error, 0.01);
}

// Circle of radius 3 m at 1.5 m/s (0.75 m/s^2 centripetal), heading along the tangent; flown
// once on the nominal model and once on a mismatched one (drag and motor lag doubled, 5 %
// heavier) that the controller does not know about.
TEST(ClosedLoopTest, CircleOfThreeMetresAtOnePointFiveMetresPerSecondIsTracked) {
  const double radius = 3.0, speed = 1.5;
  const Eigen::Vector3d centre(0, 0, 2);
  // Angular progress ramps to speed / radius in 3 s.
  const auto reference = [&](double t) {
    const auto s = RampedProgress(t, speed / radius, 3.0);
    const double c = std::cos(s[0]), sn = std::sin(s[0]);
    const Eigen::Vector3d u(-sn, c, 0), n(c, sn, 0);
    TrajectorySample r;
    r.p = centre + radius * n;
    r.v = radius * s[1] * u;
    r.a = radius * (s[2] * u - s[1] * s[1] * n);
    r.j = radius * (s[3] * u - 3 * s[1] * s[2] * n - s[1] * s[1] * s[1] * u);
    r.yaw = s[0] + std::numbers::pi / 2;
    r.yaw_rate = s[1];
    return r;
  };
  const double laps_end = 3.0 + 2 * (2 * std::numbers::pi * radius / speed);  // two laps

  struct Case {
    std::string name;
    double drag_factor, lag_factor, mass_factor;
    double max_bound, cruise_bound, yaw_bound_deg;
  };
  for (const Case& c : {Case{"circle", 1.0, 1.0, 1.0, 0.01, 0.01, 0.5},
                        Case{"circle_mismatch", 2.0, 2.0, 1.05, 0.08, 0.06, 1.0}}) {
    VehicleParams truth;
    truth.linear_drag *= c.drag_factor;
    truth.motor_time_constant_up *= c.lag_factor;
    truth.motor_time_constant_down *= c.lag_factor;
    truth.mass *= c.mass_factor;
    Controller controller(VehicleParams{});
    QuadrotorModel model(truth);
    model.ResetAt(centre + Eigen::Vector3d(radius, 0, 0),
                  Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ())));
    const auto trace = Fly(&controller, &model, reference, laps_end);
    const ErrorStats all = PositionErrorStats(trace, 0.0, laps_end);
    const ErrorStats cruise = PositionErrorStats(trace, 5.0, laps_end);
    double yaw_error = 0.0, radial_error = 0.0;
    for (const auto& s : trace) {
      if (s.t < 5.0) continue;
      yaw_error = std::max(yaw_error, std::abs(WrapAngle(YawOf(s.state.q_WB) - s.reference.yaw)));
      radial_error =
          std::max(radial_error, std::abs((s.state.p_WB - centre).head<2>().norm() - radius));
    }
    Measured(c.name + "_max_error_m", all.max);
    Measured(c.name + "_rms_error_m", all.rms);
    Measured(c.name + "_cruise_max_error_m", cruise.max);
    Measured(c.name + "_cruise_max_radial_error_m", radial_error);
    Measured(c.name + "_cruise_max_yaw_error_deg", yaw_error * kDeg);
    EXPECT_LT(all.max, c.max_bound) << c.name;
    EXPECT_LT(cruise.max, c.cruise_bound) << c.name;
    EXPECT_LT(radial_error, c.cruise_bound) << c.name;
    EXPECT_LT(yaw_error * kDeg, c.yaw_bound_deg) << c.name;
  }
}

TEST(ClosedLoopTest, YawStepIsTrackedWhileHoldingPosition) {
  const VehicleParams vehicle;
  for (double yaw_ref_deg : {90.0, -170.0}) {
    Controller controller(vehicle);
    QuadrotorModel model(vehicle);
    const Eigen::Vector3d p_ref(0, 0, 1);
    model.ResetAt(p_ref);
    const double yaw_ref = yaw_ref_deg / kDeg;
    const auto trace = Fly(&controller, &model, [&](double) { return Hold(p_ref, yaw_ref); }, 6.0);
    double settle_time = 0.0, overshoot = 0.0;
    for (const auto& s : trace) {
      const double err = WrapAngle(YawOf(s.state.q_WB) - yaw_ref);
      if (std::abs(err) > 2.0 / kDeg) settle_time = s.t;
      // Overshoot: past the target in the direction of travel.
      if (s.t > 0.5) overshoot = std::max(overshoot, (yaw_ref > 0 ? err : -err) * kDeg);
    }
    const ErrorStats pos = PositionErrorStats(trace, 0.0, 6.0);
    const std::string name = "yaw_step_" + std::to_string(static_cast<int>(yaw_ref_deg));
    Measured(name + "_settle_time_2deg_s", settle_time);
    Measured(name + "_overshoot_deg", overshoot);
    Measured(name + "_max_position_error_m", pos.max);
    EXPECT_LT(settle_time, 3.0) << "yaw step " << yaw_ref_deg << " deg within 2 deg by 3 s";
    // The half-turn starts at nearly full attitude-error torque (2 sin(85 deg)), so it arrives
    // faster and overshoots a little more than the quarter turn.
    EXPECT_LT(overshoot, std::abs(yaw_ref_deg) > 150.0 ? 3.0 : 2.0);
    EXPECT_LT(pos.max, 0.03) << "yaw must not disturb the position much";
    EXPECT_LT(std::abs(WrapAngle(YawOf(trace.back().state.q_WB) - yaw_ref)) * kDeg, 0.5);
  }
}

TEST(ClosedLoopTest, LongStepRespectsTheTiltLimitAndArrives) {
  const VehicleParams vehicle;
  Controller controller(vehicle);
  QuadrotorModel model(vehicle);
  const Eigen::Vector3d p0(0, 0, 2), p_ref(10, 0, 2);
  model.ResetAt(p0);
  const auto trace = Fly(&controller, &model, [&](double) { return Hold(p_ref); }, 10.0);
  double max_tilt = 0.0, altitude_dev = 0.0;
  for (const auto& s : trace) {
    max_tilt = std::max(max_tilt, TiltDegOf(s.state.q_WB));
    altitude_dev = std::max(altitude_dev, std::abs(s.state.p_WB.z() - p0.z()));
  }
  Measured("long_step_max_tilt_deg", max_tilt);
  Measured("long_step_max_altitude_deviation_m", altitude_dev);
  Measured("long_step_final_error_m", PositionError(trace.back()));
  EXPECT_LT(max_tilt, 35.0 + 3.0) << "attitude follows the 35 deg desired-tilt limit";
  EXPECT_LT(altitude_dev, 0.15) << "vertical force has priority over horizontal";
  EXPECT_LT(PositionError(trace.back()), 0.05);
}

TEST(ClosedLoopTest, RecoversFromSixtyDegreeRollWithSmallAltitudeLoss) {
  const VehicleParams vehicle;
  Controller controller(vehicle);
  QuadrotorModel model(vehicle);
  const Eigen::Vector3d p_ref(0, 0, 5);
  model.ResetAt(p_ref, Eigen::Quaterniond(Eigen::AngleAxisd(60.0 / kDeg,
                                                              Eigen::Vector3d::UnitX())));
  const auto trace = Fly(&controller, &model, [&](double) { return Hold(p_ref); }, 6.0);
  double level_time = 0.0, altitude_loss = 0.0;
  for (const auto& s : trace) {
    if (TiltDegOf(s.state.q_WB) > 5.0) level_time = s.t;
    altitude_loss = std::max(altitude_loss, p_ref.z() - s.state.p_WB.z());
  }
  Measured("roll60_time_to_level_5deg_s", level_time);
  Measured("roll60_max_altitude_loss_m", altitude_loss);
  EXPECT_LT(level_time, 1.0);
  EXPECT_LT(altitude_loss, 0.5);
  EXPECT_LT(PositionError(trace.back()), 0.05);
}

TEST(ClosedLoopTest, AYawErrorNearHalfATurnStillLevelsTheVehicle) {
  // Rolled 30 deg and facing 178 deg away from the reference yaw: the whole rotation error is
  // near 180 deg, where the paper's error (sin of the angle) all but vanishes, tilt included,
  // and the vehicle drifted off. The quaternion error keeps correcting both.
  const VehicleParams vehicle;
  Controller controller(vehicle);
  QuadrotorModel model(vehicle);
  const Eigen::Vector3d p_ref(0, 0, 5);
  model.ResetAt(p_ref, Eigen::Quaterniond(Eigen::AngleAxisd(178.0 / kDeg, Eigen::Vector3d::UnitZ()) *
                                          Eigen::AngleAxisd(30.0 / kDeg, Eigen::Vector3d::UnitX())));
  const auto trace = Fly(&controller, &model, [&](double) { return Hold(p_ref); }, 6.0);
  double level_time = 0.0;
  for (const auto& s : trace)
    if (TiltDegOf(s.state.q_WB) > 5.0) level_time = s.t;
  const ErrorStats pos = PositionErrorStats(trace, 0.0, 6.0);
  Measured("yaw178_roll30_time_to_level_5deg_s", level_time);
  Measured("yaw178_roll30_max_position_error_m", pos.max);
  EXPECT_LT(level_time, 1.5);
  EXPECT_LT(pos.max, 1.0);
  EXPECT_LT(std::abs(WrapAngle(YawOf(trace.back().state.q_WB))) * kDeg, 2.0) << "and turned to the reference yaw";
  EXPECT_LT(PositionError(trace.back()), 0.05);
}

TEST(ClosedLoopTest, ALargeYawErrorDoesNotTurnTheTiltCorrectionSideways) {
  // Facing 140-160 deg away from the reference yaw, rolled 25 deg, and asked to move 3 m
  // sideways: in the whole rotation error a tilt error appears mostly about the perpendicular
  // axis at such a yaw error, and the vehicle went to 57-61 deg and lost 0.2-0.3 m of altitude
  // (an s3 flight lagging its turning reference by 110-150 deg reached 86 deg and fell).
  // Corrected tilt first, it stays at the 35 deg desired-tilt limit.
  const VehicleParams vehicle;
  for (double yaw_deg : {140.0, -160.0}) {
    Controller controller(vehicle);
    QuadrotorModel model(vehicle);
    const Eigen::Vector3d p0(0, 0, 5), p_ref(0, 3, 5);
    model.ResetAt(p0, Eigen::Quaterniond(Eigen::AngleAxisd(yaw_deg / kDeg, Eigen::Vector3d::UnitZ()) *
                                         Eigen::AngleAxisd(25.0 / kDeg, Eigen::Vector3d::UnitX())));
    const auto trace = Fly(&controller, &model, [&](double) { return Hold(p_ref); }, 6.0);
    double max_tilt = 0.0, altitude_loss = 0.0;
    for (const auto& s : trace) {
      max_tilt = std::max(max_tilt, TiltDegOf(s.state.q_WB));
      altitude_loss = std::max(altitude_loss, p0.z() - s.state.p_WB.z());
    }
    const std::string name = "yaw" + std::to_string(static_cast<int>(yaw_deg)) + "_roll25_step";
    Measured(name + "_max_tilt_deg", max_tilt);
    Measured(name + "_max_altitude_loss_m", altitude_loss);
    EXPECT_LT(max_tilt, 35.0 + 3.0);
    EXPECT_LT(altitude_loss, 0.1);
    EXPECT_LT(PositionError(trace.back()), 0.05);
  }
}

TEST(ClosedLoopTest, SaturatedThrustDemandStillYieldsCommandedTorqueSign) {
  // Full-loop version of the mixer priority: with a huge upward demand (far target above),
  // the attitude still corrects an initial 20 deg roll: the achieved roll torque has the sign
  // the controller commanded at every step where it asked for a meaningful torque.
  const VehicleParams vehicle;
  Controller controller(vehicle);
  QuadrotorModel model(vehicle);
  model.ResetAt({0, 0, 0}, Eigen::Quaterniond(Eigen::AngleAxisd(20.0 / kDeg,
                                                                 Eigen::Vector3d::UnitX())));
  const auto trace = Fly(&controller, &model, [&](double) { return Hold({0, 0, 100}); }, 1.0);
  int saturated_steps = 0;
  for (const auto& s : trace) {
    if (s.mix.thrust_clipped || s.output.thrust_limited) ++saturated_steps;
    for (int axis = 0; axis < 2; ++axis) {
      const double asked = s.output.wrench.torque_B[axis];
      if (std::abs(asked) < 1e-3) continue;
      EXPECT_GT(s.mix.achieved.torque_B[axis] * asked, 0.0)
          << "t = " << s.t << " axis " << axis << " asked " << asked;
    }
  }
  Measured("saturated_climb_saturated_steps", saturated_steps);
  EXPECT_GT(saturated_steps, 100) << "the test must actually saturate";
  EXPECT_LT(TiltDegOf(trace.back().state.q_WB), 5.0) << "roll corrected during the climb";
}

}  // namespace
}  // namespace enavi::navstack
