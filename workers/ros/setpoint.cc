#include "workers/ros/setpoint.h"

#include <cmath>

#include "api/fixed.h"

namespace enavi::ros {
namespace {

bool Finite(const Eigen::Vector3d& v) { return v.allFinite(); }

std::string Vec(const Eigen::Vector3d& v) {
  return "(" + api::Fixed(v.x(), 3) + ", " + api::Fixed(v.y(), 3) + ", " + api::Fixed(v.z(), 3) + ")";
}

}  // namespace

double YawOf(const Eigen::Quaterniond& q) {
  return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()), 1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
}

std::optional<std::string> CheckCommand(const Command& command, const CommandLimits& limits) {
  if (command.points.empty()) return command.type + " with no points";
  for (std::size_t i = 0; i < command.points.size(); ++i) {
    const Setpoint& s = command.points[i];
    const std::string at = command.points.size() > 1 ? "point " + std::to_string(i) + ": " : "";
    if (!std::isfinite(s.t)) return at + "time is not finite";
    if (!Finite(s.p)) return at + "position is not finite";
    if (!Finite(s.v)) return at + "velocity is not finite";
    if (!Finite(s.a)) return at + "acceleration is not finite";
    if (!std::isfinite(s.yaw) || !std::isfinite(s.yaw_rate)) return at + "yaw or yaw rate is not finite";
    const Eigen::Vector3d margin = Eigen::Vector3d::Constant(limits.margin_m);
    if (!limits.bounds.isEmpty()) {
      const Eigen::AlignedBox3d allowed(limits.bounds.min() - margin, limits.bounds.max() + margin);
      if (!allowed.contains(s.p))
        return at + "position " + Vec(s.p) + " is more than " + api::Fixed(limits.margin_m, 1) +
               " m outside the world's bounds " + Vec(limits.bounds.min()) + " - " + Vec(limits.bounds.max());
    }
    if (s.v.norm() > limits.v_max)
      return at + "velocity " + api::Fixed(s.v.norm(), 2) + " m/s is above " + api::Fixed(limits.v_max, 0) + " m/s";
    if (s.a.norm() > limits.a_max)
      return at + "acceleration " + api::Fixed(s.a.norm(), 2) + " m/s^2 is above " + api::Fixed(limits.a_max, 0) +
             " m/s^2";
    if (std::abs(s.yaw_rate) > limits.yaw_rate_max)
      return at + "yaw rate " + api::Fixed(s.yaw_rate, 2) + " rad/s is above " + api::Fixed(limits.yaw_rate_max, 0) +
             " rad/s";
    if (i > 0 && s.t < command.points[i - 1].t) return at + "time goes backwards";
  }
  return std::nullopt;
}

navstack::TrajectorySample SampleCommand(const Command& command, double t) {
  auto sample = [](const Setpoint& s) {
    navstack::TrajectorySample r;
    r.p = s.p;
    r.v = s.v;
    r.a = s.a;
    r.yaw = s.yaw;
    r.yaw_rate = s.yaw_rate;
    return r;
  };
  const std::vector<Setpoint>& pts = command.points;
  if (pts.size() == 1 || t <= pts.front().t) return sample(pts.front());
  if (t >= pts.back().t) return sample(pts.back());
  std::size_t i = 1;
  while (pts[i].t < t) ++i;
  const Setpoint& a = pts[i - 1];
  const Setpoint& b = pts[i];
  const double span = b.t - a.t;
  const double w = span > 0 ? (t - a.t) / span : 1.0;
  navstack::TrajectorySample r;
  r.p = a.p + w * (b.p - a.p);
  r.v = a.v + w * (b.v - a.v);
  r.a = a.a + w * (b.a - a.a);
  r.yaw = navstack::WrapAngle(a.yaw + w * navstack::WrapAngle(b.yaw - a.yaw));
  r.yaw_rate = a.yaw_rate + w * (b.yaw_rate - a.yaw_rate);
  return r;
}

}  // namespace enavi::ros
