#pragma once
// Small inline worlds for the planning tests and benchmarks: VoxelGrids drawn as ASCII plans
// (extruded over the grid's height) and a seeded park of pillars and boxes.

#include <cstdint>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "navstack/map/voxel_grid.h"

namespace enavi::navstack::testing {

/// A plan view: each character is a `cell_size` square column of the grid, the first line is the
/// highest y, the first column x = 0. '#' occupied over the whole height, '.' free, '?' unknown;
/// 'S' and 'G' are free and mark the start and goal (at height `marker_z`).
struct AsciiWorld {
  VoxelGrid grid;
  Eigen::Vector3d start = Eigen::Vector3d::Zero();
  Eigen::Vector3d goal = Eigen::Vector3d::Zero();
};

inline AsciiWorld WorldFromAscii(const std::string& plan, double cell_size, double resolution,
                                 double height, double marker_z) {
  std::vector<std::string> rows;
  std::istringstream in(plan);
  for (std::string line; std::getline(in, line);) {
    const auto first = line.find_first_not_of(' ');
    if (first == std::string::npos) continue;
    rows.push_back(line.substr(first));
  }
  if (rows.empty()) throw std::invalid_argument("WorldFromAscii: empty plan");
  const int w = static_cast<int>(rows.front().size()), h = static_cast<int>(rows.size());
  const int k = static_cast<int>(cell_size / resolution + 0.5);  // grid cells per character
  AsciiWorld world;
  world.grid = VoxelGrid(Eigen::Vector3d::Zero(), resolution,
                         Eigen::Vector3i(w * k, h * k, static_cast<int>(height / resolution + 0.5)),
                         CellState::kFree);
  for (int r = 0; r < h; ++r) {
    if (static_cast<int>(rows[r].size()) != w) throw std::invalid_argument("WorldFromAscii: ragged plan");
    for (int c = 0; c < w; ++c) {
      const char ch = rows[r][c];
      const int cy = h - 1 - r;
      const Eigen::Vector3d centre((c + 0.5) * cell_size, (cy + 0.5) * cell_size, marker_z);
      if (ch == 'S') world.start = centre;
      if (ch == 'G') world.goal = centre;
      const CellState state = ch == '#' ? CellState::kOccupied
                              : ch == '?' ? CellState::kUnknown
                                          : CellState::kFree;
      for (int z = 0; z < world.grid.dims.z(); ++z) {
        for (int y = cy * k; y < (cy + 1) * k; ++y) {
          for (int x = c * k; x < (c + 1) * k; ++x) {
            world.grid.cells[world.grid.Index({x, y, z})] = state;
          }
        }
      }
    }
  }
  return world;
}

/// Marks the cells whose centre lies in [lo, hi].
inline void FillBox(VoxelGrid* grid, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                    CellState state = CellState::kOccupied) {
  for (int z = 0; z < grid->dims.z(); ++z) {
    for (int y = 0; y < grid->dims.y(); ++y) {
      for (int x = 0; x < grid->dims.x(); ++x) {
        const Eigen::Vector3d c = grid->CenterOf({x, y, z});
        if ((c.array() >= lo.array()).all() && (c.array() <= hi.array()).all()) {
          grid->cells[grid->Index({x, y, z})] = state;
        }
      }
    }
  }
}

/// A park-like grid of size_xy x size_xy x height at `resolution`: the ground row occupied,
/// `pillars` tree trunks (radius 0.15-0.4 m) and `boxes` benches/kiosks (0.5-2 m) scattered by a
/// fixed seed, none within 1.2 m of the start (1, size_xy / 2) or goal (size_xy - 1, size_xy / 2)
/// at 1.5 m height. Random numbers are drawn from mt19937's raw output (portable).
inline AsciiWorld ParkWorld(double size_xy, double height, double resolution, int pillars,
                            int boxes, std::uint32_t seed) {
  AsciiWorld world;
  const int n = static_cast<int>(size_xy / resolution + 0.5);
  world.grid = VoxelGrid(Eigen::Vector3d::Zero(), resolution,
                         Eigen::Vector3i(n, n, static_cast<int>(height / resolution + 0.5)),
                         CellState::kFree);
  world.start = Eigen::Vector3d(1.0, 0.5 * size_xy, 1.5);
  world.goal = Eigen::Vector3d(size_xy - 1.0, 0.5 * size_xy, 1.5);
  std::mt19937 rng(seed);
  const auto uniform = [&rng](double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(rng()) / 4294967296.0);
  };
  const auto far_from_ends = [&world](const Eigen::Vector2d& p, double r) {
    return (p - world.start.head<2>()).norm() > r + 1.2 && (p - world.goal.head<2>()).norm() > r + 1.2;
  };
  VoxelGrid& g = world.grid;
  FillBox(&g, Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(size_xy + 1, size_xy + 1, 0.5 * resolution));
  for (int i = 0; i < pillars; ++i) {
    const Eigen::Vector2d c(uniform(0.0, size_xy), uniform(0.0, size_xy));
    const double r = uniform(0.15, 0.4);
    if (!far_from_ends(c, r)) continue;
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        if ((g.CenterOf({x, y, 0}).head<2>() - c).norm() > r) continue;
        for (int z = 0; z < g.dims.z(); ++z) g.cells[g.Index({x, y, z})] = CellState::kOccupied;
      }
    }
  }
  for (int i = 0; i < boxes; ++i) {
    const Eigen::Vector2d c(uniform(0.0, size_xy), uniform(0.0, size_xy));
    const Eigen::Vector3d half(uniform(0.25, 1.0), uniform(0.25, 1.0), uniform(0.25, 1.0));
    if (!far_from_ends(c, half.head<2>().norm())) continue;
    FillBox(&g, Eigen::Vector3d(c.x(), c.y(), 0.0) - half.cwiseProduct(Eigen::Vector3d(1, 1, 0)),
            Eigen::Vector3d(c.x(), c.y(), 0.0) + half.cwiseProduct(Eigen::Vector3d(1, 1, 2)));
  }
  return world;
}

/// The part of `world` covering `box` (cell-aligned, clipped to the world), as perception would
/// extract it from the map for PlanningVolume(box).
inline VoxelGrid ExtractBox(const VoxelGrid& world, const Eigen::AlignedBox3d& box) {
  const Eigen::Vector3i lo = world.CellOf(box.min()).cwiseMax(0);
  const Eigen::Vector3i hi = world.CellOf(box.max() - Eigen::Vector3d::Constant(1e-9))
                                 .cwiseMin(world.dims - Eigen::Vector3i::Ones());
  VoxelGrid g(world.origin + lo.cast<double>() * world.resolution, world.resolution,
              (hi - lo + Eigen::Vector3i::Ones()).cwiseMax(0));
  for (int z = 0; z < g.dims.z(); ++z) {
    for (int y = 0; y < g.dims.y(); ++y) {
      for (int x = 0; x < g.dims.x(); ++x) {
        g.cells[g.Index({x, y, z})] = world.cells[world.Index(lo + Eigen::Vector3i(x, y, z))];
      }
    }
  }
  return g;
}

}  // namespace enavi::navstack::testing
