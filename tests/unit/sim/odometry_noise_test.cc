// Imperfect odometry: presets, drift growth, white noise, determinism, validation.

#include "workers/sim/odometry_noise.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

namespace enavi::sim {
namespace {

TEST(OdometryNoise, NoneIsTheTruthExactly) {
  OdometryNoise noise(OdometryNoisePreset("none"), 5);
  navstack::VehicleState s;
  s.p_WB = {1.0, 2.0, 3.0};
  const navstack::VehicleState e = noise.Corrupt(s, 1.0);
  EXPECT_EQ(e.p_WB, s.p_WB);
  EXPECT_EQ(e.q_WB.coeffs(), s.q_WB.coeffs());
}

TEST(OdometryNoise, DriftGrowsAsSqrtTimeAndPresetsAreOrdered) {
  // Over many seeds, the position error's spread at t is sqrt(white^2 + walk^2 t) per axis.
  for (const char* name : {"good", "typical", "poor"}) {
    const OdometryNoiseOptions o = OdometryNoisePreset(name);
    double sum2_1 = 0.0, sum2_16 = 0.0;
    const int seeds = 4000;
    for (int seed = 0; seed < seeds; ++seed) {
      OdometryNoise noise(o, seed);
      navstack::VehicleState s;
      for (int k = 1; k <= 160; ++k) {
        noise.Corrupt(s, 0.1 * k);
        if (k == 10) sum2_1 += noise.last_position_error().x() * noise.last_position_error().x();
      }
      sum2_16 += noise.last_position_error().x() * noise.last_position_error().x();
    }
    const auto expected = [&](double t) {
      return std::sqrt(o.position_white_m * o.position_white_m +
                       o.position_walk_m_per_sqrt_s * o.position_walk_m_per_sqrt_s * t);
    };
    EXPECT_NEAR(std::sqrt(sum2_1 / seeds), expected(1.0), 0.05 * expected(1.0)) << name;
    EXPECT_NEAR(std::sqrt(sum2_16 / seeds), expected(16.0), 0.05 * expected(16.0)) << name;
  }
  EXPECT_LT(OdometryNoisePreset("good").position_walk_m_per_sqrt_s,
            OdometryNoisePreset("typical").position_walk_m_per_sqrt_s);
  EXPECT_LT(OdometryNoisePreset("typical").position_walk_m_per_sqrt_s,
            OdometryNoisePreset("poor").position_walk_m_per_sqrt_s);
}

TEST(OdometryNoise, YawErrorRotatesTheEstimateAboutWorldZ) {
  OdometryNoise noise(OdometryNoisePreset("poor"), 9);
  navstack::VehicleState s;
  s.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  const navstack::VehicleState e = noise.Corrupt(s, 2.0);
  ASSERT_NE(noise.last_yaw_error(), 0.0);
  const Eigen::Vector3d x = e.q_WB * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(std::atan2(x.y(), x.x()), 0.3 + noise.last_yaw_error(), 1e-12);
  EXPECT_EQ(e.v_WB, s.v_WB);
}

TEST(OdometryNoise, SameSeedSameErrors) {
  OdometryNoise a(OdometryNoisePreset("typical"), 3), b(OdometryNoisePreset("typical"), 3);
  OdometryNoise c(OdometryNoisePreset("typical"), 4);
  navstack::VehicleState s;
  const Eigen::Vector3d pa = a.Corrupt(s, 1.0).p_WB, pb = b.Corrupt(s, 1.0).p_WB;
  EXPECT_EQ(pa, pb);
  EXPECT_NE(pa, c.Corrupt(s, 1.0).p_WB);
}

TEST(OdometryNoise, RejectsBadValuesNamingTheField) {
  EXPECT_THROW(OdometryNoisePreset("awful"), std::invalid_argument);
  OdometryNoiseOptions o;
  o.position_walk_m_per_sqrt_s = -0.1;
  try {
    OdometryNoise n(o, 1);
    FAIL() << "accepted a negative walk";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("odometry_noise.position_walk:", 0), 0u) << e.what();
  }
  OdometryNoise n(OdometryNoisePreset("good"), 1);
  navstack::VehicleState s;
  n.Corrupt(s, 1.0);
  EXPECT_THROW(n.Corrupt(s, 0.5), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::sim
