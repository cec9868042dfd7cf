#include "server/report/chart.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "server/report/ticks.h"

namespace enavi::report {
namespace {

constexpr Rgb kAxis{0.15, 0.15, 0.15};
constexpr Rgb kGridLine{0.88, 0.88, 0.88};
constexpr double kLeft = 62.0;    // px for y tick labels and the y label
constexpr double kRight = 12.0;
constexpr double kTop = 26.0;     // px for the panel title
constexpr double kBottom = 40.0;  // px for x tick labels and the x label

std::pair<double, double> Padded(double lo, double hi) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) return {0.0, 1.0};
  if (hi - lo < 1e-12) {
    const double pad = std::max(0.5, 0.1 * std::abs(lo));
    return {lo - pad, hi + pad};
  }
  const double pad = 0.05 * (hi - lo);
  return {lo - pad, hi + pad};
}

}  // namespace

Chart::Chart(std::string title, std::string x_label, std::string y_label)
    : title_(std::move(title)), x_label_(std::move(x_label)), y_label_(std::move(y_label)) {}

Chart& Chart::AddSeries(std::string name, std::vector<double> x, std::vector<double> y, std::optional<Rgb> color) {
  Series s;
  s.name = std::move(name);
  s.x = std::move(x);
  s.y = std::move(y);
  s.color = color;
  return AddSeries(std::move(s));
}

Chart& Chart::AddSeries(Series series) {
  if (series.x.size() != series.y.size()) {
    throw std::invalid_argument("chart series '" + series.name + "': " + std::to_string(series.x.size()) +
                                " x values but " + std::to_string(series.y.size()) + " y values");
  }
  series_.push_back(std::move(series));
  return *this;
}

Chart& Chart::SetYRange(double lo, double hi) {
  if (!(hi > lo)) throw std::invalid_argument("chart '" + title_ + "': y range needs lo < hi");
  y_fixed_ = {lo, hi};
  return *this;
}

Chart& Chart::SetXRange(double lo, double hi) {
  if (!(hi > lo)) throw std::invalid_argument("chart '" + title_ + "': x range needs lo < hi");
  x_fixed_ = {lo, hi};
  return *this;
}

std::pair<double, double> Chart::XRange() const {
  if (x_fixed_) return *x_fixed_;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& s : series_) {
    for (double v : s.x) {
      if (!std::isfinite(v)) continue;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  if (!std::isfinite(lo)) return {0.0, 1.0};
  if (hi - lo < 1e-12) return {lo - 0.5, hi + 0.5};
  return {lo, hi};
}

std::pair<double, double> Chart::YRange() const {
  if (y_fixed_) return *y_fixed_;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& s : series_) {
    for (std::size_t i = 0; i < s.y.size(); ++i) {
      if (!std::isfinite(s.y[i]) || !std::isfinite(s.x[i])) continue;
      lo = std::min(lo, s.y[i]);
      hi = std::max(hi, s.y[i]);
    }
  }
  return Padded(lo, hi);
}

void Chart::Render(Canvas* canvas, double x, double y, double w, double h,
                   const std::optional<std::pair<double, double>>& x_range, bool x_tick_labels) const {
  const auto [x_lo, x_hi] = x_range ? *x_range : XRange();
  const auto [y_lo, y_hi] = YRange();
  const double px0 = x + kLeft, px1 = x + w - kRight;
  const double py0 = y + kTop, py1 = y + h - (x_tick_labels ? kBottom : 8.0);
  if (px1 - px0 < 20.0 || py1 - py0 < 20.0) throw std::invalid_argument("chart '" + title_ + "': area too small");
  auto to_px = [&, x_lo = x_lo, x_hi = x_hi, y_lo = y_lo, y_hi = y_hi](double vx, double vy) {
    return Eigen::Vector2d(px0 + (vx - x_lo) / (x_hi - x_lo) * (px1 - px0),
                           py1 - (vy - y_lo) / (y_hi - y_lo) * (py1 - py0));
  };

  canvas->Text(px0, y + 17.0, title_, 13.0, colors::kBlack, TextAlign::kLeft, true);
  // Grid and ticks.
  const double y_step = NiceStep(y_lo, y_hi, 5);
  for (double v : NiceTicks(y_lo, y_hi, 5)) {
    const double py = to_px(x_lo, v).y();
    canvas->Line(px0, py, px1, py, kGridLine, 1.0);
    canvas->Line(px0 - 4.0, py, px0, py, kAxis, 1.0);
    canvas->Text(px0 - 7.0, py + 4.0, FormatTick(v, y_step), 11.0, kAxis, TextAlign::kRight);
  }
  const double x_step = NiceStep(x_lo, x_hi, 8);
  for (double v : NiceTicks(x_lo, x_hi, 8)) {
    const double px = to_px(v, y_lo).x();
    canvas->Line(px, py0, px, py1, kGridLine, 1.0);
    canvas->Line(px, py1, px, py1 + 4.0, kAxis, 1.0);
    if (x_tick_labels) canvas->Text(px, py1 + 17.0, FormatTick(v, x_step), 11.0, kAxis, TextAlign::kCenter);
  }
  if (x_tick_labels && !x_label_.empty()) {
    canvas->Text(0.5 * (px0 + px1), py1 + 34.0, x_label_, 12.0, colors::kBlack, TextAlign::kCenter);
  }
  if (!y_label_.empty()) {
    canvas->Text(x + 14.0, 0.5 * (py0 + py1), y_label_, 12.0, colors::kBlack, TextAlign::kCenter, false, true);
  }

  // Series, clipped to the plot area; non-finite points break the line.
  canvas->PushClip(px0, py0, px1 - px0, py1 - py0);
  for (std::size_t k = 0; k < series_.size(); ++k) {
    const Series& s = series_[k];
    const Rgb color = s.color.value_or(PaletteColor(static_cast<int>(k)));
    std::vector<Eigen::Vector2d> run;
    auto flush = [&] {
      if (run.size() == 1) canvas->FillCircle(run[0].x(), run[0].y(), 0.8 * s.line_width + 0.5, color);
      canvas->Polyline(run, color, s.line_width);
      run.clear();
    };
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
        flush();
        continue;
      }
      const Eigen::Vector2d p = to_px(s.x[i], s.y[i]);
      if (s.step && !run.empty()) run.emplace_back(p.x(), run.back().y());
      run.push_back(p);
    }
    flush();
  }
  canvas->PopClip();
  canvas->StrokeRect(px0, py0, px1 - px0, py1 - py0, kAxis, 1.0);

  // Legend, top right inside the plot.
  if (!series_.empty()) {
    double legend_w = 0.0;
    for (const auto& s : series_) legend_w = std::max(legend_w, canvas->TextWidth(s.name, 11.0));
    legend_w += 34.0;
    const double lx = px1 - legend_w - 6.0, ly = py0 + 6.0;
    const double lh = 16.0 * static_cast<double>(series_.size()) + 6.0;
    canvas->FillRect(lx, ly, legend_w, lh, colors::kWhite, 0.85);
    canvas->StrokeRect(lx, ly, legend_w, lh, kGridLine, 1.0);
    for (std::size_t k = 0; k < series_.size(); ++k) {
      const Rgb color = series_[k].color.value_or(PaletteColor(static_cast<int>(k)));
      const double ry = ly + 12.0 + 16.0 * static_cast<double>(k);
      canvas->Line(lx + 6.0, ry - 4.0, lx + 24.0, ry - 4.0, color, 2.5);
      canvas->Text(lx + 29.0, ry, series_[k].name, 11.0, colors::kBlack);
    }
  }
}

void Chart::SavePng(const std::string& path, int width, int height) const {
  Canvas canvas(width, height);
  Render(&canvas, 0.0, 0.0, width, height);
  canvas.SavePng(path);
}

ChartStack::ChartStack(std::string title, std::string x_label) : title_(std::move(title)), x_label_(std::move(x_label)) {}

Chart& ChartStack::AddPanel(std::string title, std::string y_label) {
  panels_.emplace_back(std::move(title), x_label_, std::move(y_label));
  return panels_.back();
}

void ChartStack::Render(Canvas* canvas) const {
  if (panels_.empty()) throw std::invalid_argument("chart stack '" + title_ + "' has no panels");
  const double header = title_.empty() ? 0.0 : 30.0;
  // Shared x range: union over panels.
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& p : panels_) {
    const auto [a, b] = p.XRange();
    lo = std::min(lo, a);
    hi = std::max(hi, b);
  }
  if (!title_.empty()) canvas->Text(kLeft, 21.0, title_, 16.0, colors::kBlack, TextAlign::kLeft, true);
  const double bottom_extra = kBottom - 8.0;  // the last panel also carries the x labels
  const double panel_h = (canvas->height() - header - bottom_extra) / static_cast<double>(panels_.size());
  for (std::size_t i = 0; i < panels_.size(); ++i) {
    const bool last = i + 1 == panels_.size();
    panels_[i].Render(canvas, 0.0, header + panel_h * static_cast<double>(i), canvas->width(),
                      panel_h + (last ? bottom_extra : 0.0), std::make_pair(lo, hi), last);
  }
}

void ChartStack::SavePng(const std::string& path, int width, int panel_height) const {
  const int header = title_.empty() ? 0 : 30;
  Canvas canvas(width, header + panel_height * static_cast<int>(std::max<std::size_t>(1, panels_.size())) +
                           static_cast<int>(kBottom - 8.0));
  Render(&canvas);
  canvas.SavePng(path);
}

}  // namespace enavi::report
