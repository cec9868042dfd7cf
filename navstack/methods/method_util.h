#pragma once
// Small pieces every navigation method needs: per-plan seeds, yaw of an attitude, a hover
// reference, the box a remaining trajectory sweeps.

#include <cmath>
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/state.h"
#include "navstack/planning/trajectory.h"

namespace enavi::navstack {

/// splitmix64: decorrelates the per-plan seeds drawn from one episode seed.
inline std::uint64_t MixSeed(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// The search seed of plan number `call` of an episode seeded `seed`.
inline std::uint32_t PlanSeed(std::uint64_t seed, std::int64_t call) {
  return static_cast<std::uint32_t>(MixSeed(seed ^ MixSeed(static_cast<std::uint64_t>(call))));
}

inline double YawOf(const Eigen::Quaterniond& q_WB) {
  const Eigen::Vector3d x_W = q_WB * Eigen::Vector3d::UnitX();
  return std::atan2(x_W.y(), x_W.x());
}

/// A plan's start from the measured state: position, velocity, heading and heading rate (the
/// world-z component of the body rate), zero acceleration.
inline TrajectorySample StartFromState(const VehicleState& state) {
  TrajectorySample s;
  s.p = state.p_WB;
  s.v = state.v_WB;
  s.yaw = YawOf(state.q_WB);
  s.yaw_rate = (state.q_WB * state.w_WB_B).z();
  return s;
}

/// Hover at p facing yaw.
inline TrajectorySample HoldAt(const Eigen::Vector3d& p, double yaw) {
  TrajectorySample s;
  s.p = p;
  s.yaw = yaw;
  return s;
}

/// Bounding box of `traj` from t to `t_end`, padded by `pad` (what a collision check reads).
inline Eigen::AlignedBox3d SweptBox(const Trajectory& traj, double t, double t_end, double pad) {
  Eigen::AlignedBox3d box;
  const double step = 0.1;
  for (double s = t; s <= t_end + step; s += step) box.extend(traj.Sample(s).p);
  box.min().array() -= pad;
  box.max().array() += pad;
  return box;
}

}  // namespace enavi::navstack
