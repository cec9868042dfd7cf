#include "navstack/planning/bspline.h"

#include <cmath>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

namespace enavi::navstack {
namespace {

UniformBspline RandomSpline(int n, double dt, std::uint32_t seed) {
  std::mt19937 rng(seed);
  Eigen::Matrix3Xd q(3, n);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) q(k, i) = 0.5 * i + (rng() % 1000) / 1000.0;
  }
  return UniformBspline(q, dt);
}

TEST(BsplineTest, DerivativesMatchFiniteDifferences) {
  const UniformBspline s = RandomSpline(12, 0.25, 3);
  const double h = 1e-5;
  for (double t : {0.01, 0.3, 0.74, 1.13, 1.26, 2.2}) {  // off the knots (jerk jumps there)
    for (int d = 1; d <= 3; ++d) {
      const Eigen::Vector3d fd = (s.Evaluate(t + h, d - 1) - s.Evaluate(t - h, d - 1)) / (2 * h);
      EXPECT_TRUE(s.Evaluate(t, d).isApprox(fd, 1e-5))
          << "derivative " << d << " at t = " << t << ": " << s.Evaluate(t, d).transpose()
          << " vs finite difference " << fd.transpose();
    }
  }
}

TEST(BsplineTest, IsContinuousAcrossKnotsUpToAcceleration) {
  const UniformBspline s = RandomSpline(9, 0.2, 8);
  for (int k = 1; k < s.num_segments(); ++k) {
    const double t = k * s.dt();
    for (int d = 0; d <= 2; ++d) {
      EXPECT_TRUE(s.Evaluate(t - 1e-9, d).isApprox(s.Evaluate(t + 1e-9, d), 1e-6))
          << "derivative " << d << " at knot " << k;
    }
  }
}

TEST(BsplineTest, StartControlPointsReproduceTheStartState) {
  const Eigen::Vector3d p0(1, -2, 3), v0(0.7, 0.1, -0.4), a0(-1.5, 2.0, 0.3);
  Eigen::Matrix3Xd q(3, 4);
  q.leftCols<3>() = StartControlPoints(p0, v0, a0, 0.2);
  q.col(3) = Eigen::Vector3d(5, 5, 5);
  const UniformBspline s(q, 0.2);
  EXPECT_TRUE(s.Position(0).isApprox(p0, 1e-12));
  EXPECT_TRUE(s.Velocity(0).isApprox(v0, 1e-12));
  EXPECT_TRUE(s.Acceleration(0).isApprox(a0, 1e-12));
}

TEST(BsplineTest, FromPathStartsAtTheStartStateAndEndsAtRestAtTheGoal) {
  const std::vector<Eigen::Vector3d> path = {{0, 0, 1}, {3, 0, 1}, {3, 4, 1.5}};
  const Eigen::Vector3d v0(1.0, -0.5, 0.0), a0(0.4, 0.8, -0.2);
  const UniformBspline s = BsplineFromPath(v0, a0, path, 2.0, 3.0, 0.4);
  EXPECT_TRUE(s.Position(0).isApprox(path.front(), 1e-12));
  EXPECT_LT((s.Velocity(0) - v0).norm(), 1e-12);
  EXPECT_LT((s.Acceleration(0) - a0).norm(), 1e-12);
  const double T = s.duration();
  EXPECT_LT((s.Position(T) - path.back()).norm(), 1e-12);
  EXPECT_LT(s.Velocity(T).norm(), 1e-12);
  EXPECT_LT(s.Acceleration(T).norm(), 1e-12);
  // About the time of a 0.9 v_max / 0.8 a_max trapezoid over the path's 7.03 m.
  const double length = 3.0 + std::sqrt(16.0 + 0.25);
  EXPECT_GT(T, length / 1.8);
  EXPECT_LT(T, length / 1.8 + 2.0);
  // The fit follows the corner of the path within a fraction of a metre.
  double nearest = 1e9;
  for (int i = 0; i <= 400; ++i) nearest = std::min(nearest, (s.Position(T * i / 400) - path[1]).norm());
  EXPECT_LT(nearest, 0.6);
}

// A plan under a speed limit below the flown speed (E-Navi's reaction-constraint fallback): the
// profile brakes from the start speed at 0.8 a_max, so the curve slows down along the path and
// never flies back to knots timed as if it had started at the limit.
TEST(BsplineTest, FromPathStartingAboveTheSpeedLimitBrakesWithoutFlyingBack) {
  const std::vector<Eigen::Vector3d> path = {{0, 0, 1}, {10, 0, 1}};
  const double v_limit = 0.3, a_max = 3.0, v_start = 1.9;
  const UniformBspline s = BsplineFromPath(Eigen::Vector3d(v_start, 0, 0), Eigen::Vector3d::Zero(), path, v_limit,
                                           a_max, 0.4);
  const double T = s.duration();
  double least_vx = 1e9, x_max = -1e9;
  for (int i = 0; i <= 2000; ++i) {
    const double t = T * i / 2000;
    least_vx = std::min(least_vx, s.Velocity(t).x());
    x_max = std::max(x_max, s.Position(t).x());
  }
  EXPECT_GT(least_vx, -0.02) << "the curve flies back along the path";
  EXPECT_LT(x_max, 10.0 + 1e-6);
  // Braking from 1.9 to 0.27 m/s at 0.8 a_max takes 0.68 s; the fit may round it by a knot span.
  // Up to the last three spans: the knot spans that hold the start speed are longer than the final
  // stop from 0.27 m/s (0.11 s), so the fit rounds that stop with a small bump, 35 s into a plan
  // that a replan replaces long before.
  const double t_braked = (v_start - 0.9 * v_limit) / (0.8 * a_max) + 0.5;
  const double t_last = T - 3 * s.dt();
  double fastest_after = 0;
  for (int i = 0; i <= 1000; ++i) {
    const double t = t_braked + (t_last - t_braked) * i / 1000;
    fastest_after = std::max(fastest_after, s.Velocity(t).norm());
  }
  EXPECT_LT(fastest_after, 1.15 * v_limit) << "still above the limit " << t_braked << " s into the plan";
}

TEST(BsplineTest, ZeroLengthPathGivesFourSegmentsThatStopAtThePoint) {
  const std::vector<Eigen::Vector3d> path = {{1, 1, 1}};
  const UniformBspline s = BsplineFromPath(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), path, 2.0, 3.0, 0.4);
  EXPECT_EQ(s.num_segments(), 4);
  EXPECT_LT((s.Position(0.5 * s.duration()) - path[0]).norm(), 1e-12);
}

TEST(BsplineTest, ControlBoundsBoundTheSampledCurve) {
  const UniformBspline s = RandomSpline(15, 0.3, 21);
  const double v_bound = s.MaxControlSpeed(), a_bound = s.MaxControlAcceleration();
  for (int i = 0; i <= 1000; ++i) {
    const double t = s.duration() * i / 1000;
    EXPECT_LE(s.Velocity(t).norm(), v_bound + 1e-9);
    EXPECT_LE(s.Acceleration(t).norm(), a_bound + 1e-9);
  }
}

TEST(BsplineTest, RejectsTooFewControlPoints) {
  EXPECT_THROW(UniformBspline(Eigen::Matrix3Xd::Zero(3, 3), 0.1), std::invalid_argument);
  EXPECT_THROW(UniformBspline(Eigen::Matrix3Xd::Zero(3, 4), 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack
