#pragma once
// A raster canvas for plots: a thin RAII owner of a cairo image surface with the few drawing
// calls reports need. Coordinates are pixels, origin top-left, y down. Colours are RGB in [0, 1].

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace enavi::report {

struct Rgb {
  double r = 0.0, g = 0.0, b = 0.0;
};

namespace colors {
inline constexpr Rgb kWhite{1.0, 1.0, 1.0};
inline constexpr Rgb kBlack{0.0, 0.0, 0.0};
inline constexpr Rgb kGrey{0.5, 0.5, 0.5};
inline constexpr Rgb kStart{0.0, 0.72, 0.0};  ///< start markers: green
inline constexpr Rgb kGoal{0.86, 0.0, 0.0};   ///< goal markers: red
}  // namespace colors

/// Colour `i` of a fixed qualitative palette (series in charts), cycling.
Rgb PaletteColor(int i);

enum class TextAlign { kLeft, kCenter, kRight };

/// An image surface (ARGB32) owned for its lifetime. Move-only.
class Canvas {
 public:
  Canvas(int width, int height, Rgb background = colors::kWhite);
  ~Canvas();
  Canvas(Canvas&& other) noexcept;
  Canvas& operator=(Canvas&& other) noexcept;
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }

  /// Restricts drawing to a rectangle until the matching PopClip.
  void PushClip(double x, double y, double w, double h);
  void PopClip();

  void Line(double x0, double y0, double x1, double y1, Rgb color, double line_width = 1.0);
  /// Dashed line (`dash` px on, `dash` px off).
  void DashedLine(double x0, double y0, double x1, double y1, Rgb color, double line_width, double dash);
  void Polyline(const std::vector<Eigen::Vector2d>& points, Rgb color, double line_width = 1.0, bool closed = false);
  void FillPolygon(const std::vector<Eigen::Vector2d>& points, Rgb color, double alpha = 1.0);
  void FillRect(double x, double y, double w, double h, Rgb color, double alpha = 1.0);
  void StrokeRect(double x, double y, double w, double h, Rgb color, double line_width = 1.0);
  void FillCircle(double cx, double cy, double radius, Rgb color);
  void StrokeCircle(double cx, double cy, double radius, Rgb color, double line_width = 1.0);
  /// Axis-aligned ellipse.
  void FillEllipse(double cx, double cy, double rx, double ry, Rgb color, double alpha = 1.0);
  void StrokeEllipse(double cx, double cy, double rx, double ry, Rgb color, double line_width = 1.0);

  /// Text in "DejaVu Sans" with its baseline at y; `rotate_90` draws it reading bottom-to-top
  /// (y axis labels), anchored at (x, y) with the same alignment along the text direction.
  void Text(double x, double y, const std::string& text, double size, Rgb color,
            TextAlign align = TextAlign::kLeft, bool bold = false, bool rotate_90 = false);
  double TextWidth(const std::string& text, double size, bool bold = false) const;

  /// Colour of one pixel (for tests and probes); alpha ignored.
  Rgb Pixel(int x, int y) const;

  /// Writes a PNG; throws std::runtime_error naming `path` on failure.
  void SavePng(const std::string& path) const;
  /// The PNG file's bytes (for serving over HTTP).
  std::vector<std::uint8_t> PngBytes() const;

 private:
  void Release();
  int width_ = 0;
  int height_ = 0;
  void* surface_ = nullptr;  // cairo_surface_t*
  void* cr_ = nullptr;       // cairo_t*
};

/// A decoded PNG (ARGB32 as cairo stores it), for tests and image checks.
struct PngImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint32_t> argb;  ///< row-major, premultiplied ARGB
  Rgb Pixel(int x, int y) const;
};

/// Reads a PNG; throws std::runtime_error naming `path` on failure.
PngImage ReadPng(const std::string& path);

}  // namespace enavi::report
