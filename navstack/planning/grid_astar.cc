#include "navstack/planning/grid_astar.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <queue>
#include <cstdlib>
#include <memory>

namespace enavi::navstack {
namespace {

using Vec3i = Eigen::Vector3i;

// Ego-Planner, dyn_a_star.h: tie_breaker_ = 1.0 + 1.0 / 10000.
constexpr double kTieBreaker = 1.0 + 1.0 / 10000;

// Ego-Planner, dyn_a_star.cpp getDiagHeu: diagonal distance in cells on a 26-connected grid.
double DiagonalHeuristic(const Vec3i& a, const Vec3i& b) {
  std::array<int, 3> d = {std::abs(a.x() - b.x()), std::abs(a.y() - b.y()), std::abs(a.z() - b.z())};
  std::sort(d.begin(), d.end());
  return std::sqrt(3.0) * d[0] + std::sqrt(2.0) * (d[1] - d[0]) + (d[2] - d[1]);
}

struct Node {
  Vec3i cell;
  double g;
  int parent;  // index into the node list, -1 for the start
  bool closed;
};

struct OpenEntry {
  double f;
  std::int64_t order;  // insertion counter: deterministic ties
  int node;
  bool operator>(const OpenEntry& o) const { return f != o.f ? f > o.f : order > o.order; }
};

}  // namespace

AstarResult GridAstar(const InflatedOccupancy& occupancy, const Eigen::AlignedBox3d& bounds,
                      const Eigen::Vector3d& start, const Eigen::Vector3d& goal, WorkCounts* work,
                      const OverBudget& over_budget) {
  const VoxelGrid& grid = occupancy.grid();
  AstarResult result;
  const auto usable = [&](const Vec3i& c) {
    return grid.InBounds(c) && bounds.contains(grid.CenterOf(c)) && !occupancy.CellOccupied(c);
  };
  // Occupied ends walk away from the other end until free (or out of the bounds: no path).
  const auto adjust = [&](Eigen::Vector3d p, const Eigen::Vector3d& other, Vec3i* cell) {
    const Eigen::Vector3d away = (p - other).normalized() * grid.resolution;
    *cell = grid.CellOf(p);
    while (!usable(*cell)) {
      if (!grid.InBounds(*cell) || !bounds.contains(grid.CenterOf(*cell)) || !away.allFinite()) {
        return false;
      }
      p += away;
      *cell = grid.CellOf(p);
    }
    return true;
  };
  Vec3i s, t;
  if (!adjust(start, goal, &s) || !adjust(goal, start, &t)) return result;

  // Grid index -> node + 1 (0: not seen). calloc'd: pages the search never reaches stay untouched.
  struct FreeDeleter {
    void operator()(std::int32_t* p) const { std::free(p); }
  };
  const std::unique_ptr<std::int32_t[], FreeDeleter> index_of(
      static_cast<std::int32_t*>(std::calloc(grid.cells.size(), sizeof(std::int32_t))));
  if (!index_of) throw std::bad_alloc();
  std::vector<Node> nodes;
  std::priority_queue<OpenEntry, std::vector<OpenEntry>, std::greater<>> open;
  std::int64_t order = 0;
  nodes.push_back({s, 0.0, -1, false});
  index_of[grid.Index(s)] = 1;
  open.push({kTieBreaker * DiagonalHeuristic(s, t), order++, 0});
  int expansions = 0;
  const auto finish = [&](AstarStatus status) {
    result.status = status;
    result.expansions = expansions;
    return result;
  };
  while (!open.empty()) {
    const OpenEntry top = open.top();
    open.pop();
    if (nodes[top.node].closed) continue;  // a stale entry (a cheaper one came first)
    if (over_budget && over_budget(work != nullptr ? *work : WorkCounts{})) {
      return finish(AstarStatus::kOverBudget);
    }
    nodes[top.node].closed = true;
    ++expansions;
    if (work != nullptr) work->Add(WorkUnit::kAstarExpansion, 1);
    const Vec3i cur = nodes[top.node].cell;
    if (cur == t) {
      for (int i = top.node; i >= 0; i = nodes[i].parent) result.path.push_back(grid.CenterOf(nodes[i].cell));
      std::reverse(result.path.begin(), result.path.end());
      return finish(AstarStatus::kOk);
    }
    const double g_cur = nodes[top.node].g;
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          const Vec3i c = cur + Vec3i(dx, dy, dz);
          if (!grid.InBounds(c)) continue;
          const double g = g_cur + std::sqrt(static_cast<double>(dx * dx + dy * dy + dz * dz));
          std::int32_t& slot = index_of[grid.Index(c)];
          if (slot == 0) {
            slot = static_cast<std::int32_t>(nodes.size()) + 1;
            if (!usable(c)) {
              nodes.push_back({c, 0.0, -1, true});  // remembered as blocked
              continue;
            }
            nodes.push_back({c, g, top.node, false});
          } else {
            Node& n = nodes[slot - 1];
            if (n.closed || g >= n.g) continue;
            n.g = g;
            n.parent = top.node;
          }
          open.push({g + kTieBreaker * DiagonalHeuristic(c, t), order++, slot - 1});
        }
      }
    }
  }
  return finish(AstarStatus::kNoPath);
}

}  // namespace enavi::navstack
