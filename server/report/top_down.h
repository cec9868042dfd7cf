#pragma once
// Bird's-eye view of a World: obstacles shaded by their top height, start and goal, scale bar,
// plus overlays (flight paths coloured by a value, markers) for episode reports.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "server/report/canvas.h"
#include "worlds/world.h"

namespace enavi::report {

struct TopDownOptions {
  int width = 1000;             ///< px
  int height = 0;               ///< px; 0 = from the bounds' aspect ratio (at least 540)
  double margin = 48.0;         ///< px around the map (title above, scale bar below)
  double legend_width = 170.0;  ///< px reserved on the right for the colour bars
  std::string title;            ///< default: "<name> (<scenario>, seed N)"
};

/// Renders the world on construction (the World need not outlive the view); overlays are drawn on top, start and goal stay on top of
/// everything.
///
/// Drawing rules: movers' tracks are dashed purple lines from a circle at their first waypoint;
/// obstacles are filled with a grey ramp by top height (light = low, dark = tall;
/// legend on the right) and drawn in order of increasing top height, so tall objects stay
/// visible. "Overhead" objects, whose bottom is above the start/goal altitude and which cover
/// more than a quarter of the map (a hall's ceiling), are drawn as a dashed outline only, so
/// the furniture under them shows. Ground below obstacles is a light tint when the world has a
/// ground plane, white otherwise (terrain made of boxes, e.g. a river channel, is shaded as
/// obstacles: lower is lighter).
class TopDownView {
 public:
  explicit TopDownView(const worlds::World& world, const TopDownOptions& options = {});

  /// Pixel position of a world point (x, y in metres).
  Eigen::Vector2d ToPixel(const Eigen::Vector2d& p_W) const;
  double pixels_per_metre() const { return scale_; }
  /// Top-height range of the grey ramp (m): low maps to light grey, high to dark grey.
  double height_min() const { return height_lo_; }
  double height_max() const { return height_hi_; }

  /// A path whose segments are coloured by `values` (one per point) on the viridis map over
  /// [value_min, value_max], with a colour bar titled `label` in the legend panel.
  /// @pre values.size() == xy_W.size()
  void DrawPath(const std::vector<Eigen::Vector2d>& xy_W, const std::vector<double>& values, double value_min,
                double value_max, const std::string& label, double line_width = 3.0);
  /// A path in one colour.
  void DrawPath(const std::vector<Eigen::Vector2d>& xy_W, Rgb color, double line_width = 2.0);
  /// A labelled point marker (e.g. a collision).
  void DrawMarker(const Eigen::Vector2d& p_W, Rgb color, const std::string& label);
  /// The world's movers where they are at sim time t (their shapes' footprints, purple; their
  /// tracks are part of the map), with `label` in the legend.
  void DrawMoversAt(double t, const std::string& label);

  Canvas& canvas() { return canvas_; }
  const Canvas& canvas() const { return canvas_; }
  void SavePng(const std::string& path) const { canvas_.SavePng(path); }

 private:
  void DrawObstacles(const worlds::World& world);
  void DrawMoverTracks(const worlds::World& world);
  void DrawStartGoal();
  void DrawScaleBar();
  void DrawColorBar(const std::string& label, double lo, double hi, bool grey);
  void DrawMarkerPx(const Eigen::Vector2d& px, Rgb color, const std::string& label, double radius);

  Eigen::Vector3d start_, goal_;
  std::vector<worlds::Mover> movers_;
  TopDownOptions options_;
  Canvas canvas_;
  double scale_ = 1.0;      // px per metre
  double map_x0_ = 0.0;     // px of bounds.min().x()
  double map_y0_ = 0.0;     // px of bounds.max().y()
  double map_w_ = 0.0, map_h_ = 0.0;
  double legend_y_ = 0.0;   // next free y in the legend panel
  Eigen::Vector2d bounds_min_ = Eigen::Vector2d::Zero(), bounds_max_ = Eigen::Vector2d::Zero();
  double height_lo_ = 0.0, height_hi_ = 1.0;  // grey ramp range (m)
};

}  // namespace enavi::report
