#include "workers/sim/wind.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace enavi::sim {
namespace {

constexpr double kFtPerM = 1.0 / 0.3048;
constexpr double kMpsPerKt = 1852.0 / 3600.0;

void Require(bool ok, const char* field, const char* reason) {
  if (!ok) throw std::invalid_argument(std::string(field) + ": " + reason);
}

Eigen::Vector3d Horizontal(double speed, double direction_deg) {
  const double a = direction_deg * std::numbers::pi / 180.0;
  return {speed * std::cos(a), speed * std::sin(a), 0.0};
}

// The low-altitude altitude factor 0.177 + 0.000823 h (h in ft, floored).
double AltitudeFactor(double altitude_m) {
  const double h_ft = std::max(altitude_m * kFtPerM, WindField::kMinAltitudeFt);
  return 0.177 + 0.000823 * std::min(h_ft, 1000.0);
}

}  // namespace

Turbulence ParseTurbulence(const std::string& name) {
  if (name == "none") return Turbulence::kNone;
  if (name == "light") return Turbulence::kLight;
  if (name == "moderate") return Turbulence::kModerate;
  if (name == "severe") return Turbulence::kSevere;
  throw std::invalid_argument("'" + name + "' is not one of none, light, moderate, severe");
}

const char* TurbulenceName(Turbulence t) {
  switch (t) {
    case Turbulence::kLight: return "light";
    case Turbulence::kModerate: return "moderate";
    case Turbulence::kSevere: return "severe";
    case Turbulence::kNone: break;
  }
  return "none";
}

double TurbulenceW20(Turbulence t) {
  switch (t) {
    case Turbulence::kLight: return 15.0 * kMpsPerKt;
    case Turbulence::kModerate: return 30.0 * kMpsPerKt;
    case Turbulence::kSevere: return 45.0 * kMpsPerKt;
    case Turbulence::kNone: break;
  }
  return 0.0;
}

Eigen::Vector3d WindField::ScaleLengths(double altitude_m) {
  const double f = AltitudeFactor(altitude_m);
  const double h_ft = std::max(altitude_m * kFtPerM, kMinAltitudeFt);
  const double L_uv_ft = h_ft / std::pow(f, 1.2);
  return Eigen::Vector3d(L_uv_ft, L_uv_ft, h_ft) / kFtPerM;
}

Eigen::Vector3d WindField::Intensities(Turbulence t, double altitude_m) {
  const double sigma_w = 0.1 * TurbulenceW20(t);
  const double sigma_uv = sigma_w / std::pow(AltitudeFactor(altitude_m), 0.4);
  return {sigma_uv, sigma_uv, sigma_w};
}

double WindField::GustSpeed(const api::GustSpec& g, double t) {
  if (g.speed_mps <= 0.0 || t <= g.start_s) return 0.0;
  const double s = t - g.start_s;
  const double half = 0.5 * g.speed_mps;
  if (s < g.rise_s) return half * (1.0 - std::cos(std::numbers::pi * s / g.rise_s));
  if (s < g.rise_s + g.hold_s) return g.speed_mps;
  const double d = s - g.rise_s - g.hold_s;
  if (d < g.rise_s) return half * (1.0 + std::cos(std::numbers::pi * d / g.rise_s));
  return 0.0;
}

double DrydenTransverseStep(Eigen::Vector2d* x, double a, double dt, double n1, double n2) {
  // Exact discretisation: x(k+1) = e^{A dt} x(k) + w, A = [[-a, 0], [1, -a]],
  // e^{A dt} = e^{-a dt} [[1, 0], [dt, 1]], Cov(w) = q^2 int_0^dt e^{-2 a s} [[1, s], [s, s^2]] ds.
  const double q2 = 1.0 / a;
  const double b = 2.0 * a, bh = b * dt, e = std::exp(-bh);
  const double I0 = -std::expm1(-bh) / b;
  const double I1 = (1.0 - e * (1.0 + bh)) / (b * b);
  const double I2 = (2.0 - e * (bh * bh + 2.0 * bh + 2.0)) / (b * b * b);
  const double L11 = std::sqrt(q2 * I0);
  const double L21 = q2 * I1 / L11;
  const double L22 = std::sqrt(std::max(q2 * I2 - L21 * L21, 0.0));
  const double phi = std::exp(-a * dt);
  const Eigen::Vector2d prev = *x;
  (*x)(0) = phi * prev(0) + L11 * n1;
  (*x)(1) = phi * (dt * prev(0) + prev(1)) + L21 * n1 + L22 * n2;
  return std::sqrt(3.0) * a * (*x)(0) + (1.0 - std::sqrt(3.0)) * a * a * (*x)(1);
}

WindField::WindField(const api::WindSpec& wind, double dt, std::uint64_t seed)
    : spec_(wind), dt_(dt), rng_(navstack::rl::DeriveSeed(seed, 0x77696e64 /* "wind" */)) {
  if (const std::string error = api::WindSpecError(spec_); !error.empty()) throw std::invalid_argument(error);
  Require(std::isfinite(dt) && dt > 0.0, "dt", "must be > 0");
  turbulence_ = ParseTurbulence(spec_.turbulence);
  mean_W_ = Horizontal(spec_.speed_mps, spec_.direction_deg);
  axis_u_W_ = Horizontal(1.0, spec_.direction_deg);
  air_W_ = mean_W_;
}

Eigen::Vector3d WindField::Step(double altitude_m, const Eigen::Vector3d& v_W) {
  t_ += dt_;
  Eigen::Vector3d air = mean_W_;
  air += Horizontal(GustSpeed(spec_.gust, t_), spec_.gust.direction_deg);
  if (turbulence_ != Turbulence::kNone) {
    const double V = std::max((v_W - mean_W_).norm(), kMinRelativeSpeed);
    const Eigen::Vector3d L = ScaleLengths(altitude_m);
    const Eigen::Vector3d sigma = Intensities(turbulence_, altitude_m);
    // Always five draws per step, so the stream position depends only on the step count.
    double n[5];
    for (double& ni : n) ni = rng_.Normal();
    const double phi_u = std::exp(-V * dt_ / L(0));
    u_ = phi_u * u_ + std::sqrt(-std::expm1(-2.0 * V * dt_ / L(0))) * n[0];
    const double yv = DrydenTransverseStep(&xv_, V / L(1), dt_, n[1], n[2]);
    const double yw = DrydenTransverseStep(&xw_, V / L(2), dt_, n[3], n[4]);
    const Eigen::Vector3d axis_v_W = Eigen::Vector3d::UnitZ().cross(axis_u_W_);
    air += sigma(0) * u_ * axis_u_W_ + sigma(1) * yv * axis_v_W;
    air.z() += sigma(2) * yw;
  }
  air_W_ = air;
  return air_W_;
}

}  // namespace enavi::sim
