#include "server/report/top_down.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>
#include <stdexcept>
#include <variant>

#include "server/report/colormap.h"
#include "server/report/ticks.h"
#include "worlds/movers.h"
#include "worlds/primitives.h"

namespace enavi::report {
namespace {

constexpr Rgb kGroundTint{0.93, 0.95, 0.89};
constexpr Rgb kFrame{0.2, 0.2, 0.2};
constexpr Rgb kMover{0.55, 0.22, 0.78};  // movers' tracks and shapes: purple, apart from paths and obstacles
constexpr double kColorBarWidth = 18.0;
constexpr double kColorBarHeight = 190.0;

Rgb Darker(Rgb c, double by) { return {std::max(0.0, c.r - by), std::max(0.0, c.g - by), std::max(0.0, c.b - by)}; }

std::string WorldTitle(const worlds::World& w) {
  std::string t = w.metadata.name.empty() ? std::string("world") : w.metadata.name;
  if (!w.metadata.scenario.empty() && w.metadata.scenario != "custom") {
    t += " (" + w.metadata.scenario + ", seed " + std::to_string(w.metadata.seed) + ")";
  }
  return t;
}

// Options with the automatic height (height <= 0) resolved from the world's aspect ratio.
TopDownOptions Resolved(const worlds::World& world, TopDownOptions o) {
  if (o.height > 0) return o;
  const Eigen::Vector3d size = world.bounds.sizes();
  const double avail_w = o.width - 2.0 * o.margin - o.legend_width;
  const double map_h = size.x() > 0.0 ? avail_w * size.y() / size.x() : avail_w;
  // Room for the map and the scale bar, and for two colour bars in the legend.
  o.height = static_cast<int>(std::clamp(map_h + 2.0 * o.margin + 10.0, 540.0, 4.0 * o.width));
  return o;
}

}  // namespace

TopDownView::TopDownView(const worlds::World& world, const TopDownOptions& options)
    : start_(world.start),
      goal_(world.goal),
      options_(Resolved(world, options)),
      canvas_(options_.width, options_.height) {
  if (options_.title.empty()) options_.title = WorldTitle(world);
  // Fit the bounds' xy into the map area, keeping the aspect ratio; map at the top left.
  const double avail_w = options_.width - 2.0 * options_.margin - options_.legend_width;
  const double avail_h = options_.height - 2.0 * options_.margin;
  const Eigen::Vector3d size = world.bounds.sizes();
  if (!(avail_w > 10.0 && avail_h > 10.0) || !(size.x() > 0.0 && size.y() > 0.0)) {
    throw std::invalid_argument("top-down view: image too small for its margins or world bounds empty");
  }
  scale_ = std::min(avail_w / size.x(), avail_h / size.y());
  map_w_ = scale_ * size.x();
  map_h_ = scale_ * size.y();
  map_x0_ = options_.margin;
  map_y0_ = options_.margin;
  bounds_min_ = world.bounds.min().head<2>();
  bounds_max_ = world.bounds.max().head<2>();
  legend_y_ = options_.margin + 10.0;

  canvas_.Text(options_.margin, 0.6 * options_.margin, options_.title, 16.0, colors::kBlack, TextAlign::kLeft, true);
  if (world.ground.enabled) canvas_.FillRect(map_x0_, map_y0_, map_w_, map_h_, kGroundTint);
  DrawObstacles(world);
  DrawMoverTracks(world);
  canvas_.StrokeRect(map_x0_, map_y0_, map_w_, map_h_, kFrame, 1.0);
  DrawScaleBar();
  DrawStartGoal();
}

Eigen::Vector2d TopDownView::ToPixel(const Eigen::Vector2d& p_W) const {
  return {map_x0_ + (p_W.x() - bounds_min_.x()) * scale_, map_y0_ + (bounds_max_.y() - p_W.y()) * scale_};
}

void TopDownView::DrawObstacles(const worlds::World& world) {
  struct Item {
    double top, bottom;
    int index;
    bool overhead;
  };
  std::vector<Item> items;
  const double flight_z = std::max(world.start.z(), world.goal.z());
  const double map_area = (bounds_max_.x() - bounds_min_.x()) * (bounds_max_.y() - bounds_min_.y());
  double lo = world.ground.enabled ? world.ground.z : std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < static_cast<int>(world.objects.size()); ++i) {
    const Eigen::AlignedBox3d b = worlds::ObjectBounds(world.objects[i]);
    const double cover_x = std::max(0.0, std::min(b.max().x(), bounds_max_.x()) - std::max(b.min().x(), bounds_min_.x()));
    const double cover_y = std::max(0.0, std::min(b.max().y(), bounds_max_.y()) - std::max(b.min().y(), bounds_min_.y()));
    const bool overhead = b.min().z() > flight_z && cover_x * cover_y > 0.25 * map_area;
    items.push_back({b.max().z(), b.min().z(), i, overhead});
    if (!overhead) {
      // A mesh is shaded per triangle, so its lowest triangle top counts for the range.
      double low_top = b.max().z();
      if (const auto* mesh = std::get_if<worlds::MeshObject>(&world.objects[i])) {
        const Eigen::Affine3d X = worlds::MeshObjectPose(*mesh);
        for (const auto& t : mesh->mesh.triangles) {
          double top = -std::numeric_limits<double>::infinity();
          for (int k = 0; k < 3; ++k) top = std::max(top, (X * mesh->mesh.vertices[t[k]].cast<double>()).z());
          low_top = std::min(low_top, top);
        }
      }
      lo = std::min(lo, low_top);
      hi = std::max(hi, b.max().z());
    }
  }
  if (!std::isfinite(lo)) lo = 0.0;
  if (!(hi > lo)) hi = lo + 1.0;
  height_lo_ = lo;
  height_hi_ = hi;
  // Low first, so tall obstacles are drawn last and stay visible.
  std::stable_sort(items.begin(), items.end(), [](const Item& a, const Item& b) { return a.top < b.top; });

  canvas_.PushClip(map_x0_, map_y0_, map_w_, map_h_);
  for (const Item& item : items) {
    const worlds::Object& object = world.objects[item.index];
    const Rgb fill = GreyRamp(Normalize(item.top, lo, hi));
    const Rgb edge = Darker(fill, 0.25);
    std::vector<Eigen::Vector2d> outline;
    if (const auto* box = std::get_if<worlds::Box>(&object)) {
      const double c = std::cos(box->yaw), s = std::sin(box->yaw);
      for (const auto& [ux, uy] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
        const double lx = 0.5 * ux * box->size.x(), ly = 0.5 * uy * box->size.y();
        outline.push_back(ToPixel({box->center.x() + c * lx - s * ly, box->center.y() + s * lx + c * ly}));
      }
    } else if (const auto* mesh = std::get_if<worlds::MeshObject>(&object)) {
      // Every triangle projected and shaded by its own top, low ones first; no outline (it
      // would hide the shading). An overhead mesh is not drawn.
      if (item.overhead) continue;
      const Eigen::Affine3d X = worlds::MeshObjectPose(*mesh);
      std::vector<std::pair<double, std::vector<Eigen::Vector2d>>> tris;
      tris.reserve(mesh->mesh.triangles.size());
      for (const auto& t : mesh->mesh.triangles) {
        std::vector<Eigen::Vector2d> tri;
        double top = -std::numeric_limits<double>::infinity();
        for (int k = 0; k < 3; ++k) {
          const Eigen::Vector3d p = X * mesh->mesh.vertices[t[k]].cast<double>();
          tri.push_back(ToPixel(p.head<2>()));
          top = std::max(top, p.z());
        }
        tris.emplace_back(top, std::move(tri));
      }
      std::stable_sort(tris.begin(), tris.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      for (const auto& [top, tri] : tris) {
        // A hairline in the fill colour hides the antialiasing seams between triangles.
        const Rgb color = GreyRamp(Normalize(top, lo, hi));
        canvas_.FillPolygon(tri, color);
        canvas_.Polyline(tri, color, 0.6, true);
      }
      continue;
    } else {
      // Cylinders and ellipsoids: an ellipse footprint.
      Eigen::Vector2d centre, radii;
      if (const auto* cyl = std::get_if<worlds::Cylinder>(&object)) {
        centre = cyl->base.head<2>();
        radii = Eigen::Vector2d(cyl->radius, cyl->radius);
      } else {
        const auto& e = std::get<worlds::Ellipsoid>(object);
        centre = e.center.head<2>();
        radii = e.radii.head<2>();
      }
      const Eigen::Vector2d px = ToPixel(centre);
      // At least a pixel across, so thin poles still show.
      const double rx = std::max(1.0, radii.x() * scale_), ry = std::max(1.0, radii.y() * scale_);
      if (item.overhead) {
        for (int k = 0; k < 48; k += 2) {
          const double a0 = k * std::numbers::pi / 24.0, a1 = (k + 1) * std::numbers::pi / 24.0;
          canvas_.Line(px.x() + rx * std::cos(a0), px.y() + ry * std::sin(a0), px.x() + rx * std::cos(a1),
                       px.y() + ry * std::sin(a1), kFrame, 1.0);
        }
      } else {
        canvas_.FillEllipse(px.x(), px.y(), rx, ry, fill);
        canvas_.StrokeEllipse(px.x(), px.y(), rx, ry, edge, 0.8);
      }
      continue;
    }
    if (item.overhead) {
      for (std::size_t k = 0; k < outline.size(); ++k) {
        const auto& a = outline[k];
        const auto& b = outline[(k + 1) % outline.size()];
        canvas_.DashedLine(a.x(), a.y(), b.x(), b.y(), kFrame, 1.5, 6.0);
      }
    } else {
      canvas_.FillPolygon(outline, fill);
      canvas_.Polyline(outline, edge, 0.8, true);
    }
  }
  canvas_.PopClip();
  DrawColorBar("top height [m]", lo, hi, /*grey=*/true);
}

void TopDownView::DrawColorBar(const std::string& label, double lo, double hi, bool grey) {
  const double x = options_.width - options_.legend_width + 10.0;
  const double y = legend_y_ + 16.0;
  canvas_.Text(x, legend_y_ + 4.0, label, 12.0, colors::kBlack, TextAlign::kLeft, true);
  // Top of the bar is the high end.
  constexpr int kSteps = 64;
  for (int i = 0; i < kSteps; ++i) {
    const double t = 1.0 - (i + 0.5) / kSteps;
    canvas_.FillRect(x, y + i * kColorBarHeight / kSteps, kColorBarWidth, kColorBarHeight / kSteps + 0.5,
                     grey ? GreyRamp(t) : Viridis(t));
  }
  canvas_.StrokeRect(x, y, kColorBarWidth, kColorBarHeight, kFrame, 0.8);
  const double step = NiceStep(lo, hi, 5);
  for (double v : NiceTicks(lo, hi, 5)) {
    const double ty = y + (1.0 - Normalize(v, lo, hi)) * kColorBarHeight;
    canvas_.Line(x + kColorBarWidth, ty, x + kColorBarWidth + 4.0, ty, kFrame, 1.0);
    canvas_.Text(x + kColorBarWidth + 7.0, ty + 4.0, FormatTick(v, step), 11.0, colors::kBlack);
  }
  legend_y_ = y + kColorBarHeight + 24.0;
}

void TopDownView::DrawScaleBar() {
  // About a fifth of the map width, at a 1-2-5 length.
  const double metres_wide = map_w_ / scale_;
  double length = NiceStep(0.0, metres_wide, 5);
  if (length * scale_ > 0.3 * map_w_) length = length / 2.0;
  const double x0 = map_x0_, y = map_y0_ + map_h_ + 20.0, x1 = x0 + length * scale_;
  canvas_.Line(x0, y, x1, y, colors::kBlack, 3.0);
  canvas_.Line(x0, y - 5.0, x0, y + 5.0, colors::kBlack, 1.5);
  canvas_.Line(x1, y - 5.0, x1, y + 5.0, colors::kBlack, 1.5);
  canvas_.Text(x1 + 8.0, y + 4.0, FormatTick(length, length) + " m", 12.0, colors::kBlack);
  // Axis hint at the right end, below the map: +x to the right, +y up.
  const double ax = map_x0_ + map_w_ - 50.0, ay = map_y0_ + map_h_ + 42.0, len = 24.0;
  canvas_.Line(ax, ay, ax + len, ay, colors::kBlack, 1.5);
  canvas_.Line(ax + len, ay, ax + len - 5.0, ay - 3.5, colors::kBlack, 1.5);
  canvas_.Line(ax + len, ay, ax + len - 5.0, ay + 3.5, colors::kBlack, 1.5);
  canvas_.Line(ax, ay, ax, ay - len, colors::kBlack, 1.5);
  canvas_.Line(ax, ay - len, ax - 3.5, ay - len + 5.0, colors::kBlack, 1.5);
  canvas_.Line(ax, ay - len, ax + 3.5, ay - len + 5.0, colors::kBlack, 1.5);
  canvas_.Text(ax + len + 4.0, ay + 4.0, "x", 12.0, colors::kBlack);
  canvas_.Text(ax + 7.0, ay - len + 6.0, "y", 12.0, colors::kBlack);
}

void TopDownView::DrawMarkerPx(const Eigen::Vector2d& px, Rgb color, const std::string& label, double radius) {
  canvas_.FillCircle(px.x(), px.y(), radius + 2.0, colors::kWhite);
  canvas_.FillCircle(px.x(), px.y(), radius, color);
  if (label.empty()) return;
  const double w = canvas_.TextWidth(label, 12.0, true);
  const double tx = px.x() + radius + 5.0, ty = px.y() + 4.0;
  canvas_.FillRect(tx - 2.0, ty - 12.0, w + 4.0, 16.0, colors::kWhite, 0.8);
  canvas_.Text(tx, ty, label, 12.0, Darker(color, 0.1), TextAlign::kLeft, true);
}

void TopDownView::DrawMoverTracks(const worlds::World& world) {
  if (world.movers.empty()) return;
  movers_ = world.movers;
  canvas_.PushClip(map_x0_, map_y0_, map_w_, map_h_);
  for (const worlds::Mover& m : world.movers) {
    const std::vector<Eigen::Vector3d> track = worlds::MoverTrack(m);
    for (std::size_t i = 0; i + 1 < track.size(); ++i) {
      const Eigen::Vector2d a = ToPixel(track[i].head<2>()), b = ToPixel(track[i + 1].head<2>());
      canvas_.DashedLine(a.x(), a.y(), b.x(), b.y(), kMover, 2.0, 7.0);
    }
    const Eigen::Vector2d first = ToPixel(track.front().head<2>());
    canvas_.StrokeCircle(first.x(), first.y(), 4.0, kMover, 1.5);
    canvas_.Text(first.x() + 6.0, first.y() - 5.0, m.name, 11.0, Darker(kMover, 0.15));
  }
  canvas_.PopClip();
  const double x = options_.width - options_.legend_width + 10.0;
  canvas_.DashedLine(x, legend_y_, x + 24.0, legend_y_, kMover, 2.0, 7.0);
  canvas_.Text(x + 30.0, legend_y_ + 4.0, "mover tracks", 12.0, colors::kBlack);
  legend_y_ += 24.0;
}

void TopDownView::DrawMoversAt(double t, const std::string& label) {
  canvas_.PushClip(map_x0_, map_y0_, map_w_, map_h_);
  for (const worlds::Mover& m : movers_) {
    // The shape's footprint: its bounds in its own frame, turned and placed where it is at t.
    const worlds::MoverPose pose = worlds::MoverTrajectory(m).Pose(t);
    const Eigen::AlignedBox3f box = worlds::MoverMesh(m).Bounds();
    std::vector<Eigen::Vector2d> outline;
    for (const auto& [cx, cy] : {std::pair{0, 0}, {1, 0}, {1, 1}, {0, 1}}) {
      const Eigen::Vector3d corner(cx ? box.max().x() : box.min().x(), cy ? box.max().y() : box.min().y(), 0.0);
      outline.push_back(ToPixel(pose.ToWorld(corner).head<2>()));
    }
    canvas_.FillPolygon(outline, kMover, 0.75);
    canvas_.Polyline(outline, Darker(kMover, 0.2), 1.2, true);
  }
  canvas_.PopClip();
  if (movers_.empty() || label.empty()) return;
  const double x = options_.width - options_.legend_width + 10.0;
  canvas_.FillRect(x + 6.0, legend_y_ - 6.0, 12.0, 12.0, kMover, 0.75);
  canvas_.Text(x + 30.0, legend_y_ + 4.0, label, 12.0, colors::kBlack);
  legend_y_ += 24.0;
}

void TopDownView::DrawStartGoal() {
  DrawMarkerPx(ToPixel(start_.head<2>()), colors::kStart, "start", 8.0);
  DrawMarkerPx(ToPixel(goal_.head<2>()), colors::kGoal, "goal", 8.0);
}

void TopDownView::DrawPath(const std::vector<Eigen::Vector2d>& xy_W, const std::vector<double>& values,
                           double value_min, double value_max, const std::string& label, double line_width) {
  if (values.size() != xy_W.size()) {
    throw std::invalid_argument("DrawPath: " + std::to_string(values.size()) + " values for " +
                                std::to_string(xy_W.size()) + " points");
  }
  canvas_.PushClip(map_x0_, map_y0_, map_w_, map_h_);
  for (std::size_t i = 0; i + 1 < xy_W.size(); ++i) {
    const Eigen::Vector2d a = ToPixel(xy_W[i]), b = ToPixel(xy_W[i + 1]);
    const double v = 0.5 * (values[i] + values[i + 1]);
    canvas_.Line(a.x(), a.y(), b.x(), b.y(), Viridis(Normalize(v, value_min, value_max)), line_width);
  }
  canvas_.PopClip();
  DrawColorBar(label, value_min, value_max, /*grey=*/false);
  DrawStartGoal();
}

void TopDownView::DrawPath(const std::vector<Eigen::Vector2d>& xy_W, Rgb color, double line_width) {
  std::vector<Eigen::Vector2d> px;
  px.reserve(xy_W.size());
  for (const auto& p : xy_W) px.push_back(ToPixel(p));
  canvas_.PushClip(map_x0_, map_y0_, map_w_, map_h_);
  canvas_.Polyline(px, color, line_width);
  canvas_.PopClip();
  DrawStartGoal();
}

void TopDownView::DrawMarker(const Eigen::Vector2d& p_W, Rgb color, const std::string& label) {
  DrawMarkerPx(ToPixel(p_W), color, label, 6.0);
  DrawStartGoal();
}

}  // namespace enavi::report
