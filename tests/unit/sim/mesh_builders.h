#pragma once
// Test and benchmark scenes built directly as triangle meshes (boxes, cylinders, a ground grid,
// a seeded cluttered park), independent of the world generators.

#include <cmath>
#include <cstdint>
#include <random>

#include <Eigen/Geometry>

#include "worlds/mesh.h"

namespace enavi::sim::testing {

/// Appends the 12 triangles of the box [-half, half] placed by X (counter-clockwise seen from
/// outside).
inline void AddBox(worlds::TriangleMesh* mesh, const Eigen::Vector3d& half,
                   const Eigen::Isometry3d& X = Eigen::Isometry3d::Identity()) {
  const int base = static_cast<int>(mesh->vertices.size());
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d corner((i & 1) ? half.x() : -half.x(), (i & 2) ? half.y() : -half.y(),
                                 (i & 4) ? half.z() : -half.z());
    mesh->vertices.push_back((X * corner).cast<float>());
  }
  // Faces as corner quads (a, b, c, d) counter-clockwise seen from outside.
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    mesh->triangles.emplace_back(base + f[0], base + f[1], base + f[2]);
    mesh->triangles.emplace_back(base + f[0], base + f[2], base + f[3]);
  }
}

/// Axis-aligned box between corners lo and hi.
inline void AddAlignedBox(worlds::TriangleMesh* mesh, const Eigen::Vector3d& lo,
                          const Eigen::Vector3d& hi) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = 0.5 * (lo + hi);
  AddBox(mesh, 0.5 * (hi - lo), X);
}

/// Vertical closed cylinder (prism with `segments` sides) standing on base_center.
inline void AddCylinder(worlds::TriangleMesh* mesh, const Eigen::Vector3d& base_center,
                        double radius, double height, int segments = 24) {
  const int base = static_cast<int>(mesh->vertices.size());
  for (int i = 0; i < segments; ++i) {
    const double a = 2.0 * M_PI * i / segments;
    const Eigen::Vector3d rim(radius * std::cos(a), radius * std::sin(a), 0.0);
    mesh->vertices.push_back((base_center + rim).cast<float>());
    mesh->vertices.push_back((base_center + rim + Eigen::Vector3d(0, 0, height)).cast<float>());
  }
  const int bottom = static_cast<int>(mesh->vertices.size());
  mesh->vertices.push_back(base_center.cast<float>());
  mesh->vertices.push_back((base_center + Eigen::Vector3d(0, 0, height)).cast<float>());
  const int top = bottom + 1;
  for (int i = 0; i < segments; ++i) {
    const int j = (i + 1) % segments;
    const int b0 = base + 2 * i, t0 = b0 + 1, b1 = base + 2 * j, t1 = b1 + 1;
    mesh->triangles.emplace_back(b0, b1, t1);
    mesh->triangles.emplace_back(b0, t1, t0);
    mesh->triangles.emplace_back(bottom, b1, b0);
    mesh->triangles.emplace_back(top, t0, t1);
  }
}

/// Flat ground at height z over [-half, half]^2, split into cells of `cell` metres.
inline void AddGround(worlds::TriangleMesh* mesh, double half, double cell = 1.0, double z = 0.0) {
  const int n = std::max(1, static_cast<int>(std::lround(2.0 * half / cell)));
  const int base = static_cast<int>(mesh->vertices.size());
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh->vertices.emplace_back(static_cast<float>(-half + 2.0 * half * i / n),
                                  static_cast<float>(-half + 2.0 * half * j / n),
                                  static_cast<float>(z));
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = base + j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      mesh->triangles.emplace_back(a, b, c);
      mesh->triangles.emplace_back(a, c, d);
    }
  }
}

/// A dense park-like scene (trees: trunk cylinders with box canopies, plus scattered boxes)
/// over [-30, 30]^2 m with ground, seeded. The corridor |y| < 1.5 along x is kept free so a
/// camera can fly through it at 1.5 m.
inline worlds::TriangleMesh MakeClutteredPark(std::uint64_t seed, int trees = 400,
                                              int boxes = 120) {
  worlds::TriangleMesh mesh;
  AddGround(&mesh, 30.0, 1.0);
  std::mt19937_64 rng(seed);
  // Uniform in [lo, hi) from raw draws (std:: distributions differ between library versions).
  auto uniform = [&rng](double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53;
  };
  auto free_xy = [&]() {
    Eigen::Vector2d xy;
    do {
      xy = Eigen::Vector2d(uniform(-29.0, 29.0), uniform(-29.0, 29.0));
    } while (std::abs(xy.y()) < 1.5);
    return xy;
  };
  for (int i = 0; i < trees; ++i) {
    const Eigen::Vector2d xy = free_xy();
    const double trunk_h = uniform(2.0, 5.0);
    AddCylinder(&mesh, Eigen::Vector3d(xy.x(), xy.y(), 0.0), uniform(0.1, 0.35), trunk_h, 16);
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(xy.x(), xy.y(), trunk_h + 0.8);
    X.linear() = Eigen::AngleAxisd(uniform(0.0, M_PI), Eigen::Vector3d::UnitZ()).matrix();
    const double c = uniform(0.8, 1.6);
    AddBox(&mesh, Eigen::Vector3d(c, c, 0.9), X);
  }
  for (int i = 0; i < boxes; ++i) {
    const Eigen::Vector2d xy = free_xy();
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    const Eigen::Vector3d half(uniform(0.2, 1.5), uniform(0.2, 1.5), uniform(0.2, 1.5));
    X.translation() = Eigen::Vector3d(xy.x(), xy.y(), half.z());
    X.linear() = Eigen::AngleAxisd(uniform(0.0, M_PI), Eigen::Vector3d::UnitZ()).matrix();
    AddBox(&mesh, half, X);
  }
  return mesh;
}

}  // namespace enavi::sim::testing
