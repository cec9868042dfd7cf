#include "workers/sim/odometry_noise.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Geometry>

#include "api/episode.h"

namespace enavi::sim {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// sigma of a random walk that reaches `fraction` of a 20 m flight in 10 s (see the header).
double DriftDensity(double fraction) { return fraction * 20.0 / std::sqrt(10.0); }

}  // namespace

OdometryNoiseOptions OdometryNoisePreset(const std::string& name) {
  if (const std::string error = api::OdometryNoiseError(name); !error.empty()) throw std::invalid_argument(error);
  if (name == "good") return {0.01, DriftDensity(0.005), 0.1 * kDeg, 0.05 * kDeg};
  if (name == "typical") return {0.03, DriftDensity(0.015), 0.3 * kDeg, 0.2 * kDeg};
  if (name == "poor") return {0.10, DriftDensity(0.05), 1.0 * kDeg, 0.5 * kDeg};
  return {};  // none
}

OdometryNoise::OdometryNoise(const OdometryNoiseOptions& options, std::uint64_t seed)
    : options_(options), rng_(navstack::rl::DeriveSeed(seed, 0x6f646f6d /* "odom" */)) {
  const auto require = [](double v, const char* field) {
    if (!std::isfinite(v) || v < 0.0) throw std::invalid_argument(std::string(field) + ": must be finite and >= 0");
  };
  require(options.position_white_m, "odometry_noise.position_white");
  require(options.position_walk_m_per_sqrt_s, "odometry_noise.position_walk");
  require(options.yaw_white_rad, "odometry_noise.yaw_white");
  require(options.yaw_walk_rad_per_sqrt_s, "odometry_noise.yaw_walk");
}

void OdometryNoise::Update(double t) {
  if (!options_.Active()) return;
  const double dt = t - t_last_;
  if (!(dt >= 0.0)) throw std::invalid_argument("odometry noise: time went backwards");
  t_last_ = t;
  // Eight draws per update, always, so the stream's position depends only on the update count.
  double n[8];
  for (double& ni : n) ni = rng_.Normal();
  const double root_dt = std::sqrt(dt);
  drift_p_ += options_.position_walk_m_per_sqrt_s * root_dt * Eigen::Vector3d(n[0], n[1], n[2]);
  drift_yaw_ += options_.yaw_walk_rad_per_sqrt_s * root_dt * n[3];
  error_p_ = drift_p_ + options_.position_white_m * Eigen::Vector3d(n[4], n[5], n[6]);
  error_yaw_ = drift_yaw_ + options_.yaw_white_rad * n[7];
}

navstack::VehicleState OdometryNoise::Apply(const navstack::VehicleState& truth) const {
  if (!options_.Active()) return truth;
  const Eigen::AngleAxisd turn(error_yaw_, Eigen::Vector3d::UnitZ());
  navstack::VehicleState estimate = truth;
  estimate.p_WB += error_p_;
  estimate.q_WB = (turn * truth.q_WB).normalized();
  estimate.v_WB = turn * truth.v_WB;
  estimate.a_WB = turn * truth.a_WB;
  return estimate;
}

}  // namespace enavi::sim
