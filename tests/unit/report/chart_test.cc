#include "server/report/chart.h"

#include <cmath>

#include <gtest/gtest.h>

#include "tests/unit/worlds/test_util.h"

namespace enavi::report {
namespace {

using worlds::testing::TempDir;

// Whether any pixel in the image has (about) this colour.
bool HasColor(const PngImage& img, Rgb c, double tol = 0.03) {
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const Rgb p = img.Pixel(x, y);
      if (std::abs(p.r - c.r) < tol && std::abs(p.g - c.g) < tol && std::abs(p.b - c.b) < tol) return true;
    }
  }
  return false;
}

TEST(ChartTest, SingleChartDrawsEachSeriesInItsColour) {
  TempDir dir;
  std::vector<double> t, a, b;
  for (int i = 0; i <= 100; ++i) {
    t.push_back(0.1 * i);
    a.push_back(std::sin(0.1 * i));
    b.push_back(0.5);
  }
  Chart chart("eci over time", "time [s]", "eci");
  chart.AddSeries("eci", t, a, Rgb{1, 0, 0}).AddSeries("threshold", t, b, Rgb{0, 0, 1});
  const auto [lo, hi] = chart.YRange();
  EXPECT_LT(lo, -0.99);
  EXPECT_GT(hi, 0.99);
  const std::string path = (dir.path() / "chart.png").string();
  chart.SavePng(path, 640, 300);
  const PngImage img = ReadPng(path);
  EXPECT_EQ(img.width, 640);
  EXPECT_EQ(img.height, 300);
  EXPECT_TRUE(HasColor(img, {1, 0, 0})) << "red series missing";
  EXPECT_TRUE(HasColor(img, {0, 0, 1})) << "blue series missing";
  EXPECT_FALSE(HasColor(img, {0, 1, 0})) << "nothing green was drawn";
}

TEST(ChartTest, StackSharesTheXAxisAcrossPanels) {
  TempDir dir;
  ChartStack stack("episode", "time [s]");
  stack.AddPanel("eci", "eci").AddSeries("eci", {0, 1, 2, 3}, {0.1, 0.5, 0.9, 0.3});
  Chart& freq = stack.AddPanel("frequencies", "Hz");
  freq.AddSeries("f_per", {0, 1, 2, 3}, {30, 20, 10, 15});
  freq.AddSeries("f_col", {0, 1, 2, 3}, {10, 10, 5, 5});
  Series res;
  res.name = "res";
  res.x = {0, 10};
  res.y = {0.1, 0.3};
  res.step = true;
  stack.AddPanel("resolution", "m").AddSeries(res);
  EXPECT_EQ(stack.panel_count(), 3u);
  const std::string path = (dir.path() / "stack.png").string();
  stack.SavePng(path, 800, 180);
  const PngImage img = ReadPng(path);
  EXPECT_EQ(img.width, 800);
  EXPECT_GT(img.height, 3 * 180);
  EXPECT_TRUE(HasColor(img, PaletteColor(0)));
  EXPECT_TRUE(HasColor(img, PaletteColor(1)));
}

TEST(ChartTest, BadSeriesAndRangesAreRefused) {
  Chart c;
  EXPECT_THROW(c.AddSeries("x", {1, 2}, {1}), std::invalid_argument);
  EXPECT_THROW(c.SetYRange(1, 1), std::invalid_argument);
  EXPECT_THROW(ChartStack().SavePng("/tmp/never.png"), std::invalid_argument);
}

TEST(ChartTest, NonFiniteValuesBreakTheLineInsteadOfFailing) {
  TempDir dir;
  Chart c("gaps");
  c.AddSeries("g", {0, 1, 2, 3, 4}, {1, NAN, 2, INFINITY, 3}, Rgb{1, 0, 0});
  const auto [lo, hi] = c.YRange();
  EXPECT_TRUE(std::isfinite(lo) && std::isfinite(hi));
  c.SavePng((dir.path() / "g.png").string(), 400, 200);
  EXPECT_TRUE(HasColor(ReadPng((dir.path() / "g.png").string()), {1, 0, 0}));
}

}  // namespace
}  // namespace enavi::report
