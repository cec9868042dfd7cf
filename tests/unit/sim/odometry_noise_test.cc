// Imperfect odometry: presets, drift growth, white noise, the yaw error, determinism, validation.

#include "workers/sim/odometry_noise.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "api/episode.h"

namespace enavi::sim {
namespace {

TEST(OdometryNoise, NoneIsTheTruthExactly) {
  OdometryNoise noise(OdometryNoisePreset("none"), 5);
  EXPECT_FALSE(noise.active());
  navstack::VehicleState s;
  s.p_WB = {1.0, 2.0, 3.0};
  s.v_WB = {0.5, 0.0, 0.0};
  noise.Update(1.0);
  const navstack::VehicleState e = noise.Apply(s);
  EXPECT_EQ(e.p_WB, s.p_WB);
  EXPECT_EQ(e.v_WB, s.v_WB);
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
      for (int k = 1; k <= 160; ++k) {
        noise.Update(0.1 * k);
        if (k == 10) sum2_1 += noise.position_error().x() * noise.position_error().x();
      }
      sum2_16 += noise.position_error().x() * noise.position_error().x();
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

TEST(OdometryNoise, ErrorIsHeldBetweenUpdates) {
  OdometryNoise noise(OdometryNoisePreset("typical"), 2);
  navstack::VehicleState s;
  noise.Update(0.5);
  const Eigen::Vector3d p1 = noise.Apply(s).p_WB;
  s.p_WB = {1.0, 0.0, 0.0};
  EXPECT_LT((noise.Apply(s).p_WB - s.p_WB - p1).norm(), 1e-12);  // the same error on a moved vehicle
  noise.Update(0.6);
  EXPECT_GT((noise.Apply(s).p_WB - s.p_WB - p1).norm(), 1e-6);
}

TEST(OdometryNoise, YawErrorTurnsTheEstimateAboutWorldZ) {
  OdometryNoise noise(OdometryNoisePreset("poor"), 9);
  navstack::VehicleState s;
  s.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  s.v_WB = {2.0, 0.0, 0.5};
  s.w_WB_B = {0.1, 0.2, 0.3};
  noise.Update(2.0);
  const navstack::VehicleState e = noise.Apply(s);
  ASSERT_NE(noise.yaw_error(), 0.0);
  const Eigen::Vector3d x = e.q_WB * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(std::atan2(x.y(), x.x()), 0.3 + noise.yaw_error(), 1e-12);
  EXPECT_NEAR(std::atan2(e.v_WB.y(), e.v_WB.x()), noise.yaw_error(), 1e-12);
  EXPECT_NEAR(e.v_WB.norm(), s.v_WB.norm(), 1e-12);
  EXPECT_EQ(e.w_WB_B, s.w_WB_B);
}

TEST(OdometryNoise, SameSeedSameErrors) {
  OdometryNoise a(OdometryNoisePreset("typical"), 3), b(OdometryNoisePreset("typical"), 3);
  OdometryNoise c(OdometryNoisePreset("typical"), 4);
  a.Update(1.0);
  b.Update(1.0);
  c.Update(1.0);
  EXPECT_EQ(a.position_error(), b.position_error());
  EXPECT_EQ(a.yaw_error(), b.yaw_error());
  EXPECT_NE(a.position_error(), c.position_error());
}

TEST(OdometryNoise, RejectsBadValuesNamingTheField) {
  try {
    OdometryNoisePreset("awful");
    FAIL() << "accepted an unknown preset";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("odometry_noise: 'awful' is not one of", 0), 0u) << e.what();
  }
  // Every name the spec accepts is a preset here.
  for (const char* name : api::kOdometryNoisePresets) EXPECT_NO_THROW(OdometryNoisePreset(name)) << name;
  OdometryNoiseOptions o;
  o.position_walk_m_per_sqrt_s = -0.1;
  try {
    OdometryNoise n(o, 1);
    FAIL() << "accepted a negative walk";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("odometry_noise.position_walk:", 0), 0u) << e.what();
  }
  OdometryNoise n(OdometryNoisePreset("good"), 1);
  n.Update(1.0);
  EXPECT_THROW(n.Update(0.5), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::sim
