#include "workers/emulation/emulated_wire.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace enavi::emulation {

SampleWire ToWire(const navstack::TrajectorySample& s) {
  SampleWire w;
  for (int i = 0; i < 3; ++i) {
    w.p[i] = s.p[i];
    w.v[i] = s.v[i];
    w.a[i] = s.a[i];
    w.j[i] = s.j[i];
  }
  w.yaw = s.yaw;
  w.yaw_rate = s.yaw_rate;
  return w;
}

navstack::TrajectorySample FromWire(const SampleWire& w) {
  navstack::TrajectorySample s;
  s.p = Eigen::Vector3d(w.p[0], w.p[1], w.p[2]);
  s.v = Eigen::Vector3d(w.v[0], w.v[1], w.v[2]);
  s.a = Eigen::Vector3d(w.a[0], w.a[1], w.a[2]);
  s.j = Eigen::Vector3d(w.j[0], w.j[1], w.j[2]);
  s.yaw = w.yaw;
  s.yaw_rate = w.yaw_rate;
  return s;
}

void ToWire(const navstack::Trajectory& traj, TrajectoryWire* out) {
  const Eigen::Matrix3Xd& q = traj.spline().control_points();
  if (q.cols() > TrajectoryWire::kMaxControlPoints) {
    throw std::length_error("emulated clock: a trajectory of " + std::to_string(q.cols()) +
                            " control points does not fit the wire format (at most " +
                            std::to_string(TrajectoryWire::kMaxControlPoints) + ")");
  }
  out->count = static_cast<std::int32_t>(q.cols());
  out->t0 = traj.start_time();
  out->dt = traj.spline().dt();
  out->yaw0 = traj.Sample(traj.start_time()).yaw;
  out->yaw_rate0 = traj.start_yaw_rate();
  for (Eigen::Index c = 0; c < q.cols(); ++c)
    for (int i = 0; i < 3; ++i) out->q[c][i] = q(i, c);
}

std::shared_ptr<const navstack::Trajectory> FromWire(const TrajectoryWire& w,
                                                     const navstack::PlannerOptions& options) {
  if (w.count == 0) return nullptr;
  if (w.count < 4 || w.count > TrajectoryWire::kMaxControlPoints || !(w.dt > 0) || !std::isfinite(w.t0)) {
    throw std::invalid_argument("emulated clock: malformed trajectory message (" + std::to_string(w.count) +
                                " control points, dt " + std::to_string(w.dt) + ")");
  }
  Eigen::Matrix3Xd q(3, w.count);
  for (int c = 0; c < w.count; ++c)
    for (int i = 0; i < 3; ++i) q(i, c) = w.q[c][i];
  return std::make_shared<const navstack::Trajectory>(navstack::UniformBspline(std::move(q), w.dt), w.t0, w.yaw0,
                                                      options, w.yaw_rate0);
}

namespace {

bool SameTrajectory(const std::shared_ptr<const navstack::Trajectory>& have, const TrajectoryWire& w) {
  if (!have) return w.count == 0;
  const Eigen::Matrix3Xd& q = have->spline().control_points();
  if (w.count != q.cols() || w.t0 != have->start_time() || w.dt != have->spline().dt()) return false;
  for (int c = 0; c < w.count; ++c)
    for (int i = 0; i < 3; ++i)
      if (q(i, c) != w.q[c][i]) return false;
  return true;
}

}  // namespace

void ReferenceMirror::Update(const ReferenceWire& w) {
  has_message_ = true;
  ref_.following = w.mode != ReferenceWire::kHold;
  ref_.hold = FromWire(w.hold);
  // The usual change is a new plan whose predecessor becomes `previous`: reuse what we built.
  std::shared_ptr<const navstack::Trajectory> current =
      SameTrajectory(ref_.current, w.current) ? ref_.current : FromWire(w.current, options_);
  std::shared_ptr<const navstack::Trajectory> previous;
  if (SameTrajectory(ref_.current, w.previous)) {
    previous = ref_.current;
  } else if (SameTrajectory(ref_.previous, w.previous)) {
    previous = ref_.previous;
  } else {
    previous = FromWire(w.previous, options_);
  }
  ref_.current = std::move(current);
  ref_.previous = std::move(previous);
}

navstack::TrajectorySample ReferenceMirror::Reference(double t) const { return ref_.Sample(t); }

}  // namespace enavi::emulation
