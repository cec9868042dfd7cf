#include "navstack/planning/collision_check.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace enavi::navstack {
namespace {

// Largest control speed of the segments that [tau_from, tau_to] (trajectory-relative) touches:
// a bound of the speed over that interval.
double SpeedBound(const UniformBspline& s, double tau_from, double tau_to) {
  const Eigen::Matrix3Xd& q = s.control_points();
  const int first = std::clamp(static_cast<int>(std::floor(tau_from / s.dt())), 0, s.num_segments() - 1);
  const int last = std::clamp(static_cast<int>(std::floor(tau_to / s.dt())), 0, s.num_segments() - 1);
  double best = 0.0;
  for (int i = first; i <= last + 2 && i + 1 < q.cols(); ++i) {
    best = std::max(best, (q.col(i + 1) - q.col(i)).norm() / s.dt());
  }
  return best;
}

}  // namespace

CollisionCheckResult CheckTrajectory(const Trajectory& trajectory, double t_from, double t_to,
                                     const VoxelGrid& grid, double radius, WorkCounts* work,
                                     const ObservedSpaceRule* observed) {
  if (!(radius >= 0.0) || !(grid.resolution > 0.0) ||
      grid.cells.size() != static_cast<std::size_t>(grid.dims.cast<long long>().prod())) {
    std::ostringstream msg;
    msg << "CheckTrajectory: radius = " << radius << " must be >= 0 and the grid well formed";
    throw std::invalid_argument(msg.str());
  }
  CollisionCheckResult result;
  const double a = std::max(t_from, trajectory.start_time());
  const double b = std::min(t_to, trajectory.end_time());
  if (b < a) return result;

  // Time step: half a cell of travel at the speed bound; at least the two interval ends.
  const double speed = SpeedBound(trajectory.spline(), a - trajectory.start_time(),
                                  b - trajectory.start_time());
  const double step = 0.5 * grid.resolution / std::max(speed, 1e-6);
  const int n = std::max(1, static_cast<int>(std::ceil((b - a) / step)));

  const double r2 = radius * radius;
  const double res = grid.resolution;
  std::int64_t cells = 0;
  int samples = 0;
  for (int i = 0; i <= n && !result.collides; ++i) {
    const double t = i == n ? b : a + (b - a) * i / n;
    const Eigen::Vector3d p = trajectory.Sample(t).p;
    ++samples;
    if (observed != nullptr && grid.At(p) == CellState::kUnknown && observed->Blocks(p)) {
      result.collides = true;
      result.unobserved = true;
      result.t_hit = t;
      result.p_hit = p;
      break;
    }
    // Cells whose box is within radius of p.
    const Eigen::Vector3i lo = grid.CellOf(p - Eigen::Vector3d::Constant(radius)).cwiseMax(0);
    const Eigen::Vector3i hi =
        grid.CellOf(p + Eigen::Vector3d::Constant(radius)).cwiseMin(grid.dims - Eigen::Vector3i::Ones());
    for (int z = lo.z(); z <= hi.z() && !result.collides; ++z) {
      for (int y = lo.y(); y <= hi.y() && !result.collides; ++y) {
        for (int x = lo.x(); x <= hi.x(); ++x) {
          const Eigen::Vector3d cmin = grid.origin + Eigen::Vector3d(x, y, z) * res;
          const Eigen::Vector3d nearest = p.cwiseMax(cmin).cwiseMin(cmin + Eigen::Vector3d::Constant(res));
          if ((nearest - p).squaredNorm() > r2) continue;
          ++cells;
          if (grid.cells[grid.Index(Eigen::Vector3i(x, y, z))] == CellState::kOccupied) {
            result.collides = true;
            result.t_hit = t;
            result.p_hit = p;
            break;
          }
        }
      }
    }
  }
  if (work != nullptr) {
    work->Add(WorkUnit::kTrajectorySample, samples);
    work->Add(WorkUnit::kCellProbe, cells);
  }
  return result;
}

}  // namespace enavi::navstack
