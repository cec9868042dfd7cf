#include "worlds/detmath.h"

#include <cmath>

#include <gtest/gtest.h>

namespace enavi::worlds {
namespace {

TEST(DetmathTest, SinCosAgreeWithLibmToAFewUlps) {
  for (int i = -20000; i <= 20000; ++i) {
    const double x = i * 0.000731 * 7.0;  // about +-100 rad, irregular steps
    double s, c;
    detmath::SinCos(x, &s, &c);
    EXPECT_NEAR(s, std::sin(x), 4e-16 * (1.0 + std::abs(x))) << "x = " << x;
    EXPECT_NEAR(c, std::cos(x), 4e-16 * (1.0 + std::abs(x))) << "x = " << x;
  }
}

TEST(DetmathTest, ExactAtZeroAndQuadrants) {
  EXPECT_EQ(detmath::Sin(0.0), 0.0);
  EXPECT_EQ(detmath::Cos(0.0), 1.0);
  EXPECT_NEAR(detmath::Sin(0.5 * detmath::kPi), 1.0, 1e-16);
  EXPECT_NEAR(detmath::Cos(detmath::kPi), -1.0, 1e-16);
  EXPECT_NEAR(detmath::Sin(1.5 * detmath::kPi), -1.0, 1e-16);
}

TEST(DetmathTest, QuantizeRoundsToTheFilePrecisionAndDropsNegativeZero) {
  EXPECT_EQ(detmath::Quantize(1.23456), 1.2346);
  EXPECT_EQ(detmath::Quantize(-1.23454), -1.2345);
  const double z = detmath::Quantize(-0.00001);
  EXPECT_EQ(z, 0.0);
  EXPECT_FALSE(std::signbit(z)) << "-0 must be normalised to +0";
}

}  // namespace
}  // namespace enavi::worlds
