#include "worlds/movers.h"

#include <cmath>
#include <stdexcept>

#include "worlds/detmath.h"
#include "worlds/primitives.h"

namespace enavi::worlds {
namespace {

// The yaw b seen from a: b - a wrapped into (-pi, pi], so interpolation turns the short way.
double YawStep(double a, double b) {
  double d = std::fmod(b - a, 2.0 * detmath::kPi);
  if (d > detmath::kPi) d = d - 2.0 * detmath::kPi;
  if (d <= -detmath::kPi) d = d + 2.0 * detmath::kPi;
  return d;
}

}  // namespace

Eigen::Isometry3d MoverPose::Transform() const {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() << cos_yaw, -sin_yaw, 0.0, sin_yaw, cos_yaw, 0.0, 0.0, 0.0, 1.0;
  X.translation() = position;
  return X;
}

Eigen::Vector3d MoverPose::ToWorld(const Eigen::Vector3d& p_M) const {
  return {position.x() + (cos_yaw * p_M.x() - sin_yaw * p_M.y()),
          position.y() + (sin_yaw * p_M.x() + cos_yaw * p_M.y()), position.z() + p_M.z()};
}

MoverTrajectory::MoverTrajectory(const Mover& mover)
    : timed_(!(mover.speed > 0.0)), mode_(mover.mode), delay_(mover.start_delay) {
  const auto& w = mover.waypoints;
  if (w.size() < 2) throw std::invalid_argument("mover '" + mover.name + "': needs at least two waypoints");
  if (timed_) {
    for (std::size_t i = 0; i < w.size(); ++i) {
      if (i > 0 && !(w[i].t > w[i - 1].t)) {
        throw std::invalid_argument("mover '" + mover.name + "': waypoint times must increase");
      }
      Knot k{w[i].position, w[i].t, w[i].yaw, 1.0, 0.0};
      detmath::SinCos(w[i].yaw, &k.s, &k.c);
      knots_.push_back(k);
    }
    leg_ = knots_.back().t;
  } else {
    std::vector<Eigen::Vector3d> points;
    for (const auto& p : w) points.push_back(p.position);
    if (mover.mode == MoverMode::kLoop && points.back() != points.front()) points.push_back(points.front());
    double t = 0.0, c = 1.0, s = 0.0;
    bool heading_known = false;
    for (std::size_t i = 0; i < points.size(); ++i) {
      Knot k{points[i], t, 0.0, c, s};
      if (i + 1 < points.size()) {
        const Eigen::Vector3d d = points[i + 1] - points[i];
        const double horizontal = std::sqrt(d.x() * d.x() + d.y() * d.y());
        if (horizontal > 0.0) {
          k.c = d.x() / horizontal;
          k.s = d.y() / horizontal;
          if (!heading_known) {
            // A path that starts vertically takes the first horizontal heading from the start.
            for (auto& earlier : knots_) earlier.c = k.c, earlier.s = k.s;
            heading_known = true;
          }
        }
        t = t + std::sqrt(horizontal * horizontal + d.z() * d.z()) / mover.speed;
      }
      c = k.c;
      s = k.s;
      knots_.push_back(k);
    }
    leg_ = knots_.back().t;
    if (!(leg_ > 0.0)) throw std::invalid_argument("mover '" + mover.name + "': its path has no length");
  }
  period_ = mode_ == MoverMode::kBackAndForth ? 2.0 * leg_ : leg_;
}

MoverPose MoverTrajectory::AtLeg(double u, bool back) const {
  MoverPose pose;
  // The segment [i, i + 1] holding u (knots are few: a linear scan).
  std::size_t i = 0;
  while (i + 2 < knots_.size() && u >= knots_[i + 1].t) ++i;
  const Knot& a = knots_[i];
  const Knot& b = knots_[i + 1];
  if (u <= a.t) {
    pose.position = a.p;
  } else if (u >= b.t) {
    pose.position = b.p;
  } else {
    const double f = (u - a.t) / (b.t - a.t);
    pose.position = Eigen::Vector3d(a.p.x() + f * (b.p.x() - a.p.x()), a.p.y() + f * (b.p.y() - a.p.y()),
                                    a.p.z() + f * (b.p.z() - a.p.z()));
  }
  if (timed_) {
    double f = 0.0;
    if (u >= b.t) f = 1.0;
    else if (u > a.t) f = (u - a.t) / (b.t - a.t);
    detmath::SinCos(a.yaw + f * YawStep(a.yaw, b.yaw), &pose.sin_yaw, &pose.cos_yaw);
  } else {
    // The segment's heading; the last knot keeps the last segment's.
    const Knot& h = u >= b.t && i + 2 == knots_.size() ? b : a;
    pose.cos_yaw = h.c;
    pose.sin_yaw = h.s;
  }
  if (back) {
    pose.cos_yaw = -pose.cos_yaw;
    pose.sin_yaw = -pose.sin_yaw;
  }
  return pose;
}

MoverPose MoverTrajectory::Pose(double t) const {
  const double tau = t - delay_;
  if (!(tau > 0.0)) return AtLeg(0.0, false);
  switch (mode_) {
    case MoverMode::kOnce:
      return AtLeg(tau < leg_ ? tau : leg_, false);
    case MoverMode::kLoop:
      return AtLeg(std::fmod(tau, leg_), false);
    case MoverMode::kBackAndForth: {
      const double u = std::fmod(tau, 2.0 * leg_);
      return u <= leg_ ? AtLeg(u, false) : AtLeg(2.0 * leg_ - u, true);
    }
  }
  return AtLeg(0.0, false);
}

TriangleMesh MoverMesh(const Mover& mover) {
  TriangleMesh mesh;
  for (const Object& o : mover.shape) mesh.Append(ObjectMesh(o));
  return mesh;
}

std::vector<Eigen::Vector3d> MoverTrack(const Mover& mover) {
  std::vector<Eigen::Vector3d> track;
  for (const auto& w : mover.waypoints) track.push_back(w.position);
  if (mover.speed > 0.0 && mover.mode == MoverMode::kLoop && !track.empty() && track.back() != track.front()) {
    track.push_back(track.front());
  }
  return track;
}

const char* MoverModeName(MoverMode mode) {
  switch (mode) {
    case MoverMode::kLoop: return "loop";
    case MoverMode::kBackAndForth: return "back_and_forth";
    case MoverMode::kOnce: return "once";
  }
  return "?";
}

bool ParseMoverMode(const std::string& name, MoverMode* mode) {
  for (const MoverMode m : {MoverMode::kLoop, MoverMode::kBackAndForth, MoverMode::kOnce}) {
    if (name == MoverModeName(m)) {
      *mode = m;
      return true;
    }
  }
  return false;
}

}  // namespace enavi::worlds
