#include "server/report/canvas.h"

#include <cairo.h>

#include <array>
#include <cmath>
#include <cstring>
#include <numbers>
#include <stdexcept>
#include <utility>

namespace enavi::report {
namespace {

cairo_t* Cr(void* p) { return static_cast<cairo_t*>(p); }
cairo_surface_t* Surface(void* p) { return static_cast<cairo_surface_t*>(p); }

void SetColor(cairo_t* cr, Rgb c, double alpha = 1.0) { cairo_set_source_rgba(cr, c.r, c.g, c.b, alpha); }

void SetFont(cairo_t* cr, double size, bool bold) {
  cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
}

Rgb Unpack(std::uint32_t argb) {
  const double a = static_cast<double>((argb >> 24) & 0xff);
  if (a == 0.0) return {0.0, 0.0, 0.0};
  // Un-premultiply.
  return {static_cast<double>((argb >> 16) & 0xff) / a, static_cast<double>((argb >> 8) & 0xff) / a,
          static_cast<double>(argb & 0xff) / a};
}

}  // namespace

Rgb PaletteColor(int i) {
  // Qualitative colours, readable on white and distinct from the start/goal green and red.
  static constexpr std::array<Rgb, 8> kPalette = {{{0.12, 0.47, 0.71},
                                                   {1.00, 0.50, 0.05},
                                                   {0.17, 0.63, 0.17},
                                                   {0.84, 0.15, 0.16},
                                                   {0.58, 0.40, 0.74},
                                                   {0.55, 0.34, 0.29},
                                                   {0.89, 0.47, 0.76},
                                                   {0.09, 0.75, 0.81}}};
  const int n = static_cast<int>(kPalette.size());
  return kPalette[((i % n) + n) % n];
}

Canvas::Canvas(int width, int height, Rgb background) : width_(width), height_(height) {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384) {
    throw std::invalid_argument("canvas size must be within 1..16384 px (got " + std::to_string(width) + "x" +
                                std::to_string(height) + ")");
  }
  cairo_surface_t* s = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, width, height);
  if (cairo_surface_status(s) != CAIRO_STATUS_SUCCESS) {
    const std::string why = cairo_status_to_string(cairo_surface_status(s));
    cairo_surface_destroy(s);
    throw std::runtime_error("cannot create a " + std::to_string(width) + "x" + std::to_string(height) +
                             " image: " + why);
  }
  surface_ = s;
  cr_ = cairo_create(s);
  SetColor(Cr(cr_), background);
  cairo_paint(Cr(cr_));
  cairo_set_line_join(Cr(cr_), CAIRO_LINE_JOIN_ROUND);
  cairo_set_line_cap(Cr(cr_), CAIRO_LINE_CAP_ROUND);
}

Canvas::~Canvas() { Release(); }

Canvas::Canvas(Canvas&& other) noexcept
    : width_(other.width_), height_(other.height_), surface_(other.surface_), cr_(other.cr_) {
  other.surface_ = nullptr;
  other.cr_ = nullptr;
}

Canvas& Canvas::operator=(Canvas&& other) noexcept {
  if (this != &other) {
    Release();
    width_ = other.width_;
    height_ = other.height_;
    surface_ = std::exchange(other.surface_, nullptr);
    cr_ = std::exchange(other.cr_, nullptr);
  }
  return *this;
}

void Canvas::Release() {
  if (cr_ != nullptr) cairo_destroy(Cr(cr_));
  if (surface_ != nullptr) cairo_surface_destroy(Surface(surface_));
  cr_ = nullptr;
  surface_ = nullptr;
}

void Canvas::PushClip(double x, double y, double w, double h) {
  cairo_t* cr = Cr(cr_);
  cairo_save(cr);
  cairo_rectangle(cr, x, y, w, h);
  cairo_clip(cr);
}

void Canvas::PopClip() { cairo_restore(Cr(cr_)); }

void Canvas::Line(double x0, double y0, double x1, double y1, Rgb color, double line_width) {
  cairo_t* cr = Cr(cr_);
  SetColor(cr, color);
  cairo_set_line_width(cr, line_width);
  cairo_move_to(cr, x0, y0);
  cairo_line_to(cr, x1, y1);
  cairo_stroke(cr);
}

void Canvas::DashedLine(double x0, double y0, double x1, double y1, Rgb color, double line_width, double dash) {
  cairo_t* cr = Cr(cr_);
  cairo_set_dash(cr, &dash, 1, 0.0);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
  Line(x0, y0, x1, y1, color, line_width);
  cairo_set_dash(cr, nullptr, 0, 0.0);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
}

void Canvas::Polyline(const std::vector<Eigen::Vector2d>& points, Rgb color, double line_width, bool closed) {
  if (points.size() < 2) return;
  cairo_t* cr = Cr(cr_);
  SetColor(cr, color);
  cairo_set_line_width(cr, line_width);
  cairo_move_to(cr, points[0].x(), points[0].y());
  for (std::size_t i = 1; i < points.size(); ++i) cairo_line_to(cr, points[i].x(), points[i].y());
  if (closed) cairo_close_path(cr);
  cairo_stroke(cr);
}

void Canvas::FillPolygon(const std::vector<Eigen::Vector2d>& points, Rgb color, double alpha) {
  if (points.size() < 3) return;
  cairo_t* cr = Cr(cr_);
  SetColor(cr, color, alpha);
  cairo_move_to(cr, points[0].x(), points[0].y());
  for (std::size_t i = 1; i < points.size(); ++i) cairo_line_to(cr, points[i].x(), points[i].y());
  cairo_close_path(cr);
  cairo_fill(cr);
}

void Canvas::FillRect(double x, double y, double w, double h, Rgb color, double alpha) {
  cairo_t* cr = Cr(cr_);
  SetColor(cr, color, alpha);
  cairo_rectangle(cr, x, y, w, h);
  cairo_fill(cr);
}

void Canvas::StrokeRect(double x, double y, double w, double h, Rgb color, double line_width) {
  cairo_t* cr = Cr(cr_);
  SetColor(cr, color);
  cairo_set_line_width(cr, line_width);
  cairo_rectangle(cr, x, y, w, h);
  cairo_stroke(cr);
}

void Canvas::FillCircle(double cx, double cy, double radius, Rgb color) { FillEllipse(cx, cy, radius, radius, color); }

void Canvas::StrokeCircle(double cx, double cy, double radius, Rgb color, double line_width) {
  StrokeEllipse(cx, cy, radius, radius, color, line_width);
}

void Canvas::FillEllipse(double cx, double cy, double rx, double ry, Rgb color, double alpha) {
  if (rx <= 0.0 || ry <= 0.0) return;
  cairo_t* cr = Cr(cr_);
  cairo_save(cr);
  cairo_translate(cr, cx, cy);
  cairo_scale(cr, rx, ry);
  cairo_arc(cr, 0.0, 0.0, 1.0, 0.0, 2.0 * std::numbers::pi);
  cairo_restore(cr);
  SetColor(cr, color, alpha);
  cairo_fill(cr);
}

void Canvas::StrokeEllipse(double cx, double cy, double rx, double ry, Rgb color, double line_width) {
  if (rx <= 0.0 || ry <= 0.0) return;
  cairo_t* cr = Cr(cr_);
  cairo_save(cr);
  cairo_translate(cr, cx, cy);
  cairo_scale(cr, rx, ry);
  cairo_arc(cr, 0.0, 0.0, 1.0, 0.0, 2.0 * std::numbers::pi);
  cairo_restore(cr);  // stroke in device space so the line width is not scaled
  SetColor(cr, color);
  cairo_set_line_width(cr, line_width);
  cairo_stroke(cr);
}

void Canvas::Text(double x, double y, const std::string& text, double size, Rgb color, TextAlign align, bool bold,
                  bool rotate_90) {
  cairo_t* cr = Cr(cr_);
  SetFont(cr, size, bold);
  cairo_text_extents_t ext;
  cairo_text_extents(cr, text.c_str(), &ext);
  const double shift = align == TextAlign::kLeft ? 0.0 : (align == TextAlign::kCenter ? 0.5 : 1.0) * ext.x_advance;
  cairo_save(cr);
  cairo_translate(cr, x, y);
  if (rotate_90) cairo_rotate(cr, -0.5 * std::numbers::pi);
  cairo_move_to(cr, -shift, 0.0);
  SetColor(cr, color);
  cairo_show_text(cr, text.c_str());
  cairo_restore(cr);
}

double Canvas::TextWidth(const std::string& text, double size, bool bold) const {
  cairo_t* cr = Cr(cr_);
  SetFont(cr, size, bold);
  cairo_text_extents_t ext;
  cairo_text_extents(cr, text.c_str(), &ext);
  return ext.x_advance;
}

Rgb Canvas::Pixel(int x, int y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) {
    throw std::out_of_range("pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") outside the canvas");
  }
  cairo_surface_t* s = Surface(surface_);
  cairo_surface_flush(s);
  const unsigned char* data = cairo_image_surface_get_data(s);
  const int stride = cairo_image_surface_get_stride(s);
  std::uint32_t v;
  std::memcpy(&v, data + static_cast<std::size_t>(y) * stride + 4 * x, 4);
  return Unpack(v);
}

void Canvas::SavePng(const std::string& path) const {
  cairo_surface_t* s = Surface(surface_);
  cairo_surface_flush(s);
  const cairo_status_t status = cairo_surface_write_to_png(s, path.c_str());
  if (status != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error("cannot write PNG '" + path + "': " + cairo_status_to_string(status));
  }
}

std::vector<std::uint8_t> Canvas::PngBytes() const {
  cairo_surface_t* s = Surface(surface_);
  cairo_surface_flush(s);
  std::vector<std::uint8_t> out;
  const cairo_status_t status = cairo_surface_write_to_png_stream(
      s,
      [](void* closure, const unsigned char* data, unsigned int length) {
        auto* bytes = static_cast<std::vector<std::uint8_t>*>(closure);
        bytes->insert(bytes->end(), data, data + length);
        return CAIRO_STATUS_SUCCESS;
      },
      &out);
  if (status != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error(std::string("cannot encode PNG: ") + cairo_status_to_string(status));
  }
  return out;
}

Rgb PngImage::Pixel(int x, int y) const {
  if (x < 0 || y < 0 || x >= width || y >= height) {
    throw std::out_of_range("pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") outside the image");
  }
  return Unpack(argb[static_cast<std::size_t>(y) * width + x]);
}

PngImage ReadPng(const std::string& path) {
  cairo_surface_t* s = cairo_image_surface_create_from_png(path.c_str());
  const cairo_status_t status = cairo_surface_status(s);
  if (status != CAIRO_STATUS_SUCCESS) {
    cairo_surface_destroy(s);
    throw std::runtime_error("cannot read PNG '" + path + "': " + cairo_status_to_string(status));
  }
  // Normalise to ARGB32 whatever the PNG's own format.
  PngImage img;
  img.width = cairo_image_surface_get_width(s);
  img.height = cairo_image_surface_get_height(s);
  cairo_surface_t* argb = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, img.width, img.height);
  cairo_t* cr = cairo_create(argb);
  cairo_set_source_surface(cr, s, 0, 0);
  cairo_paint(cr);
  cairo_destroy(cr);
  cairo_surface_flush(argb);
  const unsigned char* data = cairo_image_surface_get_data(argb);
  const int stride = cairo_image_surface_get_stride(argb);
  img.argb.resize(static_cast<std::size_t>(img.width) * img.height);
  for (int y = 0; y < img.height; ++y) {
    std::memcpy(&img.argb[static_cast<std::size_t>(y) * img.width], data + static_cast<std::size_t>(y) * stride,
                4 * static_cast<std::size_t>(img.width));
  }
  cairo_surface_destroy(argb);
  cairo_surface_destroy(s);
  return img;
}

}  // namespace enavi::report
