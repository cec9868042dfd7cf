#pragma once
// What the path search, the goal choice and the start checks ask of the map: how much clearance a
// point has. Two implementations: the exact distance field of the whole snapshot (ESDF pipeline)
// and the grid's inflated occupancy (rebound pipeline, no distance field).

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace enavi::navstack {

class ClearanceMap {
 public:
  virtual ~ClearanceMap() = default;
  /// Clearance of p_W from the nearest obstacle [m], exact below `needed`; values >= needed may be
  /// capped (a probe need not look further than the caller asks).
  virtual double Clearance(const Eigen::Vector3d& p_W, double needed) const = 0;
  /// True if p_W has clearance >= needed; an implementation may answer false conservatively (it
  /// never answers true for a point closer than needed).
  virtual bool IsClear(const Eigen::Vector3d& p_W, double needed) const = 0;
  virtual double resolution() const = 0;
  /// The box the map covers.
  virtual Eigen::AlignedBox3d Box() const = 0;
};

}  // namespace enavi::navstack
