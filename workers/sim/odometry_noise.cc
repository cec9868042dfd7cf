#include "workers/sim/odometry_noise.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Geometry>

namespace enavi::sim {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// sigma of a random walk that reaches `fraction` of a 20 m flight in 10 s (see the header).
constexpr double DriftDensity(double fraction) { return fraction * 20.0 / 3.1622776601683795; }

}  // namespace

OdometryNoiseOptions OdometryNoisePreset(const std::string& name) {
  if (name == "none") return {};
  if (name == "good") return {0.01, DriftDensity(0.005), 0.1 * kDeg, 0.05 * kDeg};
  if (name == "typical") return {0.03, DriftDensity(0.015), 0.3 * kDeg, 0.2 * kDeg};
  if (name == "poor") return {0.10, DriftDensity(0.05), 1.0 * kDeg, 0.5 * kDeg};
  throw std::invalid_argument("'" + name + "' is not one of none, good, typical, poor");
}

void ValidateOdometryNoise(const OdometryNoiseOptions& o) {
  const auto require = [](double v, const char* field) {
    if (!std::isfinite(v) || v < 0.0) {
      throw std::invalid_argument(std::string(field) + ": must be finite and >= 0");
    }
  };
  require(o.position_white_m, "odometry_noise.position_white");
  require(o.position_walk_m_per_sqrt_s, "odometry_noise.position_walk");
  require(o.yaw_white_rad, "odometry_noise.yaw_white");
  require(o.yaw_walk_rad_per_sqrt_s, "odometry_noise.yaw_walk");
}

OdometryNoise::OdometryNoise(const OdometryNoiseOptions& options, std::uint64_t seed)
    : options_(options), rng_(navstack::rl::DeriveSeed(seed, 0x6f646f6d /* "odom" */)) {
  ValidateOdometryNoise(options_);
}

navstack::VehicleState OdometryNoise::Corrupt(const navstack::VehicleState& truth, double t) {
  if (!options_.Active()) {
    last_dp_.setZero();
    last_dyaw_ = 0.0;
    return truth;
  }
  const double dt = t - t_last_;
  if (!(dt >= 0.0)) throw std::invalid_argument("odometry noise: time went backwards");
  t_last_ = t;
  // Eight draws per call, always, so the stream position depends only on the number of calls.
  double n[8];
  for (double& ni : n) ni = rng_.Normal();
  const double sw = options_.position_walk_m_per_sqrt_s * std::sqrt(dt);
  drift_p_ += sw * Eigen::Vector3d(n[0], n[1], n[2]);
  drift_yaw_ += options_.yaw_walk_rad_per_sqrt_s * std::sqrt(dt) * n[3];
  last_dp_ = drift_p_ + options_.position_white_m * Eigen::Vector3d(n[4], n[5], n[6]);
  last_dyaw_ = drift_yaw_ + options_.yaw_white_rad * n[7];

  navstack::VehicleState est = truth;
  est.p_WB += last_dp_;
  est.q_WB = (Eigen::AngleAxisd(last_dyaw_, Eigen::Vector3d::UnitZ()) * truth.q_WB).normalized();
  return est;
}

}  // namespace enavi::sim
