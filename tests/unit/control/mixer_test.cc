// Motor mixer: allocation conventions, round trip through the inverse allocation, and the
// saturation priority (roll/pitch > collective thrust > yaw).

#include "navstack/control/mixer.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace enavi::navstack {
namespace {

constexpr double kTol = 1e-9;

TEST(MixerTest, SingleRotorWrenchFollowsGeometryAndSpin) {
  const VehicleParams vehicle;
  const Mixer mixer(vehicle);
  const auto rotors = vehicle.RotorPositions();
  for (int i = 0; i < 4; ++i) {
    std::array<double, 4> f{};
    f[i] = 2.0;
    const Wrench w = mixer.WrenchFromThrusts(f);
    // Force 2 N along +z at r_i: torque r_i x (0, 0, 2) = (2 y_i, -2 x_i, 0), plus the
    // reaction -spin_i k_m f_i about z.
    EXPECT_NEAR(w.thrust, 2.0, kTol) << "rotor " << i;
    EXPECT_NEAR(w.torque_B.x(), 2.0 * rotors[i].y(), kTol) << "rotor " << i;
    EXPECT_NEAR(w.torque_B.y(), -2.0 * rotors[i].x(), kTol) << "rotor " << i;
    EXPECT_NEAR(w.torque_B.z(), -VehicleParams::kSpin[i] * vehicle.moment_coeff * 2.0, kTol)
        << "rotor " << i;
  }
}

TEST(MixerTest, HoverWrenchGivesEqualRotorSpeeds) {
  const VehicleParams vehicle;
  const Mixer mixer(vehicle);
  const double weight = vehicle.mass * vehicle.Gravity();
  const MixResult mix = mixer.Mix({weight, Eigen::Vector3d::Zero()});
  const double expected = std::sqrt(weight / 4.0 / vehicle.thrust_coeff);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(mix.command.omega[i], expected, 1e-9);
  EXPECT_FALSE(mix.roll_pitch_scaled || mix.thrust_clipped || mix.yaw_clipped);
}

TEST(MixerTest, RoundTripRecoversWrenchWhenUnsaturated) {
  const VehicleParams vehicle;
  const Mixer mixer(vehicle);
  const double f_max = vehicle.MaxThrustPerRotor();
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> rotor_thrust(0.05 * f_max, 0.95 * f_max);
  for (int trial = 0; trial < 500; ++trial) {
    // A wrench that is feasible by construction: the one some in-range thrusts produce.
    std::array<double, 4> f{};
    for (double& fi : f) fi = rotor_thrust(rng);
    const Wrench demand = mixer.WrenchFromThrusts(f);

    const MixResult mix = mixer.Mix(demand);
    ASSERT_FALSE(mix.roll_pitch_scaled || mix.thrust_clipped || mix.yaw_clipped)
        << "trial " << trial << " is feasible and must not saturate";
    const Wrench back = mixer.WrenchFromSpeeds(mix.command);
    EXPECT_NEAR(back.thrust, demand.thrust, 1e-9) << "trial " << trial;
    EXPECT_LT((back.torque_B - demand.torque_B).norm(), 1e-9) << "trial " << trial;
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(mix.thrust[i], f[i], 1e-9) << "trial " << trial;
  }
}

TEST(MixerTest, HugeThrustDemandKeepsRollPitchTorqueExactly) {
  const VehicleParams vehicle;
  const Mixer mixer(vehicle);
  const Wrench demand{200.0, Eigen::Vector3d(0.8, -0.5, 0.1)};
  const MixResult mix = mixer.Mix(demand);

  EXPECT_TRUE(mix.thrust_clipped);
  EXPECT_FALSE(mix.roll_pitch_scaled) << "0.8/-0.5 N m fit in the rotors' range";
  EXPECT_LE(mix.achieved.thrust, 4.0 * vehicle.MaxThrustPerRotor() + 1e-9);
  EXPECT_NEAR(*std::max_element(mix.thrust.begin(), mix.thrust.end()),
              vehicle.MaxThrustPerRotor(), 1e-9)
      << "thrust should be as high as roll/pitch allows: one rotor at its maximum";
  EXPECT_NEAR(mix.achieved.torque_B.x(), 0.8, 1e-9);
  EXPECT_NEAR(mix.achieved.torque_B.y(), -0.5, 1e-9);
  EXPECT_GE(mix.achieved.torque_B.z(), -1e-12) << "yaw may shrink but never flips sign";
  for (int i = 0; i < 4; ++i) {
    EXPECT_LE(mix.command.omega[i], vehicle.omega_max + 1e-9);
    EXPECT_GE(mix.thrust[i], 0.0);
  }
}

TEST(MixerTest, ZeroThrustDemandStillProducesRollPitchTorque) {
  const VehicleParams vehicle;
  const Mixer mixer(vehicle);
  const MixResult mix = mixer.Mix({0.0, Eigen::Vector3d(-0.6, 0.4, 0.0)});
  EXPECT_TRUE(mix.thrust_clipped) << "collective must rise to make room for the torque";
  EXPECT_NEAR(mix.achieved.torque_B.x(), -0.6, 1e-9);
  EXPECT_NEAR(mix.achieved.torque_B.y(), 0.4, 1e-9);
}

TEST(MixerTest, ExcessiveRollPitchIsScaledKeepingDirection) {
  const VehicleParams vehicle;
  const Mixer mixer(vehicle);
  const Eigen::Vector3d tau(10.0, 5.0, 0.0);
  const MixResult mix = mixer.Mix({vehicle.mass * vehicle.Gravity(), tau});
  ASSERT_TRUE(mix.roll_pitch_scaled);
  const Eigen::Vector2d got = mix.achieved.torque_B.head<2>();
  EXPECT_GT(got.x(), 0.0);
  EXPECT_GT(got.y(), 0.0);
  EXPECT_NEAR(got.x() / got.y(), 2.0, 1e-9) << "direction of the roll/pitch torque is kept";
  // The scaled torque uses the rotors' full range: one pair at zero, one at the maximum.
  const auto& f = mix.thrust;
  const double f_max = vehicle.MaxThrustPerRotor();
  const double spread = *std::max_element(f.begin(), f.end()) - *std::min_element(f.begin(), f.end());
  EXPECT_NEAR(spread, f_max, 1e-9);
}

TEST(MixerTest, YawGivesWayBeforeThrustAndRollPitch) {
  const VehicleParams vehicle;
  const Mixer mixer(vehicle);
  const double weight = vehicle.mass * vehicle.Gravity();
  const Wrench demand{weight, Eigen::Vector3d(0.3, 0.2, -5.0)};
  const MixResult mix = mixer.Mix(demand);
  EXPECT_TRUE(mix.yaw_clipped);
  EXPECT_FALSE(mix.thrust_clipped);
  EXPECT_NEAR(mix.achieved.thrust, weight, 1e-9);
  EXPECT_NEAR(mix.achieved.torque_B.x(), 0.3, 1e-9);
  EXPECT_NEAR(mix.achieved.torque_B.y(), 0.2, 1e-9);
  EXPECT_LT(mix.achieved.torque_B.z(), -0.05) << "yaw keeps its sign and what headroom allows";
  EXPECT_GT(mix.achieved.torque_B.z(), -5.0);
}

TEST(MixerTest, NonFiniteDemandIsAContractViolation) {
  const Mixer mixer;
  EXPECT_THROW(mixer.Mix({std::nan(""), Eigen::Vector3d::Zero()}), std::domain_error);
  EXPECT_THROW(mixer.Mix({10.0, Eigen::Vector3d(0, INFINITY, 0)}), std::domain_error);
}

TEST(MixerTest, BadVehicleParametersAreRefusedWithTheFieldName) {
  VehicleParams vehicle;
  vehicle.thrust_coeff = -1.0;
  try {
    Mixer mixer(vehicle);
    FAIL() << "negative thrust_coeff accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("thrust_coeff"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace enavi::navstack
