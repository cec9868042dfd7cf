#include "worlds/validate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>
#include <variant>

#include "worlds/detmath.h"
#include "worlds/movers.h"
#include "worlds/number_text.h"
#include "worlds/obj_import.h"
#include "worlds/primitives.h"

// All arithmetic here is scalar and in a fixed order: a validation verdict decides whether a
// generator resamples, so it must not depend on SIMD width or fused multiply-add.

namespace enavi::worlds {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kFar = 20.0;  // beyond this, ellipsoid distances are cheap lower bounds

struct V3 {
  double x, y, z;
};
V3 Sub(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
double Dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 Cross(const V3& a, const V3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
V3 ToV3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

double BoxDistance(const Box& b, double c, double s, const V3& p) {
  const double dx = p.x - b.center.x(), dy = p.y - b.center.y(), dz = p.z - b.center.z();
  // Into the box frame: rotate by -yaw.
  const double q[3] = {std::abs(c * dx + s * dy) - 0.5 * b.size.x(), std::abs(-s * dx + c * dy) - 0.5 * b.size.y(),
                       std::abs(dz) - 0.5 * b.size.z()};
  double outside = 0.0;
  for (double v : q) outside = outside + (v > 0.0 ? v * v : 0.0);
  const double inside = std::min(std::max(q[0], std::max(q[1], q[2])), 0.0);
  return std::sqrt(outside) + inside;
}

double CylinderDistance(const Cylinder& cyl, const V3& p) {
  const double dx = p.x - cyl.base.x(), dy = p.y - cyl.base.y();
  const double radial = std::sqrt(dx * dx + dy * dy) - cyl.radius;
  const double vertical = std::max(cyl.base.z() - p.z, p.z - (cyl.base.z() + cyl.height));
  const double ox = std::max(radial, 0.0), oz = std::max(vertical, 0.0);
  return std::sqrt(ox * ox + oz * oz) + std::min(std::max(radial, vertical), 0.0);
}

// Exact below `cap`; at or above it, only guaranteed to be >= cap too (saves the bisection when
// the caller only compares against a threshold).
double EllipsoidDistance(const Ellipsoid& e, const V3& p, double cap = kFar) {
  const double r[3] = {e.radii.x(), e.radii.y(), e.radii.z()};
  const double y[3] = {std::abs(p.x - e.center.x()), std::abs(p.y - e.center.y()), std::abs(p.z - e.center.z())};
  double s2 = 0.0;
  for (int i = 0; i < 3; ++i) s2 = s2 + (y[i] / r[i]) * (y[i] / r[i]);
  const double s = std::sqrt(s2);
  const double r_min = std::min(r[0], std::min(r[1], r[2]));
  const double r_max = std::max(r[0], std::max(r[1], r[2]));
  // Scaling by 1/r is Lipschitz with 1/r_min (and its inverse with r_max): the surface distance
  // lies in [r_min (s-1), r_max (s-1)].
  if (s <= 1.0) return r_min * (s - 1.0);  // inside (a bound on the depth; sign is what matters)
  const double lower = r_min * (s - 1.0);
  if (lower >= cap || r_max == r_min) return lower;
  // Exact: closest point x_i = r_i^2 y_i / (t + r_i^2) with sum((x_i / r_i)^2) = 1, t > 0
  // (monotone in t, so bisection; fixed iteration count for determinism).
  double norm_y = 0.0;
  for (int i = 0; i < 3; ++i) norm_y = norm_y + y[i] * y[i];
  double lo = 0.0, hi = r_max * std::sqrt(norm_y) + 1.0;
  for (int it = 0; it < 80; ++it) {
    const double t = 0.5 * (lo + hi);
    double g = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double v = r[i] * y[i] / (t + r[i] * r[i]);
      g = g + v * v;
    }
    if (g > 1.0) lo = t; else hi = t;
  }
  const double t = 0.5 * (lo + hi);
  double d2 = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double x = r[i] * r[i] * y[i] / (t + r[i] * r[i]);
    d2 = d2 + (y[i] - x) * (y[i] - x);
  }
  return std::sqrt(d2);
}

// Squared distance from p to triangle abc (closest-point regions by barycentric tests).
double PointTriangleDistance2(const V3& p, const V3& a, const V3& b, const V3& c) {
  const V3 ab = Sub(b, a), ac = Sub(c, a), ap = Sub(p, a);
  auto dist2 = [&](const V3& q) { const V3 d = Sub(p, q); return Dot(d, d); };
  const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return dist2(a);
  const V3 bp = Sub(p, b);
  const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return dist2(b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return dist2({a.x + v * ab.x, a.y + v * ab.y, a.z + v * ab.z});
  }
  const V3 cp = Sub(p, c);
  const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return dist2(c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return dist2({a.x + w * ac.x, a.y + w * ac.y, a.z + w * ac.z});
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return dist2({b.x + w * (c.x - b.x), b.y + w * (c.y - b.y), b.z + w * (c.z - b.z)});
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return dist2({a.x + ab.x * v + ac.x * w, a.y + ab.y * v + ac.y * w, a.z + ab.z * v + ac.z * w});
}

// Does the ray p + t d (t > 0) cross triangle abc? (Moller-Trumbore)
bool RayHitsTriangle(const V3& p, const V3& d, const V3& a, const V3& b, const V3& c) {
  const V3 e1 = Sub(b, a), e2 = Sub(c, a);
  const V3 h = Cross(d, e2);
  const double det = Dot(e1, h);
  if (std::abs(det) < 1e-14) return false;
  const double inv = 1.0 / det;
  const V3 s = Sub(p, a);
  const double u = Dot(s, h) * inv;
  if (u < 0.0 || u > 1.0) return false;
  const V3 q = Cross(s, e1);
  const double v = Dot(d, q) * inv;
  if (v < 0.0 || u + v > 1.0) return false;
  return Dot(e2, q) * inv > 0.0;
}

V3 Corner(const Eigen::Matrix3d& tri, int k) { return {tri(0, k), tri(1, k), tri(2, k)}; }

double AabbDistance(const Eigen::AlignedBox3d& box, const V3& p) {
  const double dx = std::max({box.min().x() - p.x, 0.0, p.x - box.max().x()});
  const double dy = std::max({box.min().y() - p.y, 0.0, p.y - box.max().y()});
  const double dz = std::max({box.min().z() - p.z, 0.0, p.z - box.max().z()});
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

std::string Metres(double v) { return FormatFixed(v, 2, false) + " m"; }

std::string PointText(const Eigen::Vector3d& v) {
  std::string out = "[";
  out.append(FormatFixed(v.x(), 2, false)).append(", ").append(FormatFixed(v.y(), 2, false)).append(", ");
  return out.append(FormatFixed(v.z(), 2, false)).append("]");
}

}  // namespace

ObstacleField::ObstacleField(const World& world, bool include_ground) : world_(world), include_ground_(include_ground) {
  items_.reserve(world.objects.size());
  for (const auto& object : world.objects) {
    Item item;
    item.bounds = ObjectBounds(object);
    if (const auto* box = std::get_if<Box>(&object)) detmath::SinCos(box->yaw, &item.sin_yaw, &item.cos_yaw);
    if (const auto* mesh = std::get_if<MeshObject>(&object)) {
      const Eigen::Affine3d X = MeshObjectPose(*mesh);
      item.first_triangle = static_cast<int>(triangles_.size());
      item.triangle_count = static_cast<int>(mesh->mesh.triangles.size());
      // Watertight when every undirected edge is shared by exactly two triangles.
      std::map<std::pair<int, int>, int> edges;
      for (const auto& t : mesh->mesh.triangles) {
        Eigen::Matrix3d tri;
        for (int k = 0; k < 3; ++k) {
          const Eigen::Vector3d v = mesh->mesh.vertices[t[k]].cast<double>();
          // Scalar placement (same as MeshObjectPose's matrix, no SIMD products).
          for (int r = 0; r < 3; ++r) {
            tri(r, k) = X(r, 0) * v.x() + X(r, 1) * v.y() + X(r, 2) * v.z() + X(r, 3);
          }
          const int a = t[k], b = t[(k + 1) % 3];
          ++edges[{std::min(a, b), std::max(a, b)}];
        }
        triangles_.push_back(tri);
      }
      item.closed = !edges.empty() &&
                    std::all_of(edges.begin(), edges.end(), [](const auto& e) { return e.second == 2; });
    }
    items_.push_back(item);
  }
}

double ObstacleField::ObjectDistance(int index, const Eigen::Vector3d& p_W) const {
  return ObjectDistanceCapped(index, p_W, kFar);
}

double ObstacleField::ObjectDistanceCapped(int index, const Eigen::Vector3d& p_W, double cap) const {
  const V3 p = ToV3(p_W);
  struct Visitor {
    const ObstacleField& self;
    const Item& item;
    const V3& p;
    double cap;
    double operator()(const Box& b) const { return BoxDistance(b, item.cos_yaw, item.sin_yaw, p); }
    double operator()(const Cylinder& c) const { return CylinderDistance(c, p); }
    double operator()(const Ellipsoid& e) const { return EllipsoidDistance(e, p, cap); }
    double operator()(const MeshObject&) const {
      double best2 = kInf;
      for (int i = 0; i < item.triangle_count; ++i) {
        const auto& tri = self.triangles_[item.first_triangle + i];
        best2 = std::min(best2, PointTriangleDistance2(p, Corner(tri, 0), Corner(tri, 1), Corner(tri, 2)));
      }
      const double d = std::sqrt(best2);
      if (!item.closed || !item.bounds.contains(Eigen::Vector3d(p.x, p.y, p.z))) return d;
      // Inside a watertight mesh when a ray crosses it an odd number of times. The direction is
      // deliberately not axis-aligned so it rarely grazes edges of axis-aligned models.
      const V3 dir{0.5773502691896258, 0.5773502791896258, 0.5773502591896258};
      int hits = 0;
      for (int i = 0; i < item.triangle_count; ++i) {
        const auto& tri = self.triangles_[item.first_triangle + i];
        hits += RayHitsTriangle(p, dir, Corner(tri, 0), Corner(tri, 1), Corner(tri, 2)) ? 1 : 0;
      }
      return hits % 2 == 1 ? -d : d;
    }
  };
  return std::visit(Visitor{*this, items_[index], p, cap}, world_.objects[index]);
}

double ObstacleField::Distance(const Eigen::Vector3d& p_W, int* nearest) const {
  double best = kInf;
  int best_index = -2;
  if (include_ground_ && world_.ground.enabled) {
    best = p_W.z() - world_.ground.z;
    best_index = -1;
  }
  const V3 p = ToV3(p_W);
  for (int i = 0; i < static_cast<int>(items_.size()); ++i) {
    // The bounding box is a lower bound on the distance of anything inside it.
    if (AabbDistance(items_[i].bounds, p) >= best) continue;
    const double d = ObjectDistance(i, p_W);
    if (d < best) {
      best = d;
      best_index = i;
    }
  }
  if (nearest != nullptr) *nearest = best_index;
  return best;
}

double ObstacleField::SegmentClearance(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double step) const {
  const double dx = b.x() - a.x(), dy = b.y() - a.y(), dz = b.z() - a.z();
  const double length = std::sqrt(dx * dx + dy * dy + dz * dz);
  const int n = std::max(1, static_cast<int>(std::ceil(length / step)));
  double least = kInf;
  for (int i = 0; i <= n; ++i) {
    const double t = static_cast<double>(i) / n;
    const Eigen::Vector3d p(a.x() + t * (b.x() - a.x()), a.y() + t * (b.y() - a.y()), a.z() + t * (b.z() - a.z()));
    least = std::min(least, Distance(p));
  }
  return least;
}

// Inflated occupancy grid over the world bounds and the flood fill on it.
class OccupancyRaster {
 public:
  OccupancyRaster(const ObstacleField& field, const World& world, double cell, double threshold)
      : field_(field), world_(world), cell_(cell), threshold_(threshold) {
    const Eigen::Vector3d size = world.bounds.sizes();
    n_[0] = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(size.x() / cell)));
    n_[1] = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(size.y() / cell)));
    n_[2] = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(size.z() / cell)));
    state_.assign(static_cast<std::size_t>(n_[0] * n_[1] * n_[2]), kFree);
  }

  // Marks every cell whose centre is closer than the threshold to an obstacle.
  void Rasterise() {
    if (world_.ground.enabled) {
      for (std::int64_t k = 0; k < n_[2]; ++k) {
        if (Centre(2, k) - world_.ground.z >= threshold_) continue;
        for (std::int64_t j = 0; j < n_[1]; ++j)
          for (std::int64_t i = 0; i < n_[0]; ++i) state_[Index(i, j, k)] = kBlocked;
      }
    }
    for (int o = 0; o < static_cast<int>(world_.objects.size()); ++o) {
      const auto& item = field_.items_[o];
      if (std::holds_alternative<MeshObject>(world_.objects[o])) {
        // Per triangle: cells near the surface. A watertight interior is sealed off by the
        // blocked shell (at least 2 x threshold > one cell thick), so it is never reached.
        for (int t = 0; t < item.triangle_count; ++t) {
          const auto& tri = field_.triangles_[item.first_triangle + t];
          Eigen::AlignedBox3d box;
          for (int k = 0; k < 3; ++k) box.extend(tri.col(k));
          MarkRange(box, [&](const V3& p) {
            return PointTriangleDistance2(p, Corner(tri, 0), Corner(tri, 1), Corner(tri, 2)) <
                   threshold_ * threshold_;
          });
        }
      } else {
        MarkRange(item.bounds, [&](const V3& p) {
          return field_.ObjectDistanceCapped(o, Eigen::Vector3d(p.x, p.y, p.z), threshold_) < threshold_;
        });
      }
    }
  }

  // Flood fill (6-connected) from the free cells around `from`; true if it reaches the free
  // cells around `to`.
  bool Connected(const Eigen::Vector3d& from, const Eigen::Vector3d& to, std::int64_t* reached) {
    std::vector<std::int64_t> queue;
    for (std::int64_t idx : Neighbourhood(from)) {
      if (state_[idx] == kFree) {
        state_[idx] = kVisited;
        queue.push_back(idx);
      }
    }
    std::vector<std::int64_t> targets = Neighbourhood(to);
    std::sort(targets.begin(), targets.end());
    const std::int64_t stride[3] = {1, n_[0], n_[0] * n_[1]};
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::int64_t idx = queue[head];
      if (std::binary_search(targets.begin(), targets.end(), idx)) {
        *reached = static_cast<std::int64_t>(queue.size());
        return true;
      }
      const std::int64_t c[3] = {idx % n_[0], (idx / n_[0]) % n_[1], idx / (n_[0] * n_[1])};
      for (int axis = 0; axis < 3; ++axis) {
        for (int dir = -1; dir <= 1; dir += 2) {
          const std::int64_t nc = c[axis] + dir;
          if (nc < 0 || nc >= n_[axis]) continue;
          const std::int64_t nidx = idx + dir * stride[axis];
          if (state_[nidx] != kFree) continue;
          state_[nidx] = kVisited;
          queue.push_back(nidx);
        }
      }
    }
    *reached = static_cast<std::int64_t>(queue.size());
    return false;
  }

 private:
  static constexpr std::uint8_t kFree = 0, kBlocked = 1, kVisited = 2;

  double Centre(int axis, std::int64_t i) const { return world_.bounds.min()[axis] + (static_cast<double>(i) + 0.5) * cell_; }
  std::int64_t Index(std::int64_t i, std::int64_t j, std::int64_t k) const { return i + n_[0] * (j + n_[1] * k); }
  std::int64_t CellOf(int axis, double v) const {
    const auto i = static_cast<std::int64_t>(std::floor((v - world_.bounds.min()[axis]) / cell_));
    return std::clamp<std::int64_t>(i, 0, n_[axis] - 1);
  }

  // The 3x3x3 block of cells around p (clamped to the grid).
  std::vector<std::int64_t> Neighbourhood(const Eigen::Vector3d& p) const {
    std::vector<std::int64_t> out;
    const std::int64_t c[3] = {CellOf(0, p.x()), CellOf(1, p.y()), CellOf(2, p.z())};
    for (std::int64_t k = std::max<std::int64_t>(0, c[2] - 1); k <= std::min(n_[2] - 1, c[2] + 1); ++k)
      for (std::int64_t j = std::max<std::int64_t>(0, c[1] - 1); j <= std::min(n_[1] - 1, c[1] + 1); ++j)
        for (std::int64_t i = std::max<std::int64_t>(0, c[0] - 1); i <= std::min(n_[0] - 1, c[0] + 1); ++i)
          out.push_back(Index(i, j, k));
    return out;
  }

  // Tests the free cells whose centres lie within `box` grown by the threshold.
  template <typename Blocks>
  void MarkRange(const Eigen::AlignedBox3d& box, Blocks&& blocks) {
    std::int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      const double min_v = box.min()[a] - threshold_, max_v = box.max()[a] + threshold_;
      if (max_v < world_.bounds.min()[a] || min_v > world_.bounds.max()[a]) return;
      lo[a] = CellOf(a, min_v);
      hi[a] = CellOf(a, max_v);
    }
    for (std::int64_t k = lo[2]; k <= hi[2]; ++k)
      for (std::int64_t j = lo[1]; j <= hi[1]; ++j)
        for (std::int64_t i = lo[0]; i <= hi[0]; ++i) {
          auto& s = state_[Index(i, j, k)];
          if (s == kBlocked) continue;
          if (blocks(V3{Centre(0, i), Centre(1, j), Centre(2, k)})) s = kBlocked;
        }
  }

  const ObstacleField& field_;
  const World& world_;
  double cell_;
  double threshold_;
  std::int64_t n_[3] = {1, 1, 1};
  std::vector<std::uint8_t> state_;
};

ValidationResult ValidateWorld(const World& world, const ValidationOptions& options) {
  ValidationResult result;
  auto fail = [&](std::string field, std::string reason) {
    result.ok = false;
    result.field = std::move(field);
    result.reason = std::move(reason);
    return result;
  };

  // Bounds: a real, finite, not absurd volume.
  const Eigen::Vector3d lo = world.bounds.min(), hi = world.bounds.max();
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]) || !(hi[a] > lo[a])) {
      return fail("bounds", "min must be below max on every axis (got min " + PointText(lo) + ", max " + PointText(hi) + ")");
    }
    if (hi[a] - lo[a] > kMaxExtent) {
      return fail("bounds", "extent " + Metres(hi[a] - lo[a]) + " along " + "xyz"[a] + " exceeds the 2000 m limit");
    }
  }

  // Start and goal: inside the bounds, clear of everything by `clearance`.
  const ObstacleField field(world);
  const std::pair<const char*, Eigen::Vector3d> ends[2] = {{"start", world.start}, {"goal", world.goal}};
  for (const auto& [name, p] : ends) {
    if (!p.allFinite()) return fail(name, "not a finite point");
    for (int a = 0; a < 3; ++a) {
      if (p[a] < lo[a] || p[a] > hi[a]) {
        return fail(name, PointText(p) + " is outside the bounds (min " + PointText(lo) + ", max " + PointText(hi) + ")");
      }
    }
    int nearest = -2;
    const double d = field.Distance(p, &nearest);
    if (d < options.clearance) {
      const std::string what = nearest == -1 ? std::string("the ground (z = ") + FormatFixed(world.ground.z, 2, false) + ")"
                                             : "objects[" + std::to_string(nearest) + "] (" +
                                                   ObjectKind(world.objects[nearest]) + ")";
      if (d <= 0.0) return fail(name, PointText(p) + " is inside " + (nearest == -1 ? "(below) " : "") + what);
      return fail(name, PointText(p) + " is " + Metres(d) + " from " + what + "; needs at least " +
                            Metres(options.clearance) + " clearance");
    }
  }

  // Movers: the vehicle must not start inside one (the box around its shape where it stands at
  // t = 0, grown by the clearance). Where they go later is the flight's business.
  for (std::size_t i = 0; i < world.movers.size(); ++i) {
    const Mover& mover = world.movers[i];
    const MoverPose pose = MoverTrajectory(mover).Pose(0.0);
    Eigen::AlignedBox3d box;
    const TriangleMesh mesh = MoverMesh(mover);
    for (const auto& v : mesh.vertices) box.extend(pose.ToWorld(v.cast<double>()));
    if (!box.isEmpty() && box.exteriorDistance(world.start) < options.clearance) {
      return fail("movers[" + std::to_string(i) + "]", "'" + mover.name + "' stands within " + Metres(options.clearance) +
                                                           " of start " + PointText(world.start) + " at t = 0");
    }
  }

  if (!options.check_route) return result;

  // Route: choose the grid cell (grown in fixed 1.25x steps until the grid fits the budget).
  double cell = options.cell;
  const Eigen::Vector3d size = hi - lo;
  auto cells_for = [&](double c) {
    return std::ceil(size.x() / c) * std::ceil(size.y() / c) * std::ceil(size.z() / c);
  };
  while (cells_for(cell) > static_cast<double>(options.max_cells)) cell = cell * 1.25;
  result.cell = cell;
  OccupancyRaster raster(field, world, cell, options.route_radius + 0.5 * cell);
  raster.Rasterise();
  if (!raster.Connected(world.start, world.goal, &result.cells_reached)) {
    return fail("goal", "no collision-free route at least " + Metres(2.0 * options.route_radius) +
                            " wide from start to goal (grid " + FormatFixed(cell, 3, false) + " m, " +
                            std::to_string(result.cells_reached) + " cells reachable from start)");
  }
  return result;
}

}  // namespace enavi::worlds
