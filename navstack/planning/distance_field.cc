#include "navstack/planning/distance_field.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace enavi::navstack {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Scratch buffers of one 1-D lower-envelope pass (Felzenszwalb & Huttenlocher 2012, "Distance
// transforms of sampled functions"): parabola apexes v, boundaries z, input f, output d.
struct LineScratch {
  std::vector<int> v;
  std::vector<double> z, f, d;
  explicit LineScratch(int n) : v(n), z(n + 1), f(n), d(n) {}
};

// d[q] = min_p (q - p)^2 + f[p] over the finite f; all +inf when none is finite.
void LowerEnvelope1d(int n, LineScratch* s) {
  const std::vector<double>& f = s->f;
  int first = 0;
  while (first < n && f[first] == kInf) ++first;
  if (first == n) {
    std::fill(s->d.begin(), s->d.begin() + n, kInf);
    return;
  }
  // Build the lower envelope of the parabolas rooted at finite samples.
  int k = 0;
  s->v[0] = first;
  s->z[0] = -kInf;
  s->z[1] = kInf;
  for (int q = first + 1; q < n; ++q) {
    if (f[q] == kInf) continue;
    const double fq = f[q] + static_cast<double>(q) * q;
    double sep;
    while (true) {
      const int p = s->v[k];
      sep = (fq - (f[p] + static_cast<double>(p) * p)) / (2.0 * (q - p));
      if (sep > s->z[k]) break;
      --k;  // z[0] = -inf guarantees k >= 0 afterwards
    }
    ++k;
    s->v[k] = q;
    s->z[k] = sep;
    s->z[k + 1] = kInf;
  }
  // Read the envelope back at every integer position.
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (s->z[k + 1] < q) ++k;
    const double dq = q - s->v[k];
    s->d[q] = dq * dq + f[s->v[k]];
  }
}

void CheckGrid(const VoxelGrid& grid) {
  std::ostringstream msg;
  if ((grid.dims.array() <= 0).any()) {
    msg << "VoxelGrid.dims = (" << grid.dims.transpose() << "): every dimension must be >= 1";
  } else if (!(grid.resolution > 0.0) || !std::isfinite(grid.resolution)) {
    msg << "VoxelGrid.resolution = " << grid.resolution << ": must be > 0";
  } else if (grid.cells.size() != static_cast<std::size_t>(grid.dims.cast<long long>().prod())) {
    msg << "VoxelGrid.cells has " << grid.cells.size() << " entries, dims need "
        << grid.dims.cast<long long>().prod();
  } else if (!grid.origin.allFinite()) {
    msg << "VoxelGrid.origin is not finite";
  } else {
    return;
  }
  throw std::invalid_argument(msg.str());
}

}  // namespace

DistanceField::DistanceField(const VoxelGrid& grid, WorkCounts* work)
    : origin_(grid.origin), resolution_(grid.resolution), dims_(grid.dims) {
  CheckGrid(grid);
  const int nx = dims_.x(), ny = dims_.y(), nz = dims_.z();
  const std::size_t sy = static_cast<std::size_t>(nx),
                    sz = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  dist_.assign(grid.cells.size(), kInf);

  // Pass x: squared 1-D distance to the nearest occupied cell of the row (two sweeps).
  for (int z = 0; z < nz; ++z) {
    for (int y = 0; y < ny; ++y) {
      const std::size_t row = y * sy + z * sz;
      double last = -kInf;
      for (int x = 0; x < nx; ++x) {
        if (grid.cells[row + x] == CellState::kOccupied) {
          last = x;
          has_obstacles_ = true;
        }
        if (last > -kInf) dist_[row + x] = (x - last) * (x - last);
      }
      last = kInf;
      for (int x = nx - 1; x >= 0; --x) {
        if (grid.cells[row + x] == CellState::kOccupied) last = x;
        if (last < kInf) dist_[row + x] = std::min(dist_[row + x], (last - x) * (last - x));
      }
    }
  }

  // Passes y and z: lower envelopes of parabolas over the previous pass' values.
  if (has_obstacles_) {
    LineScratch line(std::max(ny, nz));
    for (int z = 0; z < nz; ++z) {
      for (int x = 0; x < nx; ++x) {
        const std::size_t base = x + z * sz;
        for (int y = 0; y < ny; ++y) line.f[y] = dist_[base + y * sy];
        LowerEnvelope1d(ny, &line);
        for (int y = 0; y < ny; ++y) dist_[base + y * sy] = line.d[y];
      }
    }
    for (int y = 0; y < ny; ++y) {
      for (int x = 0; x < nx; ++x) {
        const std::size_t base = x + y * sy;
        for (int z = 0; z < nz; ++z) line.f[z] = dist_[base + z * sz];
        LowerEnvelope1d(nz, &line);
        for (int z = 0; z < nz; ++z) dist_[base + z * sz] = line.d[z];
      }
    }
  }

  // Squared cell distances between centres -> metres to the nearest occupied voxel's face.
  const double half = 0.5 * resolution_;
  for (double& d : dist_) {
    d = has_obstacles_ ? std::sqrt(d) * resolution_ - half : kNoObstacleDistance;
  }
  if (work != nullptr) work->Add(WorkUnit::kDistanceCell, static_cast<std::int64_t>(dist_.size()));
}

double DistanceField::Distance(const Eigen::Vector3d& p_W) const { return Distance(p_W, nullptr); }

double DistanceField::Distance(const Eigen::Vector3d& p_W, Eigen::Vector3d* grad_W) const {
  // Continuous index of p in cell-centre coordinates, clamped to the grid.
  Eigen::Vector3i i0, i1;
  Eigen::Vector3d w;
  bool clamped[3];
  for (int k = 0; k < 3; ++k) {
    const double c = (p_W[k] - origin_[k]) / resolution_ - 0.5;
    const int n = dims_[k];
    clamped[k] = c < 0.0 || c > n - 1 || n == 1;
    const double cc = std::clamp(c, 0.0, static_cast<double>(n - 1));
    int lo = static_cast<int>(std::floor(cc));
    lo = std::min(lo, std::max(n - 2, 0));
    i0[k] = lo;
    i1[k] = std::min(lo + 1, n - 1);
    w[k] = i1[k] == lo ? 0.0 : cc - lo;
  }
  // Corner values c[xyz] with x the lowest bit.
  double c[8];
  for (int b = 0; b < 8; ++b) {
    const Eigen::Vector3i cell((b & 1) ? i1.x() : i0.x(), (b & 2) ? i1.y() : i0.y(),
                               (b & 4) ? i1.z() : i0.z());
    c[b] = dist_[Index(cell)];
  }
  const double wx = w.x(), wy = w.y(), wz = w.z();
  const double c00 = c[0] + wx * (c[1] - c[0]);
  const double c10 = c[2] + wx * (c[3] - c[2]);
  const double c01 = c[4] + wx * (c[5] - c[4]);
  const double c11 = c[6] + wx * (c[7] - c[6]);
  const double c0 = c00 + wy * (c10 - c00);
  const double c1 = c01 + wy * (c11 - c01);
  const double value = c0 + wz * (c1 - c0);
  if (grad_W != nullptr) {
    // Exact derivative of the trilinear interpolant; zero where the point was clamped.
    const double dx0 = (c[1] - c[0]) + wy * ((c[3] - c[2]) - (c[1] - c[0]));
    const double dx1 = (c[5] - c[4]) + wy * ((c[7] - c[6]) - (c[5] - c[4]));
    const double dx = dx0 + wz * (dx1 - dx0);
    const double dy = (c10 - c00) + wz * ((c11 - c01) - (c10 - c00));
    const double dz = c1 - c0;
    *grad_W = Eigen::Vector3d(clamped[0] ? 0.0 : dx, clamped[1] ? 0.0 : dy, clamped[2] ? 0.0 : dz) /
              resolution_;
  }
  return value;
}

}  // namespace enavi::navstack
