#include "server/report/canvas.h"

#include <filesystem>
#include <stdexcept>

#include <gtest/gtest.h>

#include "server/report/colormap.h"
#include "server/report/ticks.h"
#include "tests/unit/worlds/test_util.h"

namespace enavi::report {
namespace {

using worlds::testing::TempDir;

void ExpectColor(Rgb actual, Rgb expected, double tol, const std::string& what) {
  EXPECT_NEAR(actual.r, expected.r, tol) << what << " (red)";
  EXPECT_NEAR(actual.g, expected.g, tol) << what << " (green)";
  EXPECT_NEAR(actual.b, expected.b, tol) << what << " (blue)";
}

TEST(CanvasTest, ShapesLandWhereTheyAreDrawn) {
  Canvas c(200, 100);
  c.FillRect(10, 10, 30, 20, {1, 0, 0});
  c.FillCircle(100, 50, 10, {0, 0, 1});
  c.Line(150, 10, 150, 90, {0, 1, 0}, 4.0);
  ExpectColor(c.Pixel(20, 20), {1, 0, 0}, 0.01, "inside the rectangle");
  ExpectColor(c.Pixel(45, 20), colors::kWhite, 0.01, "right of the rectangle");
  ExpectColor(c.Pixel(100, 50), {0, 0, 1}, 0.01, "circle centre");
  ExpectColor(c.Pixel(100, 65), colors::kWhite, 0.01, "below the circle");
  ExpectColor(c.Pixel(150, 50), {0, 1, 0}, 0.01, "on the line");
  EXPECT_THROW(c.Pixel(200, 0), std::out_of_range);
}

TEST(CanvasTest, ClipRestrictsDrawing) {
  Canvas c(100, 100);
  c.PushClip(0, 0, 50, 100);
  c.FillRect(0, 0, 100, 100, colors::kBlack);
  c.PopClip();
  ExpectColor(c.Pixel(25, 50), colors::kBlack, 0.01, "inside the clip");
  ExpectColor(c.Pixel(75, 50), colors::kWhite, 0.01, "outside the clip");
}

TEST(CanvasTest, TextPutsInkOnTheCanvas) {
  Canvas c(200, 50);
  c.Text(10, 35, "WWW", 30, colors::kBlack, TextAlign::kLeft, true);
  int dark = 0;
  for (int y = 0; y < 50; ++y)
    for (int x = 0; x < 200; ++x) dark += c.Pixel(x, y).r < 0.5 ? 1 : 0;
  EXPECT_GT(dark, 100) << "the font (DejaVu Sans via cairo) rendered no glyphs";
  EXPECT_GT(c.TextWidth("WWW", 30), c.TextWidth("W", 30));
}

TEST(CanvasTest, SavedPngDecodesWithTheSameSizeAndPixels) {
  TempDir dir;
  Canvas c(64, 32, {0.2, 0.4, 0.6});
  c.FillRect(0, 0, 8, 8, {1, 1, 0});
  const std::string path = (dir.path() / "c.png").string();
  c.SavePng(path);
  const PngImage img = ReadPng(path);
  EXPECT_EQ(img.width, 64);
  EXPECT_EQ(img.height, 32);
  ExpectColor(img.Pixel(2, 2), {1, 1, 0}, 0.01, "yellow corner");
  ExpectColor(img.Pixel(40, 20), {0.2, 0.4, 0.6}, 0.01, "background");
}

TEST(CanvasTest, SaveAndReadFailuresNameThePath) {
  Canvas c(10, 10);
  try {
    c.SavePng("/nonexistent-dir/x.png");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/x.png"), std::string::npos) << e.what();
  }
  TempDir dir;
  const auto junk = dir.Write("junk.png", "not a png");
  try {
    ReadPng(junk.string());
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("junk.png"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Canvas(0, 10), std::invalid_argument);
}

TEST(CanvasTest, CanvasIsMovable) {
  Canvas a(20, 20);
  a.FillRect(0, 0, 20, 20, {1, 0, 0});
  Canvas b = std::move(a);
  ExpectColor(b.Pixel(5, 5), {1, 0, 0}, 0.01, "moved canvas keeps its pixels");
}

TEST(ColormapTest, ViridisRunsFromPurpleToYellowMonotonicallyInLightness) {
  const Rgb lo = Viridis(0.0), hi = Viridis(1.0);
  EXPECT_GT(lo.b, lo.g) << "low end is purple-blue";
  EXPECT_GT(hi.r, 0.9) << "high end is yellow";
  EXPECT_GT(hi.g, 0.85);
  double last = -1.0;
  for (int i = 0; i <= 100; ++i) {
    const Rgb c = Viridis(i / 100.0);
    const double lightness = 0.3 * c.r + 0.59 * c.g + 0.11 * c.b;
    EXPECT_GT(lightness, last - 1e-9) << "t = " << i / 100.0;
    last = lightness;
  }
  ExpectColor(Viridis(-3.0), lo, 1e-12, "clamped below");
  ExpectColor(Viridis(7.0), hi, 1e-12, "clamped above");
  EXPECT_GT(GreyRamp(0.0).r, GreyRamp(1.0).r) << "tall is darker";
}

void ExpectTicks(const std::vector<double>& actual, const std::vector<double>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < actual.size(); ++i) EXPECT_NEAR(actual[i], expected[i], 1e-12) << "tick " << i;
}

TEST(TicksTest, NiceNumbers) {
  ExpectTicks(NiceTicks(0.0, 10.0, 5), {0, 2, 4, 6, 8, 10});
  ExpectTicks(NiceTicks(0.13, 0.87, 4), {0.2, 0.4, 0.6, 0.8});
  EXPECT_DOUBLE_EQ(NiceStep(0.0, 47.0, 5), 10.0);
  EXPECT_EQ(FormatTick(0.2, 0.2), "0.2");
  EXPECT_EQ(FormatTick(-0.0, 0.5), "0.0");
  EXPECT_EQ(FormatTick(20.0, 10.0), "20");
  EXPECT_TRUE(NiceTicks(1.0, 1.0).empty());
}

}  // namespace
}  // namespace enavi::report
