#include "navstack/planning/observed_space.h"

#include <algorithm>
#include <cmath>

#include "navstack/common/argument_check.h"

namespace enavi::navstack {
namespace {

double DistanceToSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double s = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + s * ab)).norm();
}

constexpr ArgumentCheck kCheck("ObservedSpaceRule");

}  // namespace

ObservedSpaceRule ObservedSpaceRule::For(const Eigen::Vector3d& vehicle, const Eigen::Vector3d& start, double speed,
                                         double t_react, double a_brake, double radius, double resolution,
                                         const CameraIntrinsics& camera) {
  kCheck.NonNegative(speed, "speed");
  kCheck.NonNegative(t_react, "t_react");
  kCheck.NonNegative(radius, "radius");
  kCheck.Range(a_brake > 0.0 && std::isfinite(a_brake), "a_brake", a_brake, "(0, inf)");
  kCheck.Range(resolution > 0.0 && std::isfinite(resolution), "resolution", resolution, "(0, inf)");
  // The narrower half-angle of the view cone: vertical on the farm's 87 x 58 deg camera.
  const double half_angle = std::min({std::atan(camera.cx / camera.fx), std::atan((camera.width - camera.cx) / camera.fx),
                                      std::atan(camera.cy / camera.fy), std::atan((camera.height - camera.cy) / camera.fy)});
  if (!(half_angle > 0.0)) throw std::invalid_argument("ObservedSpaceRule: the camera's field of view is empty");
  ObservedSpaceRule rule;
  rule.vehicle = vehicle;
  rule.start = start;
  rule.body = (radius + std::sqrt(3.0) * resolution) / std::sin(half_angle);
  rule.reach = speed * t_react + speed * speed / (2.0 * a_brake) + radius;
  return rule;
}

bool ObservedSpaceRule::Blocks(const Eigen::Vector3d& p_W) const {
  return (p_W - vehicle).norm() <= reach && DistanceToSegment(p_W, vehicle, start) > body;
}

void BlockUnobserved(const ObservedSpaceRule& rule, VoxelGrid* grid, WorkCounts* work) {
  if (!(rule.reach > rule.body)) return;
  const Eigen::Vector3d r = Eigen::Vector3d::Constant(rule.reach);
  const Eigen::Vector3i lo = grid->CellOf(rule.vehicle - r).cwiseMax(0);
  const Eigen::Vector3i hi = grid->CellOf(rule.vehicle + r).cwiseMin(grid->dims - Eigen::Vector3i::Ones());
  std::int64_t probed = 0;
  for (int z = lo.z(); z <= hi.z(); ++z) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const Eigen::Vector3i c(x, y, z);
        const Eigen::Vector3d p = grid->CenterOf(c);
        if ((p - rule.vehicle).norm() > rule.reach) continue;
        ++probed;
        CellState& cell = grid->cells[grid->Index(c)];
        if (cell == CellState::kUnknown && rule.Blocks(p)) cell = CellState::kOccupied;
      }
    }
  }
  if (work != nullptr) work->Add(WorkUnit::kCellProbe, probed);
}

}  // namespace enavi::navstack
