#pragma once
// Time-series line charts: one panel (Chart) or panels stacked over a shared x axis
// (ChartStack), e.g. eci / f_per, f_col, f_dif / res over an episode.

#include <optional>
#include <string>
#include <vector>

#include "server/report/canvas.h"

namespace enavi::report {

struct Series {
  std::string name;
  std::vector<double> x;
  std::vector<double> y;     ///< same length as x; non-finite values break the line
  std::optional<Rgb> color{};  ///< default: PaletteColor(index in its chart)
  double line_width = 1.6;
  bool step = false;         ///< draw as a staircase (piecewise-constant values such as res)
};

/// One panel: title, axis labels, ticks at nice numbers, any number of series with a legend.
class Chart {
 public:
  explicit Chart(std::string title = "", std::string x_label = "", std::string y_label = "");

  /// @pre x.size() == y.size()
  Chart& AddSeries(std::string name, std::vector<double> x, std::vector<double> y, std::optional<Rgb> color = {});
  Chart& AddSeries(Series series);
  /// Fixed ranges (default: fitted to the data with a little headroom).
  Chart& SetYRange(double lo, double hi);
  Chart& SetXRange(double lo, double hi);

  /// Draws into the rectangle (x, y, w, h) of `canvas`, axes and labels included.
  /// `x_range` overrides the x range (shared axes); `x_tick_labels` false hides them (stacks).
  void Render(Canvas* canvas, double x, double y, double w, double h,
              const std::optional<std::pair<double, double>>& x_range = std::nullopt, bool x_tick_labels = true) const;

  /// Renders alone on a width x height image and writes a PNG (std::runtime_error on failure).
  void SavePng(const std::string& path, int width = 900, int height = 360) const;

  /// Range of the finite x values of all series (or the fixed range); {0, 1} when empty.
  std::pair<double, double> XRange() const;
  std::pair<double, double> YRange() const;

  const std::string& title() const { return title_; }
  const std::vector<Series>& series() const { return series_; }

 private:
  std::string title_, x_label_, y_label_;
  std::vector<Series> series_;
  std::optional<std::pair<double, double>> x_fixed_, y_fixed_;
};

/// Panels stacked vertically sharing one x axis (tick labels and x label on the bottom one).
class ChartStack {
 public:
  explicit ChartStack(std::string title = "", std::string x_label = "time [s]");

  /// Adds a panel and returns it for AddSeries; references stay valid until the next AddPanel.
  Chart& AddPanel(std::string title, std::string y_label);
  std::size_t panel_count() const { return panels_.size(); }

  void Render(Canvas* canvas) const;
  /// Image of `width` x (title + panel_height per panel); throws std::runtime_error on failure.
  void SavePng(const std::string& path, int width = 900, int panel_height = 200) const;

 private:
  std::string title_, x_label_;
  std::vector<Chart> panels_;
};

}  // namespace enavi::report
