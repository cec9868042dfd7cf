#include "navstack/planning/bspline.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/Cholesky>

namespace enavi::navstack {
namespace {

// Weight of the control-point acceleration regulariser of FitBspline (relative to the position
// residuals, both in metres): damps the ringing of pure interpolation without visible bias.
constexpr double kFitRegularisation = 1e-2;

// Polyline with cumulative arc length, for "the point at arc length s".
class Polyline {
 public:
  explicit Polyline(const std::vector<Eigen::Vector3d>& points) : p_(points), s_(points.size(), 0.0) {
    for (std::size_t i = 1; i < p_.size(); ++i) s_[i] = s_[i - 1] + (p_[i] - p_[i - 1]).norm();
  }
  double length() const { return s_.back(); }
  Eigen::Vector3d At(double s) const {
    if (s <= 0.0) return p_.front();
    if (s >= length()) return p_.back();
    const auto it = std::upper_bound(s_.begin(), s_.end(), s);
    const std::size_t i = static_cast<std::size_t>(it - s_.begin());  // s_[i-1] <= s < s_[i]
    const double seg = s_[i] - s_[i - 1];
    const double w = seg > 0.0 ? (s - s_[i - 1]) / seg : 0.0;
    return p_[i - 1] + w * (p_[i] - p_[i - 1]);
  }
  // Unit direction of the first non-degenerate segment (zero if none).
  Eigen::Vector3d StartDirection() const {
    for (std::size_t i = 1; i < p_.size(); ++i) {
      const Eigen::Vector3d d = p_[i] - p_[0];
      if (d.norm() > 1e-9) return d.normalized();
    }
    return Eigen::Vector3d::Zero();
  }

 private:
  const std::vector<Eigen::Vector3d>& p_;
  std::vector<double> s_;
};

// Trapezoidal (or triangular, or decelerate-only) speed profile along a path of length L from
// speed v_s to rest: s(t) for t in [0, T]. A start above the peak speed (a plan under a speed
// limit below the flown speed) first brakes to the peak at `accel`: timing the path as if it
// started at the peak would put the knots behind a curve that must keep v_s, and the fit would
// fly back to them.
class SpeedProfile {
 public:
  SpeedProfile(double length, double v_start, double v_peak, double accel) : L_(length) {
    if (L_ <= 0.0) return;
    v_s_ = std::max(0.0, v_start);
    a_ = accel;
    if (v_s_ * v_s_ / (2.0 * a_) >= L_) {
      // Too fast to stop at a: decelerate uniformly so that the path ends at rest.
      v_c_ = v_s_;
      a_dec_ = v_s_ * v_s_ / (2.0 * L_);
      t1_ = 0.0;
      t2_ = 0.0;
      t3_ = 2.0 * L_ / v_s_;
    } else {
      v_c_ = std::min(v_peak, std::sqrt((2.0 * a_ * L_ + v_s_ * v_s_) / 2.0));
      if (v_s_ > v_c_) a_ = -accel;  // brake to the peak first
      a_dec_ = accel;
      const double d1 = (v_c_ * v_c_ - v_s_ * v_s_) / (2.0 * a_);
      const double d3 = v_c_ * v_c_ / (2.0 * a_dec_);
      t1_ = (v_c_ - v_s_) / a_;
      t2_ = std::max(0.0, L_ - d1 - d3) / v_c_;
      t3_ = v_c_ / a_dec_;
    }
  }
  double duration() const { return t1_ + t2_ + t3_; }
  double ArcLength(double t) const {
    if (L_ <= 0.0) return 0.0;
    if (t <= 0.0) return 0.0;
    if (t < t1_) return v_s_ * t + 0.5 * a_ * t * t;
    const double s1 = v_s_ * t1_ + 0.5 * a_ * t1_ * t1_;
    if (t < t1_ + t2_) return s1 + v_c_ * (t - t1_);
    const double s2 = s1 + v_c_ * t2_;
    const double tau = std::min(t - t1_ - t2_, t3_);
    return std::min(L_, s2 + v_c_ * tau - 0.5 * a_dec_ * tau * tau);
  }

 private:
  double L_;
  double v_s_ = 0.0, v_c_ = 0.0, a_ = 1.0, a_dec_ = 1.0;  ///< a_: signed, of the first phase
  double t1_ = 0.0, t2_ = 0.0, t3_ = 0.0;
};

}  // namespace

UniformBspline::UniformBspline(Eigen::Matrix3Xd control_points, double dt)
    : q_(std::move(control_points)), dt_(dt) {
  if (q_.cols() < 4 || !(dt_ > 0.0) || !std::isfinite(dt_) || !q_.allFinite()) {
    std::ostringstream msg;
    msg << "UniformBspline: needs >= 4 finite control points and dt > 0 (got " << q_.cols()
        << " control points, dt = " << dt_ << ")";
    throw std::invalid_argument(msg.str());
  }
}

Eigen::Vector4d UniformBspline::Basis(double u, int derivative) {
  const double u2 = u * u, u3 = u2 * u, m = 1.0 - u;
  switch (derivative) {
    case 0:
      return Eigen::Vector4d(m * m * m, 3 * u3 - 6 * u2 + 4, -3 * u3 + 3 * u2 + 3 * u + 1, u3) / 6.0;
    case 1:
      return Eigen::Vector4d(-3 * m * m, 9 * u2 - 12 * u, -9 * u2 + 6 * u + 3, 3 * u2) / 6.0;
    case 2:
      return Eigen::Vector4d(6 * m, 18 * u - 12, -18 * u + 6, 6 * u) / 6.0;
    case 3:
      return Eigen::Vector4d(-1.0, 3.0, -3.0, 1.0);
    default:
      throw std::invalid_argument("UniformBspline::Basis: derivative must be 0..3");
  }
}

Eigen::Vector3d UniformBspline::Evaluate(double t, int derivative) const {
  const int m = num_segments();
  const double x = std::clamp(t, 0.0, duration()) / dt_;
  const int i = std::min(static_cast<int>(std::floor(x)), m - 1);
  const Eigen::Vector4d w = Basis(x - i, derivative);
  const Eigen::Vector3d sum = q_.middleCols<4>(i) * w;
  return derivative == 0 ? sum : Eigen::Vector3d(sum / std::pow(dt_, derivative));
}

double UniformBspline::MaxControlSpeed(int first_v) const {
  double best = 0.0;
  for (int i = std::max(first_v, 0); i + 1 < q_.cols(); ++i) {
    best = std::max(best, (q_.col(i + 1) - q_.col(i)).norm() / dt_);
  }
  return best;
}

double UniformBspline::MaxControlAcceleration(int first_a) const {
  double best = 0.0;
  for (int i = std::max(first_a, 0); i + 2 < q_.cols(); ++i) {
    best = std::max(best, (q_.col(i + 2) - 2.0 * q_.col(i + 1) + q_.col(i)).norm() / (dt_ * dt_));
  }
  return best;
}

Eigen::Matrix3d StartControlPoints(const Eigen::Vector3d& p0, const Eigen::Vector3d& v0,
                                   const Eigen::Vector3d& a0, double dt) {
  // Inverse of the start conditions in the class comment.
  Eigen::Matrix3d q;
  q.col(0) = p0 - v0 * dt + a0 * (dt * dt / 3.0);
  q.col(1) = p0 - a0 * (dt * dt / 6.0);
  q.col(2) = p0 + v0 * dt + a0 * (dt * dt / 3.0);
  return q;
}

UniformBspline FitBspline(const Eigen::Vector3d& p0, const Eigen::Vector3d& v0,
                          const Eigen::Vector3d& a0,
                          const std::vector<Eigen::Vector3d>& knot_targets,
                          const Eigen::Vector3d& p_end, double dt) {
  const int m = static_cast<int>(knot_targets.size()) + 1;
  if (m < 4 || !(dt > 0.0)) {
    throw std::invalid_argument("FitBspline: needs >= 3 knot targets (4 segments) and dt > 0");
  }
  const int n = m + 3;
  Eigen::Matrix3Xd q(3, n);
  q.leftCols<3>() = StartControlPoints(p0, v0, a0, dt);
  for (int j = m; j < n; ++j) q.col(j) = p_end;
  const int free_first = 3, num_free = m - 3;

  // Rows: knot positions k = 1..m-1, then sqrt(lambda) * control-point second differences.
  const int rows = (m - 1) + (n - 2);
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(rows, n);
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(rows, 3);
  for (int k = 1; k <= m - 1; ++k) {
    g(k - 1, k) = 1.0 / 6.0;
    g(k - 1, k + 1) = 4.0 / 6.0;
    g(k - 1, k + 2) = 1.0 / 6.0;
    y.row(k - 1) = knot_targets[k - 1].transpose();
  }
  const double r = std::sqrt(kFitRegularisation);
  for (int i = 0; i + 2 < n; ++i) {
    g(m - 1 + i, i) = r;
    g(m - 1 + i, i + 1) = -2.0 * r;
    g(m - 1 + i, i + 2) = r;
  }
  // Move the fixed columns to the right-hand side and solve the normal equations for the rest.
  const Eigen::MatrixXd g_free = g.middleCols(free_first, num_free);
  Eigen::MatrixXd rhs = y;
  for (int j = 0; j < n; ++j) {
    if (j >= free_first && j < free_first + num_free) continue;
    rhs -= g.col(j) * q.col(j).transpose();
  }
  const Eigen::MatrixXd h = g_free.transpose() * g_free;
  const Eigen::MatrixXd x = h.ldlt().solve(g_free.transpose() * rhs);
  q.middleCols(free_first, num_free) = x.transpose();
  return UniformBspline(std::move(q), dt);
}

UniformBspline BsplineFromPath(const Eigen::Vector3d& v0, const Eigen::Vector3d& a0,
                               const std::vector<Eigen::Vector3d>& path, double v_max,
                               double a_max, double control_point_spacing) {
  if (path.empty() || !(v_max > 0.0) || !(a_max > 0.0) || !(control_point_spacing > 0.0)) {
    throw std::invalid_argument(
        "BsplineFromPath: needs a non-empty path and positive v_max, a_max, control_point_spacing");
  }
  const Polyline line(path);
  // Time the path with a feasible-by-construction profile, below the limits so the optimiser
  // has room.
  const Eigen::Vector3d dir = line.StartDirection();
  const double v_along = std::max(0.0, v0.dot(dir));
  const SpeedProfile profile(line.length(), v_along, 0.9 * v_max, 0.8 * a_max);
  // A start velocity away from the path (or any, for a zero-length path) must be braked first and
  // its overshoot v^2 / 2a flown back: the whole profile is slowed down to last that long.
  // (Sideways velocity is braked while flying on; the optimiser handles it.)
  const double v_back = dir.isZero() ? v0.norm() : std::max(0.0, -v0.dot(dir));
  const double a_profile = 0.8 * a_max;
  const double t_profile = profile.duration();
  double t_total = t_profile;
  if (v_back > 1e-9) {
    const double overshoot = v_back * v_back / (2.0 * a_profile);
    t_total = v_back / a_profile +
              SpeedProfile(line.length() + overshoot, 0.0, 0.9 * v_max, a_profile).duration();
  }
  const double time_scale = t_total > 0.0 ? t_profile / t_total : 1.0;
  // Control points about control_point_spacing apart at the profile's fastest: a start above the
  // limit is braked within knot spans short enough to hold it.
  const double dt_nominal = control_point_spacing / std::max(v_max, v_along);
  int m = static_cast<int>(std::ceil(t_total / dt_nominal - 1e-9));
  double dt = m > 0 ? t_total / m : dt_nominal;
  if (m < 4) {
    m = 4;
    dt = dt_nominal;
  }
  std::vector<Eigen::Vector3d> targets;
  targets.reserve(m - 1);
  for (int k = 1; k < m; ++k) targets.push_back(line.At(profile.ArcLength(k * dt * time_scale)));
  return FitBspline(path.front(), v0, a0, targets, path.back(), dt);
}

}  // namespace enavi::navstack
