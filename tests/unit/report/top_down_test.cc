#include "server/report/top_down.h"

#include <gtest/gtest.h>

#include "server/report/colormap.h"
#include "tests/unit/worlds/test_util.h"

namespace enavi::report {
namespace {

using worlds::testing::TempDir;

void ExpectColor(Rgb actual, Rgb expected, double tol, const std::string& what) {
  EXPECT_NEAR(actual.r, expected.r, tol) << what << " (red)";
  EXPECT_NEAR(actual.g, expected.g, tol) << what << " (green)";
  EXPECT_NEAR(actual.b, expected.b, tol) << what << " (blue)";
}

worlds::Box MakeBox(Eigen::Vector3d centre, Eigen::Vector3d size) {
  worlds::Box b;
  b.center = centre;
  b.size = size;
  return b;
}

// Top view, 40 x 20 m:
//
//   y 10 +----------------------------------------+
//        |                                        |
//      0 |  S      [low 6x6, 2 m]   (tower)    G  |   tower: 2x2, 12 m, overlapping the low box
//        |                                        |
//    -10 +----------------------------------------+
//       -20                                       20  x
worlds::World Scene() {
  worlds::World w;
  w.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-20, -10, 0), Eigen::Vector3d(20, 10, 6));
  w.start = Eigen::Vector3d(-16, 0, 1.5);
  w.goal = Eigen::Vector3d(16, 0, 1.5);
  w.objects.emplace_back(MakeBox({8, 0, 6}, {2, 2, 12}));  // tower, listed first
  w.objects.emplace_back(MakeBox({5, 0, 1}, {8, 6, 2}));   // low block under it
  worlds::Cylinder pole;
  pole.base = {-5, 5, 0};
  pole.radius = 1.0;
  pole.height = 4.0;
  w.objects.emplace_back(pole);
  return w;
}

Eigen::Vector2i Px(const TopDownView& v, double x, double y) {
  const Eigen::Vector2d p = v.ToPixel({x, y});
  return {static_cast<int>(std::floor(p.x())), static_cast<int>(std::floor(p.y()))};
}

TEST(TopDownViewTest, ObstaclesAreShadedByTopHeightAndTallOnesStayOnTop) {
  const TopDownView view(Scene());
  EXPECT_DOUBLE_EQ(view.height_min(), 0.0);  // ground
  EXPECT_DOUBLE_EQ(view.height_max(), 12.0);
  const Canvas& c = view.canvas();
  auto at = [&](double x, double y) {
    const Eigen::Vector2i p = Px(view, x, y);
    return c.Pixel(p.x(), p.y());
  };
  ExpectColor(at(3, 0), GreyRamp(2.0 / 12.0), 0.02, "low block");
  ExpectColor(at(8, 0), GreyRamp(1.0), 0.02, "tower drawn over the low block");
  ExpectColor(at(-5, 5), GreyRamp(4.0 / 12.0), 0.02, "pole");
  ExpectColor(at(0, -7), Rgb{0.93, 0.95, 0.89}, 0.02, "open ground");
}

// The scene with a walker going back and forth from (0, -8) to (0, 8) at 1 m/s: its track is a
// dashed purple line, and DrawMoversAt puts its footprint where it is at that time.
TEST(TopDownViewTest, MoversTracksAreDrawnAndTheirShapesWhereTheyAreAtATime) {
  worlds::World w = Scene();
  worlds::Mover walker;
  walker.name = "walker";
  walker.shape.emplace_back(MakeBox({0, 0, 0.9}, {1.0, 1.0, 1.8}));
  walker.waypoints.resize(2);
  walker.waypoints[0].position = {0, -8, 0};
  walker.waypoints[1].position = {0, 8, 0};
  walker.speed = 1.0;
  walker.mode = worlds::MoverMode::kBackAndForth;
  w.movers.push_back(walker);
  const Rgb purple{0.55, 0.22, 0.78};
  TopDownView view(w);
  // Dashes: along the track, some pixels are the track's colour and some are the ground's.
  int track = 0, ground = 0;
  for (double y = -6; y <= 6; y += 0.05) {
    const Eigen::Vector2i p = Px(view, 0.0, y);
    const Rgb c = view.canvas().Pixel(p.x(), p.y());
    track += std::abs(c.r - purple.r) + std::abs(c.g - purple.g) + std::abs(c.b - purple.b) < 0.1 ? 1 : 0;
    ground += std::abs(c.g - 0.95) < 0.02 ? 1 : 0;
  }
  EXPECT_GT(track, 20) << "the track";
  EXPECT_GT(ground, 20) << "dashed, not solid";
  // At t = 12 s it is at y = 4 on its way: its footprint, filled, covers the track there.
  view.DrawMoversAt(12.0, "movers at 12 s");
  for (const double y : {3.7, 4.0, 4.3}) {
    const Eigen::Vector2i p = Px(view, 0.2, y);
    ExpectColor(view.canvas().Pixel(p.x(), p.y()), Rgb{0.66, 0.42, 0.84}, 0.05, "the walker's footprint at 12 s");
  }
  const Eigen::Vector2i off = Px(view, 0.2, -4.0);
  ExpectColor(view.canvas().Pixel(off.x(), off.y()), Rgb{0.93, 0.95, 0.89}, 0.02, "not where it was at 4 s");
}

TEST(TopDownViewTest, StartIsGreenAndGoalIsRed) {
  const TopDownView view(Scene());
  const Eigen::Vector2i s = Px(view, -16, 0), g = Px(view, 16, 0);
  ExpectColor(view.canvas().Pixel(s.x(), s.y()), colors::kStart, 0.02, "start marker");
  ExpectColor(view.canvas().Pixel(g.x(), g.y()), colors::kGoal, 0.02, "goal marker");
}

TEST(TopDownViewTest, MapFitsTheImageWithMarginsAndKeepsTheAspect) {
  TopDownOptions options;
  options.width = 900;
  options.height = 700;
  const TopDownView view(Scene(), options);
  const Eigen::Vector2d lo = view.ToPixel({-20, -10}), hi = view.ToPixel({20, 10});
  EXPECT_NEAR(lo.x(), options.margin, 1e-9);
  EXPECT_LE(hi.x(), options.width - options.legend_width - options.margin + 1e-9);
  EXPECT_LT(hi.y(), lo.y()) << "y points up in the image";
  EXPECT_NEAR((hi.x() - lo.x()) / (lo.y() - hi.y()), 2.0, 1e-9) << "40 x 20 m stays 2:1";
}

TEST(TopDownViewTest, CeilingIsAnOutlineSoFurnitureShows) {
  worlds::World hall = Scene();
  hall.objects.emplace_back(MakeBox({0, 0, 4.2}, {40, 20, 0.3}));  // ceiling above the flight altitude
  const TopDownView view(hall);
  const Eigen::Vector2i p = Px(view, 3, 0);
  ExpectColor(view.canvas().Pixel(p.x(), p.y()), GreyRamp(2.0 / 12.0), 0.02, "low block under the ceiling");
}

TEST(TopDownViewTest, PathIsColouredByValueAndMarkersStayOnTop) {
  TopDownView view(Scene());
  // Along y = -6 from x = -16 to 16, value rising from 0 to 1.
  std::vector<Eigen::Vector2d> xy;
  std::vector<double> v;
  for (int i = 0; i <= 32; ++i) {
    xy.emplace_back(-16.0 + i, -6.0);
    v.push_back(i / 32.0);
  }
  view.DrawPath(xy, v, 0.0, 1.0, "eci");
  view.DrawPath({{-16, 0}, {16, 0}}, colors::kBlack, 2.0);  // over the start and goal
  view.DrawMarker({0, 6}, {0, 0, 1}, "collision");
  const Canvas& c = view.canvas();
  Eigen::Vector2i p = Px(view, -15.5, -6.0);
  ExpectColor(c.Pixel(p.x(), p.y()), Viridis(0.5 / 32.0), 0.03, "path start is dark purple");
  p = Px(view, 15.5, -6.0);
  ExpectColor(c.Pixel(p.x(), p.y()), Viridis(31.5 / 32.0), 0.03, "path end is yellow");
  p = Px(view, -16, 0);
  ExpectColor(c.Pixel(p.x(), p.y()), colors::kStart, 0.02, "start still on top of the path");
  p = Px(view, 0, 6);
  ExpectColor(c.Pixel(p.x(), p.y()), {0, 0, 1}, 0.02, "marker");
  EXPECT_THROW(view.DrawPath(xy, {1.0}, 0.0, 1.0, "bad"), std::invalid_argument);
}

TEST(TopDownViewTest, SavedPngHasTheRequestedSizeAndTheMarkers) {
  TempDir dir;
  TopDownOptions options;
  options.width = 800;
  options.height = 600;
  const TopDownView view(Scene(), options);
  const std::string path = (dir.path() / "top.png").string();
  view.SavePng(path);
  const PngImage img = ReadPng(path);
  ASSERT_EQ(img.width, 800);
  ASSERT_EQ(img.height, 600);
  const Eigen::Vector2i s = Px(view, -16, 0), t = Px(view, 8, 0);
  ExpectColor(img.Pixel(s.x(), s.y()), colors::kStart, 0.02, "start in the PNG");
  ExpectColor(img.Pixel(t.x(), t.y()), GreyRamp(1.0), 0.02, "tower in the PNG");
}

TEST(TopDownViewTest, MeshIsShadedByItsTopTriangles) {
  worlds::World w = Scene();
  w.objects.clear();
  worlds::MeshObject cube;  // 2 x 2 x 3 m block at (0, -5)
  for (int i = 0; i < 8; ++i) cube.mesh.vertices.emplace_back(i & 1 ? 1.0f : -1.0f, i & 2 ? 1.0f : -1.0f, i & 4 ? 3.0f : 0.0f);
  cube.mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                         {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  cube.position = {0, -5, 0};
  w.objects.emplace_back(cube);
  const TopDownView view(w);
  EXPECT_DOUBLE_EQ(view.height_max(), 3.0);
  const Eigen::Vector2i p = Px(view, 0.3, -5.4);
  ExpectColor(view.canvas().Pixel(p.x(), p.y()), GreyRamp(1.0), 0.02, "top face of the mesh");
}

TEST(TopDownViewTest, AutomaticHeightFollowsTheWorldsAspect) {
  worlds::World w = Scene();
  w.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-20, -40, 0), Eigen::Vector3d(20, 40, 6));  // tall map
  const TopDownView view(w);
  EXPECT_GT(view.canvas().height(), view.canvas().width());
}

}  // namespace
}  // namespace enavi::report
