#pragma once
// The air the vehicle flies in: mean wind, a discrete "1-cosine" gust and Dryden continuous
// turbulence (MIL-F-8785C / MIL-HDBK-1797, low-altitude model), sampled once per physics step.
// The navigation stack never sees this; only the vehicle's drag does.

#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "api/episode.h"
#include "navstack/rl/random.h"

namespace enavi::sim {

/// Turbulence severity of MIL-F-8785C Sec. 3.7.2.3 (low altitude, below 1000 ft): the wind speed
/// at 20 ft, W20, that sets the intensities is 15 kt (light), 30 kt (moderate), 45 kt (severe).
enum class Turbulence { kNone, kLight, kModerate, kSevere };

/// The severity of one of api::kTurbulenceLevels.
/// @throws std::invalid_argument naming the accepted names for anything else.
Turbulence ParseTurbulence(const std::string& name);
const char* TurbulenceName(Turbulence t);
/// W20 of the severity, m/s (0 for kNone).
double TurbulenceW20(Turbulence t);

/// Dryden forming filters driven by seeded white noise, discretised exactly for the step dt: the
/// sampled sequence has exactly the continuous model's variance and autocorrelation at multiples
/// of dt (not an Euler approximation), for any dt.
///
/// Low-altitude model (MIL-F-8785C Sec. 3.7.2.3, MIL-HDBK-1797 Sec. 4.9.1 "Turbulence models"),
/// h in feet, turbulence axes u along the mean wind, v across it, w vertical:
///   L_w = h,   L_u = L_v = h / (0.177 + 0.000823 h)^1.2
///   sigma_w = 0.1 W20,   sigma_u = sigma_v = sigma_w / (0.177 + 0.000823 h)^0.4
///   Phi_u(Omega) = sigma_u^2 (2 L_u / pi) / (1 + (L_u Omega)^2)                  (first order)
///   Phi_v(Omega) = sigma_v^2 (L_v / pi) (1 + 3 (L_v Omega)^2) / (1 + (L_v Omega)^2)^2  (and w)
/// Taylor's frozen-field hypothesis turns the spatial frequency Omega into time through the speed
/// V of the vehicle relative to the mean air. The standard is written for aircraft, which never
/// hover: V is floored at kMinRelativeSpeed and h at kMinAltitudeFt (the scale lengths vanish at
/// the ground), both our choices, not the standard's.
class WindField {
 public:
  static constexpr double kMinRelativeSpeed = 1.0;  ///< m/s
  static constexpr double kMinAltitudeFt = 10.0;

  /// The mean wind, gust and turbulence of `wind`, stepped by dt, its noise seeded by `seed`.
  /// @throws std::invalid_argument with api::WindSpecError's message, or for dt <= 0.
  WindField(const api::WindSpec& wind, double dt, std::uint64_t seed);

  /// Advances one step of dt at altitude_m (above ground) with the vehicle's velocity v_W and
  /// returns the air velocity at the new instant, world frame (m/s).
  Eigen::Vector3d Step(double altitude_m, const Eigen::Vector3d& v_W);
  /// Air velocity of the last Step() (zero before the first).
  const Eigen::Vector3d& air_velocity_W() const { return air_W_; }
  double time() const { return t_; }
  const api::WindSpec& spec() const { return spec_; }

  /// Scale lengths (u, v, w) and intensities (u, v, w), metres and m/s, at altitude_m.
  static Eigen::Vector3d ScaleLengths(double altitude_m);
  static Eigen::Vector3d Intensities(Turbulence t, double altitude_m);
  /// The gust's speed at time t, m/s: (speed / 2)(1 - cos(pi (t - start) / rise)) rising, then
  /// held, then the mirrored fall (MIL-F-8785C Sec. 3.7.5 "1-cosine", in time instead of distance).
  static double GustSpeed(const api::GustSpec& gust, double t);

 private:
  api::WindSpec spec_;
  Turbulence turbulence_ = Turbulence::kNone;
  double dt_;
  double t_ = 0.0;
  navstack::rl::Rng rng_;
  Eigen::Vector3d mean_W_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_u_W_ = Eigen::Vector3d::UnitX();  ///< turbulence u axis (mean wind's)
  double u_ = 0.0;                                       ///< first-order state of u
  Eigen::Vector2d xv_ = Eigen::Vector2d::Zero();          ///< second-order states of v
  Eigen::Vector2d xw_ = Eigen::Vector2d::Zero();          ///< and of w
  Eigen::Vector3d air_W_ = Eigen::Vector3d::Zero();
};

/// Exact one-step update of the unit-variance second-order Dryden filter (shared by v and w):
/// states x1' = -a x1 + q n, x2' = -a x2 + x1 with a = V / L, output y = sqrt(3) a x1 +
/// (1 - sqrt(3)) a^2 x2 whose spectrum is the Dryden transverse shape; q = 1 / sqrt(a) gives
/// Var(y) = 1. n1, n2 are independent standard normals. Returns y after the step.
double DrydenTransverseStep(Eigen::Vector2d* x, double a, double dt, double n1, double n2);

}  // namespace enavi::sim
