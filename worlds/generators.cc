#include "worlds/generators.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <utility>
#include <variant>

#include "worlds/detmath.h"
#include "worlds/movers.h"
#include "worlds/number_text.h"
#include "worlds/primitives.h"
#include "worlds/validate.h"

// Portability rules for this file: random numbers only through Rng (raw 64-bit draws mapped by
// hand, never std::*_distribution), never two draws in one expression or one call's arguments
// (their order is the compiler's), no libm transcendental functions (detmath instead), scalar
// doubles for positions, and every value quantised to the file precision before validation.

namespace enavi::worlds {
namespace {

constexpr double kFlightAltitude = 1.5;  // m above the ground
constexpr double kCanyonAltitude = 5.0;  // m: over the low roofs, below every other one
constexpr double kDroneRadius = 0.3;     // m; the straight line must come closer than this somewhere
constexpr int kMaxDraws = 64;

std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Uniform draws from std::mt19937_64 (whose output sequence the standard specifies).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  /// [0, 1) with 53 random bits.
  double Uniform() { return static_cast<double>(engine_() >> 11) * (1.0 / 9007199254740992.0); }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  /// Integer in [lo, hi].
  int Int(int lo, int hi) { return std::min(hi, lo + static_cast<int>(Uniform() * (hi - lo + 1))); }
  bool Chance(double p) { return Uniform() < p; }
  /// A point uniform in [x0, x1] x [y0, y1]. y is drawn first: the generators once drew both as
  /// one call's arguments, whose evaluation order C++ leaves to the compiler, and GCC, which made
  /// the golden worlds, evaluates them right to left (clang left to right: other worlds).
  std::pair<double, double> PointIn(double x0, double x1, double y0, double y1) {
    const double y = Uniform(y0, y1);
    return {Uniform(x0, x1), y};
  }

 private:
  std::mt19937_64 engine_;
};

// ---------------------------------------------------------------------------------------------
// 2-D footprints for spacing objects apart (gap = free distance between footprints).

struct Footprint {
  double cx = 0, cy = 0;
  double hx = 0, hy = 0;  // rectangle half extents (axis-aligned)
  double r = 0;           // circle radius
  bool circle = false;
};

Footprint Circle(double x, double y, double r) { return {x, y, 0, 0, r, true}; }
Footprint Rect(double x, double y, double hx, double hy) { return {x, y, hx, hy, 0, false}; }

// Axis-aligned rectangle around a rectangle of size sx x sy rotated by yaw.
Footprint RotatedRect(double x, double y, double sx, double sy, double yaw) {
  double s, c;
  detmath::SinCos(yaw, &s, &c);
  return Rect(x, y, 0.5 * (std::abs(c) * sx + std::abs(s) * sy), 0.5 * (std::abs(s) * sx + std::abs(c) * sy));
}

double RectPointDistance(const Footprint& r, double x, double y) {
  const double dx = std::max(std::abs(x - r.cx) - r.hx, 0.0);
  const double dy = std::max(std::abs(y - r.cy) - r.hy, 0.0);
  return std::sqrt(dx * dx + dy * dy);
}

double Gap(const Footprint& a, const Footprint& b) {
  if (a.circle && b.circle) {
    const double dx = a.cx - b.cx, dy = a.cy - b.cy;
    return std::sqrt(dx * dx + dy * dy) - a.r - b.r;
  }
  if (a.circle) return RectPointDistance(b, a.cx, a.cy) - a.r;
  if (b.circle) return RectPointDistance(a, b.cx, b.cy) - b.r;
  const double dx = std::abs(a.cx - b.cx) - a.hx - b.hx;
  const double dy = std::abs(a.cy - b.cy) - a.hy - b.hy;
  if (dx > 0 && dy > 0) return std::sqrt(dx * dx + dy * dy);
  return std::max(dx, dy);
}

class Layout {
 public:
  bool Fits(const Footprint& f, double gap) const {
    return std::all_of(items_.begin(), items_.end(), [&](const Footprint& o) { return Gap(f, o) >= gap; });
  }
  void Add(const Footprint& f) { items_.push_back(f); }

 private:
  std::vector<Footprint> items_;
};

// A rectangular placement area in xy.
struct Area {
  double x0, x1, y0, y1;
  bool Contains(const Footprint& f, double margin = 0.0) const {
    const double hx = f.circle ? f.r : f.hx, hy = f.circle ? f.r : f.hy;
    return f.cx - hx >= x0 + margin && f.cx + hx <= x1 - margin && f.cy - hy >= y0 + margin && f.cy + hy <= y1 - margin;
  }
};

// ---------------------------------------------------------------------------------------------
// Building blocks. All take the ground height `gz` and positions as plain doubles.

struct Builder {
  World* world;

  void AddBox(double x, double y, double z_bottom, double sx, double sy, double sz, double yaw = 0.0) {
    Box b;
    b.center = Eigen::Vector3d(x, y, z_bottom + 0.5 * sz);
    b.size = Eigen::Vector3d(sx, sy, sz);
    b.yaw = yaw;
    world->objects.emplace_back(b);
  }
  // A box whose centre is at local (lx, ly) in a frame at (x, y) rotated by yaw.
  void AddBoxLocal(double x, double y, double yaw, double lx, double ly, double z_bottom, double sx, double sy,
                   double sz) {
    double s, c;
    detmath::SinCos(yaw, &s, &c);
    AddBox(x + c * lx - s * ly, y + s * lx + c * ly, z_bottom, sx, sy, sz, yaw);
  }
  void AddCylinder(double x, double y, double z_bottom, double radius, double height) {
    Cylinder c;
    c.base = Eigen::Vector3d(x, y, z_bottom);
    c.radius = radius;
    c.height = height;
    world->objects.emplace_back(c);
  }
  void AddEllipsoid(double x, double y, double z, double rx, double ry, double rz) {
    Ellipsoid e;
    e.center = Eigen::Vector3d(x, y, z);
    e.radii = Eigen::Vector3d(rx, ry, rz);
    world->objects.emplace_back(e);
  }
};

struct TreeStyle {
  double trunk_r0, trunk_r1;   // trunk radius range
  double base0, base1;         // crown bottom height range above ground
  double crown_r0, crown_r1;   // horizontal crown radii range (drawn per axis: irregular)
  double crown_z0, crown_z1;   // vertical crown radius range
  double lean;                 // max horizontal crown offset from the trunk
};

// Draws a tree's shape at (x, y): returns its footprint; `commit` adds trunk and crown.
struct Tree {
  double x, y, trunk_r, base, rx, ry, rz, ox, oy;
  Footprint footprint() const { return Circle(x + ox, y + oy, std::max(rx, ry)); }
  void Commit(Builder& b, double gz) const {
    b.AddCylinder(x, y, gz, trunk_r, base + rz);
    b.AddEllipsoid(x + ox, y + oy, gz + base + rz, rx, ry, rz);
  }
};

Tree DrawTree(Rng& rng, double x, double y, const TreeStyle& s) {
  Tree t;
  t.x = x;
  t.y = y;
  t.trunk_r = rng.Uniform(s.trunk_r0, s.trunk_r1);
  t.base = rng.Uniform(s.base0, s.base1);
  t.rx = rng.Uniform(s.crown_r0, s.crown_r1);
  t.ry = rng.Uniform(s.crown_r0, s.crown_r1);
  t.rz = rng.Uniform(s.crown_z0, s.crown_z1);
  t.ox = rng.Uniform(-s.lean, s.lean);
  t.oy = rng.Uniform(-s.lean, s.lean);
  // The crown must hold its own trunk: keep the offset inside the crown.
  t.ox = std::clamp(t.ox, -0.5 * t.rx, 0.5 * t.rx);
  t.oy = std::clamp(t.oy, -0.5 * t.ry, 0.5 * t.ry);
  return t;
}

// Straight-line parameters shared by the generators.
struct Route {
  double sx, sy, gx, gy;
  double YAt(double x) const { return gx == sx ? sy : sy + (gy - sy) * (x - sx) / (gx - sx); }
};

void SetBounds(World* w, double x0, double y0, double z0, double x1, double y1, double z1) {
  w->bounds = Eigen::AlignedBox3d(Eigen::Vector3d(x0, y0, z0), Eigen::Vector3d(x1, y1, z1));
}

// ---------------------------------------------------------------------------------------------
// Scenarios. Each builds one draw; Generate() validates and redraws.

using Params = std::map<std::string, double>;

// s1: city with buildings of varying height, open streets, some tall towers.
void BuildS1(Rng& rng, const Params& p, World* w) {
  const double L = p.at("length"), half = 0.5 * L;
  const Area area{-half - 8.0, half + 8.0, -16.0, 16.0};
  SetBounds(w, area.x0, area.y0, 0.0, area.x1, area.y1, 8.0);
  const Route route{-half, rng.Uniform(-1.5, 1.5), half, rng.Uniform(-1.5, 1.5)};
  w->start = Eigen::Vector3d(route.sx, route.sy, kFlightAltitude);
  w->goal = Eigen::Vector3d(route.gx, route.gy, kFlightAltitude);
  Builder b{w};
  Layout layout;
  layout.Add(Circle(route.sx, route.sy, 3.5));
  layout.Add(Circle(route.gx, route.gy, 3.5));
  constexpr double kStreet = 3.0;  // least gap between buildings
  auto try_building = [&](double x, double y) {
    // Footprints: many small (kiosks, houses), some medium, a few large blocks.
    const double size_class = rng.Uniform();
    const double lo = size_class < 0.5 ? 3.0 : (size_class < 0.85 ? 5.0 : 9.0);
    const double hi = size_class < 0.5 ? 5.0 : (size_class < 0.85 ? 9.0 : 13.0);
    const double sx = rng.Uniform(lo, hi), sy = rng.Uniform(lo, hi);
    const double yaw = rng.Chance(0.3) ? rng.Uniform(-0.5, 0.5) : 0.0;
    // Mostly low-rise (some below the flight ceiling), one in four a tower.
    const double h = rng.Chance(0.25) ? rng.Uniform(14.0, 30.0) : rng.Uniform(3.0, 10.0);
    const Footprint f = RotatedRect(x, y, sx, sy, yaw);
    if (!area.Contains(f) || !layout.Fits(f, kStreet)) return false;
    layout.Add(f);
    b.AddBox(x, y, 0.0, sx, sy, h, yaw);
    return true;
  };
  // Buildings on and beside the straight line, so the flight has to steer between them.
  const int blockers = std::max(2, static_cast<int>(std::round(L / 7.0)));
  for (int i = 1; i <= blockers; ++i) {
    for (int attempt = 0; attempt < 20; ++attempt) {
      const double x = -half + L * i / (blockers + 1) + rng.Uniform(-2.0, 2.0);
      if (try_building(x, route.YAt(x) + rng.Uniform(-2.5, 2.5))) break;
    }
  }
  const int target = static_cast<int>(std::round((area.x1 - area.x0) * (area.y1 - area.y0) * 0.012));
  for (int attempt = 0, placed = 0; attempt < 1000 && placed < target; ++attempt) {
    const auto [x, y] = rng.PointIn(area.x0, area.x1, area.y0, area.y1);
    placed += try_building(x, y) ? 1 : 0;
  }
  // Street lamps: thin poles at flight altitude.
  for (int attempt = 0, placed = 0; attempt < 300 && placed < 16; ++attempt) {
    const auto [x, y] = rng.PointIn(area.x0, area.x1, area.y0, area.y1);
    const Footprint f = Circle(x, y, 0.12);
    if (!area.Contains(f, 0.5) || !layout.Fits(f, 2.0)) continue;
    layout.Add(f);
    b.AddCylinder(f.cx, f.cy, 0.0, 0.12, 4.5);
    ++placed;
  }
}

// Where footpaths cross a park: called after the pavilion is placed, before the trees; adds the
// paths' strips to the layout (so trees keep clear of them) and returns their centre lines' x.
using LayPaths = std::function<std::vector<double>(Rng&, const Area&, Layout*)>;

// s2: park with dense, irregular trees, bushes and a pavilion (and, for park-people, footpaths).
void BuildPark(Rng& rng, const Params& p, World* w, const LayPaths& lay_paths, std::vector<double>* paths) {
  const double L = p.at("length"), half = 0.5 * L;
  const Area area{-half - 6.0, half + 6.0, -14.0, 14.0};
  SetBounds(w, area.x0, area.y0, 0.0, area.x1, area.y1, 7.0);
  const Route route{-half, rng.Uniform(-2.0, 2.0), half, rng.Uniform(-2.0, 2.0)};
  w->start = Eigen::Vector3d(route.sx, route.sy, kFlightAltitude);
  w->goal = Eigen::Vector3d(route.gx, route.gy, kFlightAltitude);
  Builder b{w};
  Layout layout;
  layout.Add(Circle(route.sx, route.sy, 2.5));
  layout.Add(Circle(route.gx, route.gy, 2.5));

  // Pavilion near the middle of the route: pillars under a two-tier roof; one can fly through.
  {
    const double px = rng.Uniform(-0.15 * L, 0.15 * L);
    const double py = route.YAt(px) + rng.Uniform(-2.0, 2.0);
    const double size = rng.Uniform(5.0, 6.5), yaw = rng.Uniform(0.0, 0.5 * detmath::kPi);
    const double roof = size + 1.2, pillar_h = 2.9;
    const double inset = 0.5 * size - 0.3;
    for (int i = 0; i < 4; ++i) {
      const double lx = (i & 1) ? inset : -inset, ly = (i & 2) ? inset : -inset;
      double s, c;
      detmath::SinCos(yaw, &s, &c);
      b.AddCylinder(px + c * lx - s * ly, py + s * lx + c * ly, 0.0, 0.18, pillar_h);
    }
    b.AddBox(px, py, pillar_h, roof, roof, 0.25, yaw);
    b.AddBox(px, py, pillar_h + 0.25, 0.6 * size, 0.6 * size, 0.5, yaw);
    layout.Add(RotatedRect(px, py, roof, roof, yaw));
  }

  if (lay_paths) *paths = lay_paths(rng, area, &layout);

  // Trees until the park is saturated, at least 1.2 m between crown footprints.
  const TreeStyle style{0.12, 0.3, 0.5, 2.8, 1.0, 2.4, 1.0, 2.0, 0.4};
  for (int attempt = 0, placed = 0; attempt < 3000 && placed < 200; ++attempt) {
    const auto [x, y] = rng.PointIn(area.x0, area.x1, area.y0, area.y1);
    const Tree t = DrawTree(rng, x, y, style);
    const Footprint f = t.footprint();
    if (!area.Contains(Circle(t.x, t.y, t.trunk_r)) || !layout.Fits(f, 1.2)) continue;
    layout.Add(f);
    t.Commit(b, 0.0);
    ++placed;
  }
  // Young trees with low crowns in the gaps: the park's irregular undergrowth.
  const TreeStyle young{0.06, 0.12, 0.4, 1.2, 0.5, 1.0, 0.6, 1.0, 0.2};
  for (int attempt = 0, placed = 0; attempt < 2000 && placed < 60; ++attempt) {
    const auto [x, y] = rng.PointIn(area.x0, area.x1, area.y0, area.y1);
    const Tree t = DrawTree(rng, x, y, young);
    if (!area.Contains(t.footprint()) || !layout.Fits(t.footprint(), 1.1)) continue;
    layout.Add(t.footprint());
    t.Commit(b, 0.0);
    ++placed;
  }
  // Bushes in what is left.
  for (int attempt = 0, placed = 0; attempt < 600 && placed < 20; ++attempt) {
    const double rx = rng.Uniform(0.6, 1.3), ry = rng.Uniform(0.6, 1.3), rz = rng.Uniform(0.5, 0.9);
    const auto [x, y] = rng.PointIn(area.x0, area.x1, area.y0, area.y1);
    const Footprint f = Circle(x, y, std::max(rx, ry));
    if (!area.Contains(f) || !layout.Fits(f, 1.5)) continue;
    layout.Add(f);
    b.AddEllipsoid(f.cx, f.cy, 0.6 * rz, rx, ry, rz);
    ++placed;
  }
}

void BuildS2(Rng& rng, const Params& p, World* w) { BuildPark(rng, p, w, nullptr, nullptr); }

// ---------------------------------------------------------------------------------------------
// Movers (worlds/movers.h) for the scenarios with moving obstacles.

// Pedestrians' free walking speed is 1.2-1.5 m/s (Fruin, "Pedestrian Planning and Design", 1971;
// the Highway Capacity Manual designs with 1.2 m/s); drawn a little wider for strollers and joggers.
constexpr double kWalkSpeedMin = 1.0, kWalkSpeedMax = 1.6;  // m/s
// Through traffic on a residential street, below 30 km/h.
constexpr double kCarSpeedMin = 4.0, kCarSpeedMax = 8.0;  // m/s
// To time a mover to meet the flight at a crossing: the planners' cruise (0.9 v_max, v_max 2 m/s)
// after about 2 s of take-off.
constexpr double kDroneCruise = 1.8, kTakeOff = 2.0;

// A mover going back and forth between a and b (on the ground), starting at a after `delay`.
Mover BackAndForth(std::string name, std::vector<Object> shape, double ax, double ay, double bx, double by, double speed,
                   double delay) {
  Mover m;
  m.name = std::move(name);
  m.shape = std::move(shape);
  m.speed = speed;
  m.mode = MoverMode::kBackAndForth;
  m.start_delay = delay;
  MoverWaypoint a, b;
  a.position = Eigen::Vector3d(ax, ay, 0.0);
  b.position = Eigen::Vector3d(bx, by, 0.0);
  m.waypoints = {a, b};
  return m;
}

// The same, timed to pass the point c (on the segment a-b) at time `at`: it waits at a, or, when
// a is too far to get to c in time, starts from nearer c without waiting.
Mover MeetAt(std::string name, std::vector<Object> shape, double ax, double ay, double bx, double by, double speed,
             double cx, double cy, double at) {
  const double to_c = std::sqrt((cx - ax) * (cx - ax) + (cy - ay) * (cy - ay));
  const double reach = speed * at;
  if (to_c <= reach) return BackAndForth(std::move(name), std::move(shape), ax, ay, bx, by, speed, at - to_c / speed);
  const double f = reach / to_c;  // the start moves along c-a to reach c at `at`
  return BackAndForth(std::move(name), std::move(shape), cx + f * (ax - cx), cy + f * (ay - cy), bx, by, speed, 0.0);
}

// A person: a 0.5 m wide, 1.75 m tall cylinder standing on the mover's origin.
std::vector<Object> PersonShape() {
  Cylinder body;
  body.radius = 0.25;
  body.height = 1.75;
  return {body};
}

// park-people: s2's park with two footpaths across it, on which people walk back and forth; on
// each path one is timed to cross the start-goal line about when the flight gets there.
void BuildParkPeople(Rng& rng, const Params& p, World* w) {
  constexpr double kPathHalfWidth = 0.9;
  const double L = p.at("length"), half = 0.5 * L;
  const LayPaths lay = [&](Rng& r, const Area& area, Layout* layout) {
    std::vector<double> xs;
    for (const double at : {0.3, 0.7}) {
      for (int attempt = 0; attempt < 30; ++attempt) {
        const double x = -half + L * at + r.Uniform(-0.12 * L, 0.12 * L);
        const Footprint strip = Rect(x, 0.5 * (area.y0 + area.y1), kPathHalfWidth, 0.5 * (area.y1 - area.y0));
        if (!layout->Fits(strip, 0.3)) continue;
        layout->Add(strip);
        xs.push_back(x);
        break;
      }
    }
    return xs;
  };
  std::vector<double> paths;
  BuildPark(rng, p, w, lay, &paths);
  const double y0 = w->bounds.min().y() + 0.5, y1 = w->bounds.max().y() - 0.5;
  const Route route{w->start.x(), w->start.y(), w->goal.x(), w->goal.y()};
  int n = 0;
  for (const double x : paths) {
    const double cross_y = route.YAt(x);
    const double at = kTakeOff + (x - w->start.x()) / kDroneCruise;
    // One walker timed to the flight, from a random end; one more with a random delay.
    const double speed = rng.Uniform(kWalkSpeedMin, kWalkSpeedMax);
    const bool from_low = rng.Chance(0.5);
    w->movers.push_back(MeetAt("person-" + std::to_string(n++), PersonShape(), x, from_low ? y0 : y1, x,
                               from_low ? y1 : y0, speed, x, cross_y, at));
    const double speed2 = rng.Uniform(kWalkSpeedMin, kWalkSpeedMax);
    const double side = rng.Chance(0.5) ? -0.45 : 0.45;
    const double delay = rng.Uniform(0.0, 10.0);
    w->movers.push_back(BackAndForth("person-" + std::to_string(n++), PersonShape(), x + side, from_low ? y1 : y0,
                                     x + side, from_low ? y0 : y1, speed2, delay));
  }
}

// s3: indoor hall: walls, floor and ceiling as boxes, two partitions with doorways, furniture.
void BuildS3(Rng& rng, const Params& p, World* w) {
  const double L = p.at("length"), half = 0.5 * L;
  const double hx = half + 2.5, hy = 0.5 * rng.Uniform(10.0, 12.0), H = rng.Uniform(3.8, 4.5);
  constexpr double kWall = 0.3;
  SetBounds(w, -hx - kWall, -hy - kWall, -kWall, hx + kWall, hy + kWall, H + kWall);
  w->ground.enabled = false;  // the floor is a box
  const Route route{-half, rng.Uniform(-1.5, 1.5), half, rng.Uniform(-1.5, 1.5)};
  w->start = Eigen::Vector3d(route.sx, route.sy, kFlightAltitude);
  w->goal = Eigen::Vector3d(route.gx, route.gy, kFlightAltitude);
  Builder b{w};
  // Shell.
  b.AddBox(0.0, 0.0, -kWall, 2 * (hx + kWall), 2 * (hy + kWall), kWall);  // floor
  b.AddBox(0.0, 0.0, H, 2 * (hx + kWall), 2 * (hy + kWall), kWall);       // ceiling
  b.AddBox(-hx - 0.5 * kWall, 0.0, 0.0, kWall, 2 * (hy + kWall), H);
  b.AddBox(hx + 0.5 * kWall, 0.0, 0.0, kWall, 2 * (hy + kWall), H);
  b.AddBox(0.0, -hy - 0.5 * kWall, 0.0, 2 * hx, kWall, H);
  b.AddBox(0.0, hy + 0.5 * kWall, 0.0, 2 * hx, kWall, H);

  Layout layout;
  layout.Add(Circle(route.sx, route.sy, 1.5));
  layout.Add(Circle(route.gx, route.gy, 1.5));
  // Two partitions across the hall, each with a doorway; one reaches the ceiling, one is a
  // low divider the drone may also cross above.
  const bool first_full = rng.Chance(0.5);
  for (int k = 0; k < 2; ++k) {
    const double x = (k == 0 ? -L / 6.0 : L / 6.0) + rng.Uniform(-0.5, 0.5);
    const double door = rng.Uniform(2.2, 3.0), door_y = rng.Uniform(-hy + 1.8, hy - 1.8);
    const double height = (k == 0) == first_full ? H : rng.Uniform(2.2, 2.5);
    const double y_lo = door_y - 0.5 * door, y_hi = door_y + 0.5 * door;
    b.AddBox(x, 0.5 * (-hy + y_lo), 0.0, 0.15, y_lo + hy, height);
    b.AddBox(x, 0.5 * (y_hi + hy), 0.0, 0.15, hy - y_hi, height);
    layout.Add(Rect(x, 0.5 * (-hy + y_lo), 0.075, 0.5 * (y_lo + hy)));
    layout.Add(Rect(x, 0.5 * (y_hi + hy), 0.075, 0.5 * (hy - y_hi)));
  }

  // Furniture, at least 1 m apart (shelves may stand against the walls).
  const Area inside{-hx, hx, -hy, hy};
  const int target = static_cast<int>(std::round(4 * hx * hy * 0.2));
  for (int attempt = 0, placed = 0; attempt < 1500 && placed < target; ++attempt) {
    double x = rng.Uniform(-hx, hx), y = rng.Uniform(-hy, hy);
    const double kind = rng.Uniform();
    const double yaw = rng.Chance(0.5) ? 0.0 : (rng.Chance(0.5) ? 0.5 * detmath::kPi : rng.Uniform(0.0, detmath::kPi));
    std::function<void()> commit;
    Footprint f;
    if (kind < 0.22) {  // table on four legs
      const double sx = rng.Uniform(1.2, 2.0), sy = rng.Uniform(0.7, 1.0);
      f = RotatedRect(x, y, sx, sy, yaw);
      commit = [&b, x, y, yaw, sx, sy] {
        b.AddBoxLocal(x, y, yaw, 0.0, 0.0, 0.70, sx, sy, 0.05);
        for (int i = 0; i < 4; ++i) {
          b.AddBoxLocal(x, y, yaw, (i & 1 ? 1 : -1) * (0.5 * sx - 0.06), (i & 2 ? 1 : -1) * (0.5 * sy - 0.06), 0.0,
                        0.06, 0.06, 0.70);
        }
      };
    } else if (kind < 0.36) {  // round table
      const double r = rng.Uniform(0.45, 0.7);
      f = Circle(x, y, r);
      commit = [&b, x, y, r] {
        b.AddCylinder(x, y, 0.0, 0.3, 0.03);
        b.AddCylinder(x, y, 0.03, 0.06, 0.67);
        b.AddCylinder(x, y, 0.70, r, 0.05);
      };
    } else if (kind < 0.58) {  // shelf or cabinet, often against a long wall
      const double width = rng.Uniform(1.2, 2.4), depth = rng.Uniform(0.35, 0.6);
      const double height = rng.Chance(0.7) ? rng.Uniform(1.8, 2.4) : rng.Uniform(0.9, 1.2);
      double shelf_yaw = yaw;
      if (rng.Chance(0.5)) {
        shelf_yaw = 0.0;
        y = (rng.Chance(0.5) ? -1.0 : 1.0) * (hy - 0.5 * depth - 0.02);
      }
      f = RotatedRect(x, y, width, depth, shelf_yaw);
      commit = [&b, x, y, shelf_yaw, width, depth, height] { b.AddBox(x, y, 0.0, width, depth, height, shelf_yaw); };
    } else if (kind < 0.74) {  // sofa: seat, backrest, armrests
      const double width = rng.Uniform(1.8, 2.4);
      f = RotatedRect(x, y, width, 0.9, yaw);
      commit = [&b, x, y, yaw, width] {
        b.AddBoxLocal(x, y, yaw, 0.0, 0.1, 0.0, width - 0.4, 0.7, 0.45);
        b.AddBoxLocal(x, y, yaw, 0.0, -0.35, 0.0, width, 0.2, 0.9);
        b.AddBoxLocal(x, y, yaw, -0.5 * width + 0.1, 0.1, 0.0, 0.2, 0.7, 0.65);
        b.AddBoxLocal(x, y, yaw, 0.5 * width - 0.1, 0.1, 0.0, 0.2, 0.7, 0.65);
      };
    } else if (kind < 0.88) {  // potted plant
      const double r = rng.Uniform(0.4, 0.6), top = rng.Uniform(0.5, 0.8);
      f = Circle(x, y, r);
      commit = [&b, x, y, r, top] {
        b.AddCylinder(x, y, 0.0, 0.25, 0.45);
        b.AddEllipsoid(x, y, 0.45 + top, r, r, top);
      };
    } else {  // structural pillar, floor to ceiling
      const double r = rng.Uniform(0.25, 0.35);
      f = Circle(x, y, r);
      commit = [&b, x, y, r, H] { b.AddCylinder(x, y, 0.0, r, H); };
    }
    if (!inside.Contains(f, 0.01) || !layout.Fits(f, 1.0)) continue;
    layout.Add(f);
    commit();
    ++placed;
  }
}

// s4: city grid of buildings of similar height, streets between them, parked vehicles.
void BuildS4(Rng& rng, const Params& p, World* w) {
  const double L = p.at("length");
  const double P = L / (2.0 * std::sqrt(2.0));  // grid pitch: start and goal two blocks apart diagonally
  constexpr double kStreet = 6.0;
  const double block = P - kStreet;
  const double edge = 2.0 * P + 0.5 * kStreet;
  SetBounds(w, -edge, -edge, 0.0, edge, edge, 8.0);
  // Start on the street y = -P, goal on the street x = +P, near the intersections.
  w->start = Eigen::Vector3d(-P + rng.Uniform(-1.0, 1.0), -P, kFlightAltitude);
  w->goal = Eigen::Vector3d(P, P + rng.Uniform(-1.0, 1.0), kFlightAltitude);
  Builder b{w};
  const double base_height = rng.Uniform(13.0, 17.0);
  auto height = [&] { return base_height + rng.Uniform(-1.5, 1.5); };
  for (int j = -2; j < 2; ++j) {
    for (int i = -2; i < 2; ++i) {
      const double cx = (i + 0.5) * P, cy = (j + 0.5) * P;
      const double kind = rng.Uniform();
      if (kind < 0.25) {  // two buildings split by an alley along y
        const double alley = rng.Uniform(2.5, 3.0), wx = 0.5 * (block - alley);
        b.AddBox(cx - 0.5 * (alley + wx), cy, 0.0, wx, block, height());
        b.AddBox(cx + 0.5 * (alley + wx), cy, 0.0, wx, block, height());
      } else if (kind < 0.4) {  // two buildings split by an alley along x
        const double alley = rng.Uniform(2.5, 3.0), wy = 0.5 * (block - alley);
        b.AddBox(cx, cy - 0.5 * (alley + wy), 0.0, block, wy, height());
        b.AddBox(cx, cy + 0.5 * (alley + wy), 0.0, block, wy, height());
      } else {  // one building with small setbacks
        const double l = rng.Uniform(0.0, 0.6), r = rng.Uniform(0.0, 0.6);
        const double d = rng.Uniform(0.0, 0.6), u = rng.Uniform(0.0, 0.6);
        b.AddBox(cx + 0.5 * (l - r), cy + 0.5 * (d - u), 0.0, block - l - r, block - d - u, height());
      }
    }
  }
  // Parked vehicles along the kerbs (at flight altitude), away from start and goal.
  Layout layout;
  layout.Add(Circle(w->start.x(), w->start.y(), 5.0));
  layout.Add(Circle(w->goal.x(), w->goal.y(), 5.0));
  for (int attempt = 0, placed = 0; attempt < 400 && placed < 14; ++attempt) {
    const bool along_x = rng.Chance(0.5);
    const int street = rng.Int(-1, 1);
    const double along = rng.Uniform(-2.0 * P, 2.0 * P);
    const double side = (rng.Chance(0.5) ? -1.0 : 1.0) * (0.5 * kStreet - 1.2);
    const double length = rng.Uniform(4.2, 5.2), width = 1.9, h = rng.Uniform(1.5, 2.2);
    const double x = along_x ? along : street * P + side;
    const double y = along_x ? street * P + side : along;
    const Footprint f = along_x ? Rect(x, y, 0.5 * length, 0.5 * width) : Rect(x, y, 0.5 * width, 0.5 * length);
    // Keep intersections clear so every turn stays open.
    const double to_corner = along - std::round(along / P) * P;
    if (std::abs(to_corner) < 0.5 * kStreet + 0.5 * length + 0.5 || !layout.Fits(f, 3.0)) continue;
    layout.Add(f);
    b.AddBox(x, y, 0.0, 2.0 * f.hx, 2.0 * f.hy, h);
    ++placed;
  }
  // Street lamps on both kerbs, 9-13 m apart, and one at every corner of every intersection.
  auto lamp = [&](double x, double y) {
    const Footprint f = Circle(x, y, 0.1);
    if (!layout.Fits(f, 1.0)) return;
    layout.Add(f);
    b.AddCylinder(x, y, 0.0, 0.1, 5.0);
  };
  const double kerb = 0.5 * kStreet - 0.4;
  for (int street = -1; street <= 1; ++street) {
    for (const double side : {-kerb, kerb}) {
      for (double along = -2.0 * P + rng.Uniform(0.0, 4.0); along < 2.0 * P; along += rng.Uniform(9.0, 13.0)) {
        lamp(along, street * P + side);
        lamp(street * P + side, along);
      }
    }
    for (int cross = -1; cross <= 1; ++cross) {
      for (const double sx : {-kerb, kerb}) {
        for (const double sy : {-kerb, kerb}) lamp(street * P + sx, cross * P + sy);
      }
    }
  }
}

// street-traffic: s4's city grid with vans driving up and down the two middle streets, which
// cross the flight's routes (and the straight start-goal line at the centre); each timed to reach
// the crossing about when the flight does. They drive the centre line, clear of the parked cars.
void BuildStreetTraffic(Rng& rng, const Params& p, World* w) {
  BuildS4(rng, p, w);
  const double L = p.at("length");
  const double P = L / (2.0 * std::sqrt(2.0));
  const double end = w->bounds.max().x() - 3.0;
  auto van = [&rng] {
    Box body;
    body.size = Eigen::Vector3d(rng.Uniform(4.2, 5.2), 1.7, rng.Uniform(1.8, 2.4));
    body.center = Eigen::Vector3d(0.0, 0.0, 0.5 * body.size.z());
    return std::vector<Object>{body};
  };
  // Up the street x = 0: it crosses the flight's street y = -P about P from the start.
  {
    const double speed = rng.Uniform(kCarSpeedMin, kCarSpeedMax);
    const bool north = rng.Chance(0.5);
    w->movers.push_back(
        MeetAt("van-0", van(), 0.0, north ? -end : end, 0.0, north ? end : -end, speed, 0.0, -P, kTakeOff + P / kDroneCruise));
  }
  // Along the street y = 0: it crosses the goal's street x = P about 3 P from the start.
  {
    const double speed = rng.Uniform(kCarSpeedMin, kCarSpeedMax);
    const bool east = rng.Chance(0.5);
    w->movers.push_back(MeetAt("van-1", van(), east ? -end : end, 0.0, east ? end : -end, 0.0, speed, P, 0.0,
                               kTakeOff + 3.0 * P / kDroneCruise));
  }
}

// s5: village: houses, trees and fences on terrain slabs, a river channel below the ground and
// a bridge over it.
void BuildS5(Rng& rng, const Params& p, World* w) {
  const double L = p.at("length"), half = 0.5 * L;
  const Area area{-half - 8.0, half + 8.0, -18.0, 18.0};
  const double river_x = rng.Uniform(-3.0, 3.0), river_w = rng.Uniform(5.0, 7.0);
  constexpr double kDepth = 1.5, kSlab = 1.0, kFreeboard = 0.6;  // m: bed and water below the banks
  SetBounds(w, area.x0, area.y0, -kDepth - kSlab, area.x1, area.y1, 7.0);
  w->ground.enabled = false;  // terrain slabs instead, so the river can be lower
  const Route route{-half, rng.Uniform(-1.5, 1.5), half, rng.Uniform(-1.5, 1.5)};
  w->start = Eigen::Vector3d(route.sx, route.sy, kFlightAltitude);
  w->goal = Eigen::Vector3d(route.gx, route.gy, kFlightAltitude);
  Builder b{w};
  const double ylen = area.y1 - area.y0;
  const double bank_l = river_x - 0.5 * river_w, bank_r = river_x + 0.5 * river_w;
  b.AddBox(0.5 * (area.x0 + bank_l), 0.0, -kSlab, bank_l - area.x0, ylen, kSlab);
  b.AddBox(0.5 * (bank_r + area.x1), 0.0, -kSlab, area.x1 - bank_r, ylen, kSlab);
  b.AddBox(river_x, 0.0, -kDepth - kSlab, river_w, ylen, kSlab);  // river bed
  b.AddBox(river_x, 0.0, -kDepth, river_w, ylen, kDepth - kFreeboard);  // the water, below the banks

  Layout layout;
  layout.Add(Circle(route.sx, route.sy, 2.5));
  layout.Add(Circle(route.gx, route.gy, 2.5));
  layout.Add(Rect(river_x, 0.0, 0.5 * river_w + 0.5, 0.5 * ylen));  // nothing on the banks' edge

  // Bridge near the straight line: deck resting on both banks, railings at flight altitude, a pier.
  {
    const double by = std::clamp(route.YAt(river_x) + rng.Uniform(-4.0, 4.0), area.y0 + 4.0, area.y1 - 4.0);
    const double span = river_w + 3.0;
    b.AddBox(river_x, by, 0.0, span, 3.0, 0.4);
    b.AddBox(river_x, by - 1.44, 0.4, span, 0.12, 1.0);
    b.AddBox(river_x, by + 1.44, 0.4, span, 0.12, 1.0);
    b.AddCylinder(river_x, by, -kDepth, 0.35, kDepth);
    layout.Add(Rect(river_x, by, 0.5 * span, 1.5));
  }

  // Houses: walls, eaves and a ridge, all on one vertical axis. `gap` to everything placed.
  auto try_house = [&](double x, double y, double gap) {
    const double sx = rng.Uniform(4.5, 8.0), sy = rng.Uniform(3.5, 6.0), h = rng.Uniform(2.6, 4.0);
    // Quarter turn drawn before the jitter (once one expression, its order the compiler's).
    const double quarter = rng.Chance(0.5) ? 0.0 : 0.5 * detmath::kPi;
    const double yaw = quarter + rng.Uniform(-0.25, 0.25);
    const Footprint f = RotatedRect(x, y, sx + 0.6, sy + 0.6, yaw);
    if (!area.Contains(f) || !layout.Fits(f, gap)) return false;
    layout.Add(f);
    b.AddBox(x, y, 0.0, sx, sy, h, yaw);                     // walls
    b.AddBox(x, y, h, sx + 0.6, sy + 0.6, 0.3, yaw);         // eaves
    b.AddBox(x, y, h + 0.3, sx + 0.2, 0.5 * sy, 0.9, yaw);   // ridge
    return true;
  };
  // A house on the straight line on the start side (closer than the usual spacing to the start
  // keep-out), then the village: denser on the start side, open fields across the river.
  for (int attempt = 0; attempt < 40; ++attempt) {
    const double x = rng.Uniform(route.sx + 6.0, bank_l - 3.0);
    if (try_house(x, route.YAt(x) + rng.Uniform(-2.0, 2.0), 0.5)) break;
  }
  // The village street: houses along both sides of the way to the bridge and beyond it, their
  // walls 4-7 m from the straight line, with gardens between them.
  for (double x = area.x0 + 4.0; x < area.x1 - 4.0; x += rng.Uniform(7.0, 10.0)) {
    for (const double side : {-1.0, 1.0}) {
      const double y = route.YAt(x) + side * rng.Uniform(7.0, 9.5);
      try_house(x + rng.Uniform(-1.5, 1.5), y, 2.0);
    }
  }
  for (int attempt = 0, placed = 0; attempt < 600 && placed < 10; ++attempt) {
    const auto [x, y] = rng.PointIn(area.x0, bank_l, area.y0, area.y1);
    placed += try_house(x, y, 2.8) ? 1 : 0;
  }
  for (int attempt = 0, placed = 0; attempt < 400 && placed < 3; ++attempt) {
    const auto [x, y] = rng.PointIn(bank_r, area.x1, area.y0, area.y1);
    placed += try_house(x, y, 3.0) ? 1 : 0;
  }
  // Round village trees and garden fences, mostly on the open goal side; first a row of trees on
  // each bank, either side of the bridge, as rivers are lined.
  const TreeStyle style{0.15, 0.3, 1.2, 2.5, 1.2, 2.0, 1.2, 1.8, 0.2};
  for (const double bank : {bank_l - 3.5, bank_r + 3.5}) {
    for (double y = area.y0 + 2.5; y < area.y1 - 2.5; y += rng.Uniform(4.5, 6.5)) {
      const Tree t = DrawTree(rng, bank + rng.Uniform(-0.4, 0.4), y, style);
      if (!area.Contains(t.footprint()) || !layout.Fits(t.footprint(), 0.8)) continue;
      layout.Add(t.footprint());
      t.Commit(b, 0.0);
    }
  }
  for (int attempt = 0, placed = 0; attempt < 600 && placed < 14; ++attempt) {
    const double x = rng.Chance(0.7) ? rng.Uniform(bank_r, area.x1) : rng.Uniform(area.x0, bank_l);
    const Tree t = DrawTree(rng, x, rng.Uniform(area.y0, area.y1), style);
    if (!area.Contains(t.footprint()) || !layout.Fits(t.footprint(), 2.2)) continue;
    layout.Add(t.footprint());
    t.Commit(b, 0.0);
    ++placed;
  }
  for (int attempt = 0, placed = 0; attempt < 300 && placed < 4; ++attempt) {
    const double length = rng.Uniform(5.0, 9.0);
    const bool along_x = rng.Chance(0.5);
    const double x = rng.Uniform(area.x0, area.x1), y = rng.Uniform(area.y0, area.y1);
    const Footprint f = along_x ? Rect(x, y, 0.5 * length, 0.05) : Rect(x, y, 0.05, 0.5 * length);
    if (!area.Contains(f) || !layout.Fits(f, 2.5)) continue;
    layout.Add(f);
    b.AddBox(x, y, 0.0, 2.0 * f.hx, 2.0 * f.hy, 1.2);
    ++placed;
  }
}

// canyon: street canyons of a city centre. An irregular grid of blocks with 6-10 m streets,
// each block split into buildings of mixed heights (3-48 m: some low enough to fly over at the
// 5 m flight altitude, most far above it) with small setbacks, so every intersection has corners.
// Start and goal lie on two perpendicular streets, `length` apart on a diagonal: the straight line
// crosses blocks, so the ~1.41 x length route along the streets turns at least one corner.
void BuildCanyon(Rng& rng, const Params& p, World* w) {
  const double D = p.at("length") / std::sqrt(2.0);  // start-goal offset along x and along y
  constexpr double kMargin = 16.0;                   // city beyond the route on every side
  // Street centres, walking out from the two route streets (x = 0 and y = 0 before the shift).
  struct Street {
    double centre, width;
  };
  auto streets = [&rng](double lo, double hi) {
    std::vector<Street> out;
    out.push_back({0.0, rng.Uniform(6.0, 10.0)});
    for (double x = 0.0, half = 0.5 * out[0].width; x - half > lo;) {
      const double width = rng.Uniform(6.0, 10.0), block = rng.Uniform(14.0, 24.0);
      x -= half + block + 0.5 * width;
      half = 0.5 * width;
      out.insert(out.begin(), {x, width});
    }
    for (double x = 0.0, half = 0.5 * out.back().width; x + half < hi;) {
      const double width = rng.Uniform(6.0, 10.0), block = rng.Uniform(14.0, 24.0);
      x += half + block + 0.5 * width;
      half = 0.5 * width;
      out.push_back({x, width});
    }
    return out;
  };
  // Vertical streets (constant x) from left of the start to right of the goal street, horizontal
  // ones (constant y) from below the start street to above the goal.
  const std::vector<Street> xs = streets(-D - kMargin, kMargin);
  const std::vector<Street> ys = streets(-kMargin, D + kMargin);
  // Shift so the start-goal midpoint is the origin: start (-D/2, -D/2) on the street y = -D/2,
  // goal (D/2, D/2) on the street x = D/2.
  const double ox = 0.5 * D, oy = -0.5 * D;
  const Area area{-D - kMargin + ox, kMargin + ox, -kMargin + oy, D + kMargin + oy};
  SetBounds(w, area.x0, area.y0, 0.0, area.x1, area.y1, 10.0);
  const auto [start_dx, start_dy] = rng.PointIn(-2.0, 2.0, -1.0, 1.0);
  w->start = Eigen::Vector3d(-0.5 * D + start_dx, oy + start_dy, kCanyonAltitude);
  const auto [goal_dx, goal_dy] = rng.PointIn(-1.0, 1.0, -2.0, 2.0);
  w->goal = Eigen::Vector3d(ox + goal_dx, 0.5 * D + goal_dy, kCanyonAltitude);
  Builder b{w};
  // Does the straight start-goal line cross the rectangle? (Liang-Barsky clipping in xy.)
  auto on_line = [&](double x0, double x1, double y0, double y1) {
    const double dx = w->goal.x() - w->start.x(), dy = w->goal.y() - w->start.y();
    double t0 = 0.0, t1 = 1.0;
    const double p[4] = {-dx, dx, -dy, dy};
    const double q[4] = {w->start.x() - x0, x1 - w->start.x(), w->start.y() - y0, y1 - w->start.y()};
    for (int k = 0; k < 4; ++k) {
      if (p[k] == 0.0) {
        if (q[k] < 0.0) return false;
      } else if (p[k] < 0.0) {
        t0 = std::max(t0, q[k] / p[k]);
      } else {
        t1 = std::min(t1, q[k] / p[k]);
      }
    }
    return t0 <= t1;
  };
  // One building: clipped to the bounds (the city goes on beyond them, nothing there is flown).
  // Mixed heights: some low (3-4.5 m, below the flight altitude), the rest mid-rise or towers up
  // to 48 m. No low roof on the straight line, so there is no short cut over the roofs.
  auto building = [&](double x0, double x1, double y0, double y1) {
    x0 = std::max(x0, area.x0);
    x1 = std::min(x1, area.x1);
    y0 = std::max(y0, area.y0);
    y1 = std::min(y1, area.y1);
    if (x1 - x0 < 1.0 || y1 - y0 < 1.0) return;
    const double kind = rng.Uniform();
    const double h = kind < 0.2 && !on_line(x0, x1, y0, y1)
                         ? rng.Uniform(3.0, 4.5)
                         : (kind < 0.7 ? rng.Uniform(8.0, 20.0) : rng.Uniform(20.0, 48.0));
    b.AddBox(0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.0, x1 - x0, y1 - y0, h);
  };
  for (std::size_t i = 0; i + 1 < xs.size(); ++i) {
    for (std::size_t j = 0; j + 1 < ys.size(); ++j) {
      const double bx0 = xs[i].centre + 0.5 * xs[i].width + ox, bx1 = xs[i + 1].centre - 0.5 * xs[i + 1].width + ox;
      const double by0 = ys[j].centre + 0.5 * ys[j].width + oy, by1 = ys[j + 1].centre - 0.5 * ys[j + 1].width + oy;
      // Split the block across its longer side into 1-3 buildings, each set back 0-0.8 m from
      // the street on its own, so the street walls are not flat.
      const bool along_x = bx1 - bx0 >= by1 - by0;
      const int parts = rng.Int(1, 3);
      double cut = along_x ? bx0 : by0;
      const double end = along_x ? bx1 : by1;
      for (int k = 0; k < parts; ++k) {
        const double next = k + 1 == parts ? end : cut + (end - cut) * rng.Uniform(0.7, 1.3) / (parts - k);
        const double s0 = rng.Uniform(0.0, 0.8), s1 = rng.Uniform(0.0, 0.8);
        if (along_x) {
          building(cut + (k == 0 ? s0 : 0.0), next - (k + 1 == parts ? s1 : 0.0), by0 + s0, by1 - s1);
        } else {
          building(bx0 + s0, bx1 - s1, cut + (k == 0 ? s0 : 0.0), next - (k + 1 == parts ? s1 : 0.0));
        }
        cut = next;
      }
    }
  }
}

// forest: trees only, at a given density.
void BuildForest(Rng& rng, const Params& p, World* w) {
  const double L = p.at("length"), half = 0.5 * L, density = p.at("density");
  const Area area{-half - 5.0, half + 5.0, -12.0, 12.0};
  SetBounds(w, area.x0, area.y0, 0.0, area.x1, area.y1, 7.0);
  const Route route{-half, 0.0, half, 0.0};
  w->start = Eigen::Vector3d(route.sx, route.sy, kFlightAltitude);
  w->goal = Eigen::Vector3d(route.gx, route.gy, kFlightAltitude);
  Builder b{w};
  Layout keep_out;
  keep_out.Add(Circle(route.sx, route.sy, 2.5));
  keep_out.Add(Circle(route.gx, route.gy, 2.5));
  const double area_m2 = (area.x1 - area.x0) * (area.y1 - area.y0);
  const int target = static_cast<int>(std::round(density * area_m2 / 100.0));
  if (target == 0) return;
  // Trunks at least half the mean spacing apart; crowns may touch (navigability is validated).
  const double spacing = std::sqrt(100.0 / density);
  const double min_trunk_gap = std::max(1.2, 0.5 * spacing);
  const TreeStyle style{0.12, 0.3, 0.6, 2.5, 0.9, 2.0, 1.0, 2.0, 0.3};
  Layout trunks;
  for (int attempt = 0, placed = 0; attempt < 60 * target && placed < target; ++attempt) {
    const auto [x, y] = rng.PointIn(area.x0, area.x1, area.y0, area.y1);
    const Tree t = DrawTree(rng, x, y, style);
    const Footprint trunk = Circle(t.x, t.y, t.trunk_r);
    if (!area.Contains(trunk) || !keep_out.Fits(t.footprint(), 0.0) || !trunks.Fits(trunk, min_trunk_gap)) continue;
    trunks.Add(trunk);
    t.Commit(b, 0.0);
    ++placed;
  }
}

void BuildEmpty(Rng&, const Params& p, World* w) {
  const double half = 0.5 * p.at("length");
  SetBounds(w, -half - 5.0, -10.0, 0.0, half + 5.0, 10.0, 6.0);
  w->start = Eigen::Vector3d(-half, 0.0, kFlightAltitude);
  w->goal = Eigen::Vector3d(half, 0.0, kFlightAltitude);
}

// ---------------------------------------------------------------------------------------------

struct Entry {
  GeneratorInfo info;
  void (*build)(Rng&, const Params&, World*);
  bool line_blocked;  // the straight start-goal line must hit something
  bool mover_crosses_line = false;  // some mover's track must cross the straight start-goal line
};

GeneratorParam Length(double def, double lo, double hi) {
  return {"length", lo, hi, def, "start-goal distance, m"};
}

// The worlds with movers can leave them out: the same static world, for comparisons.
GeneratorParam Movers() { return {"movers", 0.0, 1.0, 1.0, "1: with its movers; 0: the same world without them"}; }

const std::vector<Entry>& Entries() {
  static const std::vector<Entry> entries = {
      {{"s1", "city with buildings of varying height", 44.0, {Length(44.0, 20.0, 200.0)}}, BuildS1, true},
      {{"s2", "park: dense irregular trees, bushes and a pavilion", 50.0, {Length(50.0, 20.0, 200.0)}}, BuildS2, true},
      {{"s3", "indoor hall with partitions and furniture", 17.0, {Length(17.0, 8.0, 60.0)}}, BuildS3, true},
      {{"s4", "city grid of buildings of similar height", 42.0, {Length(42.0, 30.0, 150.0)}}, BuildS4, true},
      {{"s5", "village: houses, a river channel and a bridge", 32.0, {Length(32.0, 20.0, 150.0)}}, BuildS5, true},
      {{"canyon",
        "street canyons: 6-10 m streets between blocks of mixed heights (3-48 m), flown at 5 m",
        0.0,
        {Length(72.0, 30.0, 200.0)},
        kCanyonAltitude},
       BuildCanyon,
       true},
      {{"forest",
        "trees at a given density",
        0.0,
        {Length(40.0, 10.0, 200.0), {"density", 0.0, 10.0, 3.0, "trees per 100 m^2"}}},
       BuildForest,
       false},
      {{"empty", "no obstacles, ground only", 0.0, {Length(30.0, 2.0, 1000.0)}}, BuildEmpty, false},
      {{"park-people", "s2's park with footpaths across it and people walking them (movers)", 0.0,
        {Length(50.0, 20.0, 200.0), Movers()}},
       BuildParkPeople,
       true,
       true},
      {{"street-traffic", "s4's city grid with vans driving the middle streets (movers)", 0.0,
        {Length(42.0, 30.0, 150.0), Movers()}},
       BuildStreetTraffic,
       true,
       true},
  };
  return entries;
}

// Every number in the world rounded to the file precision, so the World in memory is exactly
// the World a reader of its file gets.
void QuantizeWorld(World* w) {
  auto q3 = [](Eigen::Vector3d& v) {
    for (int i = 0; i < 3; ++i) v[i] = detmath::Quantize(v[i]);
  };
  Eigen::Vector3d lo = w->bounds.min(), hi = w->bounds.max();
  q3(lo);
  q3(hi);
  w->bounds = Eigen::AlignedBox3d(lo, hi);
  w->ground.z = detmath::Quantize(w->ground.z);
  q3(w->start);
  q3(w->goal);
  auto q_object = [&q3](Object& o) {
    if (auto* b = std::get_if<Box>(&o)) {
      q3(b->center);
      q3(b->size);
      b->yaw = detmath::Quantize(b->yaw);
    } else if (auto* c = std::get_if<Cylinder>(&o)) {
      q3(c->base);
      c->radius = detmath::Quantize(c->radius);
      c->height = detmath::Quantize(c->height);
    } else if (auto* e = std::get_if<Ellipsoid>(&o)) {
      q3(e->center);
      q3(e->radii);
    }
  };
  for (auto& o : w->objects) q_object(o);
  for (auto& m : w->movers) {
    for (auto& o : m.shape) q_object(o);
    for (auto& p : m.waypoints) {
      q3(p.position);
      p.t = detmath::Quantize(p.t);
      p.yaw = detmath::Quantize(p.yaw);
    }
    m.speed = detmath::Quantize(m.speed);
    m.start_delay = detmath::Quantize(m.start_delay);
  }
}

// Does some mover's track cross the straight start-goal line (seen from above)?
bool MoverCrossesLine(const World& w) {
  const double ax = w.start.x(), ay = w.start.y(), bx = w.goal.x(), by = w.goal.y();
  auto side = [](double x0, double y0, double x1, double y1, double px, double py) {
    return (x1 - x0) * (py - y0) - (y1 - y0) * (px - x0);
  };
  for (const Mover& m : w.movers) {
    const std::vector<Eigen::Vector3d> track = MoverTrack(m);
    for (std::size_t i = 0; i + 1 < track.size(); ++i) {
      const double cx = track[i].x(), cy = track[i].y(), dx = track[i + 1].x(), dy = track[i + 1].y();
      if (side(ax, ay, bx, by, cx, cy) * side(ax, ay, bx, by, dx, dy) <= 0.0 &&
          side(cx, cy, dx, dy, ax, ay) * side(cx, cy, dx, dy, bx, by) <= 0.0) {
        return true;
      }
    }
  }
  return false;
}

std::string AllowedNames(const GeneratorInfo& info) {
  std::string out;
  for (const auto& p : info.params) out += (out.empty() ? "" : ", ") + p.name;
  return out.empty() ? "none" : out;
}

}  // namespace

const std::vector<GeneratorInfo>& Generators() {
  static const std::vector<GeneratorInfo> infos = [] {
    std::vector<GeneratorInfo> v;
    for (const auto& e : Entries()) v.push_back(e.info);
    return v;
  }();
  return infos;
}

const GeneratorInfo* FindGenerator(std::string_view id) {
  for (const auto& info : Generators()) {
    if (info.id == id) return &info;
  }
  return nullptr;
}

std::string ScenarioOf(const std::string& world) { return FindGenerator(world) ? world : std::string("custom"); }

World Generate(const std::string& scenario, std::uint64_t seed, const std::map<std::string, std::string>& params) {
  const Entry* entry = nullptr;
  for (const auto& e : Entries()) {
    if (e.info.id == scenario) entry = &e;
  }
  if (entry == nullptr) {
    std::string ids;
    for (const auto& e : Entries()) ids += (ids.empty() ? "" : ", ") + e.info.id;
    throw WorldError("", 0, "scenario", "unknown scenario '" + scenario + "' (known: " + ids + ")");
  }
  const GeneratorInfo& info = entry->info;

  // Parameters: known names, numbers within range; defaults for the rest.
  Params values;
  for (const auto& p : info.params) values[p.name] = p.default_value;
  for (const auto& [name, text] : params) {
    const auto it = std::find_if(info.params.begin(), info.params.end(), [&name = name](const auto& p) { return p.name == name; });
    if (it == info.params.end()) {
      throw WorldError(scenario, 0, "params." + name, "unknown parameter (allowed: " + AllowedNames(info) + ")");
    }
    double v = 0.0;
    const std::string range = "[" + FormatFixed(it->min) + ", " + FormatFixed(it->max) + "]";
    if (!ParseFiniteDouble(text, &v)) {
      throw WorldError(scenario, 0, "params." + name, "not a number (got '" + text + "'; allowed range " + range + ")");
    }
    if (v < it->min || v > it->max) {
      throw WorldError(scenario, 0, "params." + name, "must be in " + range + " (got " + text + ")");
    }
    values[name] = detmath::Quantize(v);
  }

  std::string last_failure;
  for (int draw = 0; draw < kMaxDraws; ++draw) {
    Rng rng(SplitMix64(SplitMix64(seed) + static_cast<std::uint64_t>(draw)));
    World w;
    entry->build(rng, values, &w);
    QuantizeWorld(&w);
    w.metadata.name = scenario + "-seed" + std::to_string(seed);
    w.metadata.scenario = scenario;
    w.metadata.seed = seed;
    w.metadata.generator_version = kGeneratorVersion;
    for (const auto& [k, v] : values) w.metadata.params[k] = FormatFixed(v);

    if (entry->mover_crosses_line && !MoverCrossesLine(w)) {
      last_failure = "no mover crosses the straight start-goal line";
      continue;
    }
    if (entry->line_blocked) {
      const ObstacleField field(w, /*include_ground=*/false);
      if (field.SegmentClearance(w.start, w.goal) >= kDroneRadius) {
        last_failure = "the straight start-goal line is free";
        continue;
      }
    }
    const ValidationResult v = ValidateWorld(w);
    if (v.ok) {
      // Without its movers: dropped only now, so the static world is the one drawn with them.
      if (const auto it = values.find("movers"); it != values.end() && it->second == 0.0) w.movers.clear();
      return w;
    }
    last_failure = v.field + ": " + v.reason;
  }
  throw WorldError(scenario, 0, "seed",
                   "no valid world in " + std::to_string(kMaxDraws) + " draws for seed " + std::to_string(seed) +
                       " (last: " + last_failure + "); try other parameters");
}

}  // namespace enavi::worlds
