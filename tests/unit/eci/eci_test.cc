#include "navstack/eci/eci.h"
#include "navstack/eci/eci_internal.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "tests/unit/perception/synthetic_depth.h"

namespace enavi::navstack {
namespace {

using testing::BoxAt;
using testing::CameraPose;
using testing::Render;
using testing::Scene;

// The farm's camera: 640x480, 87 x 58 deg, 0.2 - 10 m, so d_per = 10 m. It sits at the world
// origin looking along +x; camera x (right) is world -y, camera y (down) is world -z.
const CameraIntrinsics kCam = CameraIntrinsics::Default();
const Eigen::Isometry3d kX_WC = CameraPose(Eigen::Vector3d::Zero());
const Eigen::Vector3d kHover = Eigen::Vector3d::Zero();

// A wall filling the whole view, its face at z-depth d:   cam |--d--> |wall|
Scene WallAt(double d) {
  return Scene{{BoxAt({d + 0.5, 0, 0}, {1.0, 100, 100})}, {}};
}

// A 0.6 m cube whose face is at depth d, centred at (right, up) metres off the optical axis.
Scene CubeAt(double d, double right = 0.0, double up = 0.0) {
  return Scene{{BoxAt({d + 0.3, -right, up}, {0.6, 0.6, 0.6})}, {}};
}

// A 0.3 m cube centred at range r in the direction (azimuth right, pitch up) in degrees, given
// as tangent-plane angles like the zones: the direction is (tan az, -tan el, 1) in C.
Scene CubeInDirection(double r, double az_deg, double el_deg) {
  const double deg = M_PI / 180.0;
  const Eigen::Vector3d dir_C =
      Eigen::Vector3d(std::tan(az_deg * deg), -std::tan(el_deg * deg), 1.0).normalized();
  const Eigen::Vector3d p_W = kX_WC * (r * dir_C);
  return Scene{{BoxAt(p_W, {0.3, 0.3, 0.3})}, {}};
}

EciResult Eci(const Scene& scene, const Eigen::Vector3d& v_C = kHover, const EciOptions& o = {}) {
  return ComputeEci(Render(scene, kCam, kX_WC), kCam, v_C, o);
}

TEST(EciTest, EmptyViewIsZero) {
  const EciResult r = Eci(Scene{});
  EXPECT_EQ(r.status, EciResult::Status::kNoObstacle);
  EXPECT_EQ(r.eci, 0.0);
  EXPECT_EQ(r.valid_pixels, 0);
}

TEST(EciTest, WallDeadAheadInsideDminIsOne) {
  // 0.4 m < d_min = 0.5 m: layer 0 is full and everything behind it is occluded.
  const EciResult r = Eci(WallAt(0.4));
  ASSERT_EQ(r.status, EciResult::Status::kOk);
  EXPECT_DOUBLE_EQ(r.d0, 0.5) << "d0 is clamped up to d_min";
  EXPECT_GT(r.eci, 0.95) << "a wall about to be hit must read as (nearly) maximal complexity";
}

TEST(EciTest, WallScoreMatchesTheWeightsByHand) {
  // Wall at 1 m: d0 = 1, Lay = floor(9 / 2) + 1 = 5, layers [0,1) [1,3) [3,5) [5,7) [7,9) with
  // depth factors (10 - d_k) / 10 = .95 .8 .6 .4 .2. All returns (1 .. 1.49 m) lie in layer 1,
  // in all 9 zones, so the angular factors cancel.
  EciOptions literal;
  literal.count_occluded = false;
  const EciResult r_literal = Eci(WallAt(1.0), kHover, literal);
  EXPECT_EQ(r_literal.layers, 5);
  EXPECT_NEAR(r_literal.d0, 1.0, 1e-3);
  EXPECT_EQ(r_literal.occupied_zones, 9);
  EXPECT_NEAR(r_literal.eci, 0.8 / 2.95, 1e-3) << "only layer 1 is occupied";
  // With occlusion, layers 2-4 behind the wall count too.
  const EciResult r = Eci(WallAt(1.0));
  EXPECT_EQ(r.occupied_zones, 36);
  EXPECT_NEAR(r.eci, 2.0 / 2.95, 1e-3);
}

TEST(EciTest, WallScoreFallsWithDistance) {
  double previous = 1.1;
  for (double d : {0.4, 1.0, 2.0, 3.0, 4.0}) {
    const double eci = Eci(WallAt(d)).eci;
    EXPECT_LT(eci, previous) << "wall at " << d << " m must score below the nearer one";
    previous = eci;
  }
  // Beyond d_per / 3 the formula gives Lay = 1, only the empty layer 0 = [0, d0); the layer
  // holding the wall is kept (Lay >= 2), so a far wall still scores, lower than a near one.
  const EciResult far = Eci(WallAt(4.0));
  EXPECT_EQ(far.layers, 2);
  EXPECT_GT(far.eci, 0.05);
  // The wall's layer [d0, 3 d0) has its mid-depth 2 d0 beyond d_per from d0 = 5 m: weight 0.
  EXPECT_EQ(Eci(WallAt(6.0)).eci, 0.0);
}

TEST(EciTest, OffAxisObstacleScoresLower) {
  // The same cube at the same range, in the middle of the centre zone, of the right zone and of
  // the upper-right zone (zones are 29 x 19.3 deg: centres at 0 / 29 deg and 0 / 19.3 deg).
  for (double r : {1.5, 2.5}) {
    const EciResult ahead = Eci(CubeInDirection(r, 0.0, 0.0));
    const EciResult side = Eci(CubeInDirection(r, 29.0, 0.0));
    const EciResult corner = Eci(CubeInDirection(r, 29.0, 19.3));
    // The rotated cube's nearest corner is a little nearer than the face of the one ahead.
    EXPECT_EQ(side.layers, ahead.layers) << "same range, same layers";
    EXPECT_EQ(corner.layers, ahead.layers) << "same range, same layers";
    EXPECT_GT(corner.eci, 0.0) << "the off-axis cube must still be seen";
    EXPECT_LT(side.eci, ahead.eci) << "range " << r;
    EXPECT_LT(corner.eci, side.eci) << "range " << r;
    // The cube hides under half of its zone, so one zone is occupied in each case, and the ratios are the angular weights (up to the
    // slightly different d0).
    EXPECT_EQ(ahead.occupied_zones, 1);
    EXPECT_EQ(side.occupied_zones, 1);
    EXPECT_EQ(corner.occupied_zones, 1);
    EXPECT_NEAR(side.eci / ahead.eci, std::exp(-0.25), 0.05);
    EXPECT_NEAR(corner.eci / ahead.eci, std::exp(-0.5), 0.05);
  }
}

TEST(EciTest, FarObstacleScoresLower) {
  double previous = 1.0;
  for (double r : {1.0, 2.0, 3.0}) {
    const double eci = Eci(CubeInDirection(r, 0.0, 0.0)).eci;
    EXPECT_GT(eci, 0.0) << "range " << r;
    EXPECT_LT(eci, previous) << "cube at " << r << " m must score below the nearer one";
    previous = eci;
  }
}

TEST(EciTest, VelocityTowardObstacleRaisesEci) {
  // Cube 1.2 m to the left at 2 m (about 31 deg off axis); flying at 2 m/s either toward it or
  // mirrored away from it. v_C: x right, z forward.
  const Scene scene = CubeAt(2.0, -1.2, 0.0);
  const Eigen::Vector3d toward(-1.2, 0.0, 2.0), away(1.2, 0.0, 2.0);
  const EciResult r_toward = Eci(scene, toward.normalized() * 2.0);
  const EciResult r_away = Eci(scene, away.normalized() * 2.0);
  EXPECT_TRUE(r_toward.velocity_aligned);
  EXPECT_GT(r_toward.eci, r_away.eci);
  // Hovering or flying backwards falls back to the optical axis.
  EXPECT_FALSE(Eci(scene, Eigen::Vector3d(0, 0, 0.1)).velocity_aligned);
  const EciResult backwards = Eci(scene, Eigen::Vector3d(0, 0, -2.0));
  EXPECT_FALSE(backwards.velocity_aligned);
  EXPECT_DOUBLE_EQ(backwards.eci, Eci(scene).eci);
}

TEST(EciTest, RangeAheadIsTheCentreZonesNotTheNearestAnywhere) {
  const Eigen::Vector3d forward(0.0, 0.0, 2.0);  // v_C: flying along the optical axis
  // A cube dead ahead at 2 m: the nearest return is ahead, in layer 1 = [d0, 3 d0).
  const EciResult ahead = Eci(CubeAt(2.0), forward);
  EXPECT_NEAR(ahead.d_ahead, ahead.d0, 1e-12);
  EXPECT_NEAR(ahead.d0, 2.0, 0.01);
  // The same cube 1.2 m to the left (24-37 deg off the velocity, outside the 29 deg wide centre
  // zone): its nearest corner is the nearest return anywhere, nothing is ahead within the layers.
  const EciResult side = Eci(CubeAt(2.0, -1.2, 0.0), forward);
  EXPECT_NEAR(side.d0, std::hypot(2.0, 0.9), 0.01);
  EXPECT_DOUBLE_EQ(side.d_ahead, 10.0) << "d_per";
  // The side cube and a far one ahead at 7 m: d_ahead is the far one's range.
  Scene both = CubeAt(2.0, -1.2, 0.0);
  both.boxes.push_back(CubeAt(7.0).boxes[0]);
  const EciResult r = Eci(both, forward);
  EXPECT_NEAR(r.d_ahead, 7.0, 0.01);
  EXPECT_NEAR(r.d0, side.d0, 1e-9);
  // Hovering: the centre zone is not the direction of motion, so d_ahead falls back to d0.
  EXPECT_DOUBLE_EQ(Eci(CubeAt(2.0, -1.2, 0.0)).d_ahead, Eci(CubeAt(2.0, -1.2, 0.0)).d0);
}

TEST(EciTest, LayerCountFollowsFormula) {
  for (double d : {0.6, 0.8, 1.0, 1.7, 2.5, 3.2}) {
    const EciResult r = Eci(WallAt(d));
    // The nearest return is the pixel next to the principal point, a hair beyond d.
    EXPECT_NEAR(r.d0, d, 1e-4 * d);
    EXPECT_EQ(r.layers, std::max(2, static_cast<int>(std::floor((10.0 - r.d0) / (2.0 * r.d0))) + 1)) << d;
  }
  EXPECT_EQ(Eci(WallAt(0.3)).layers, 10) << "d0 clamped to d_min = 0.5: floor(9.5 / 1) + 1";
  EciOptions o;
  o.d_per = 6.0;
  EXPECT_EQ(Eci(WallAt(1.0), kHover, o).layers, 3) << "floor(5 / 2) + 1";
}

TEST(EciTest, MinPixelsGatesOccupancy) {
  // A 2 cm pole at 3 m covers ~7 x ~200 pixels of the centre column: occupied at the default
  // threshold, not when 2000 pixels are required.
  const Scene pole{{BoxAt({3.01, 0, 0}, {0.02, 0.02, 2.0})}, {}};
  EciOptions strict;
  strict.min_pixels = 2000;
  EXPECT_GT(Eci(pole).eci, 0.0);
  EXPECT_EQ(Eci(pole, kHover, strict).eci, 0.0);
}

// Per-pixel reference written from the definition (double precision, atan angles, the floor
// formula for the layer index): the vectorised binning must agree zone by zone.
std::vector<std::int64_t> ReferenceCounts(const DepthImage& image, const CameraIntrinsics& k,
                                          double az_c, double el_c, const EciResult& r) {
  const int M = r.zones;
  const double az_lo = std::atan(-k.cx / k.fx), az_hi = std::atan((k.width - k.cx) / k.fx);
  const double el_lo = std::atan(-k.cy / k.fy), el_hi = std::atan((k.height - k.cy) / k.fy);
  auto zone = [M](double angle, double centre, double width) {
    const int z = static_cast<int>(std::floor((angle - centre) / width + 0.5 * M));
    return std::clamp(z, 0, M - 1);
  };
  std::vector<std::int64_t> counts(static_cast<std::size_t>(r.layers) * M * M, 0);
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const double z = image.at(u, v);
      if (!DepthImage::Valid(static_cast<float>(z))) continue;
      const Eigen::Vector3d ray = k.PixelRay(u, v);
      const double range = z * ray.norm();
      const int layer = range < r.d0 ? 0 : static_cast<int>(std::floor((range - r.d0) / (2 * r.d0))) + 1;
      if (layer >= r.layers) continue;
      const int zc = zone(std::atan(ray.x()), az_c, (az_hi - az_lo) / M);
      const int zr = zone(std::atan(ray.y()), el_c, (el_hi - el_lo) / M);
      ++counts[(static_cast<std::size_t>(layer) * M + zr) * M + zc];
    }
  }
  return counts;
}

TEST(EciTest, BinningMatchesPerPixelReference) {
  // 101 x 77 is not a multiple of the vector width, and a velocity to the right and up shifts
  // the zone runs off the vector lanes: the ragged ends must be binned exactly once.
  const CameraIntrinsics small = CameraIntrinsics::FromFov(101, 77, 87.0, 58.0, 0.2, 10.0);
  const Scene scene{{BoxAt({1.3, 0.4, 0.1}, {0.6, 0.6, 0.6}), BoxAt({4.0, -1.0, 0}, {0.5, 1, 3})},
                    {{Eigen::Vector3d::UnitZ(), -1.2}}};
  for (const CameraIntrinsics& k : {small, kCam}) {
    const DepthImage image = Render(scene, k, kX_WC);
    const Eigen::Vector3d v_right_up(0.8, -0.3, 1.0);
    struct Case { Eigen::Vector3d v_C; double az_c, el_c; };
    for (const Case& c : {Case{kHover, 0.0, 0.0},
                          Case{v_right_up, std::atan(0.8), std::atan(-0.3)}}) {
      EciOptions o;
      o.min_pixels = 5;
      const EciResult r = ComputeEci(image, k, c.v_C, o);
      const std::vector<std::int64_t> expected = ReferenceCounts(image, k, c.az_c, c.el_c, r);
      ASSERT_EQ(r.pixel_counts.size(), expected.size());
      for (std::size_t i = 0; i < expected.size(); ++i) {
        // Rounding may move a pixel lying exactly on an edge; nothing more.
        EXPECT_NEAR(r.pixel_counts[i], expected[i], 2 + expected[i] / 1000) << "zone-layer " << i;
      }
    }
  }
}

TEST(EciTest, IsDeterministic) {
  const Scene scene{{BoxAt({1.3, 0.4, 0.1}, {0.6, 0.6, 0.6})}, {{Eigen::Vector3d::UnitZ(), -1.2}}};
  const DepthImage image = Render(scene, kCam, kX_WC);
  const EciResult a = ComputeEci(image, kCam, {0.5, 0.1, 2.0});
  const EciResult b = ComputeEci(image, kCam, {0.5, 0.1, 2.0});
  EXPECT_EQ(a.eci, b.eci);
  EXPECT_EQ(a.pixel_counts, b.pixel_counts);
}

TEST(EciTest, EveryKernelGivesIdenticalResults) {
  // The host's vector kernel (AVX2 here) and the portable one must agree bit for bit, or the
  // farm's results would depend on the worker's CPU.
  const CameraIntrinsics small = CameraIntrinsics::FromFov(101, 77, 87.0, 58.0, 0.2, 10.0);
  const Scene scene{{BoxAt({1.3, 0.4, 0.1}, {0.6, 0.6, 0.6}), BoxAt({4.0, -1.0, 0}, {0.5, 1, 3})},
                    {{Eigen::Vector3d::UnitZ(), -1.2}}};
  for (const CameraIntrinsics& k : {small, kCam}) {
    const DepthImage image = Render(scene, k, kX_WC);
    for (const Eigen::Vector3d& v_C : {kHover, Eigen::Vector3d(0.8, -0.3, 1.0)}) {
      const EciResult fast = ComputeEci(image, k, v_C);
      const EciResult portable = internal::ComputeEciBaseline(image, k, v_C);
      EXPECT_EQ(fast.eci, portable.eci);
      EXPECT_EQ(fast.d0, portable.d0);
      EXPECT_EQ(fast.pixel_counts, portable.pixel_counts);
    }
  }
}

TEST(EciTest, CountsOnePixelUnitPerPixelAndTheCentreZoneOnceMoreWhenMoving) {
  WorkCounts work;
  ComputeEci(Render(WallAt(2.0), kCam, kX_WC), kCam, kHover, {}, &work);
  EXPECT_EQ(work.Get(WorkUnit::kPixel), 640 * 480);
  // Moving: d_ahead reads the centre zone once more (27 % of the width x 31 % of the height).
  WorkCounts moving;
  ComputeEci(Render(WallAt(2.0), kCam, kX_WC), kCam, Eigen::Vector3d(0, 0, 2), {}, &moving);
  EXPECT_GT(moving.Get(WorkUnit::kPixel), 640 * 480 * 108 / 100);
  EXPECT_LT(moving.Get(WorkUnit::kPixel), 640 * 480 * 109 / 100);
}

TEST(EciTest, RejectsBadOptions) {
  EciOptions o;
  o.zones = 4;
  EXPECT_THROW(Eci(WallAt(1.0), kHover, o), std::invalid_argument);
  o = {};
  o.d_min = 0.01;  // 500 layers
  EXPECT_THROW(Eci(WallAt(1.0), kHover, o), std::invalid_argument);
  try {
    o = {};
    o.sigma = -1;
    Eci(WallAt(1.0), kHover, o);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("EciOptions.sigma"), std::string::npos) << e.what();
  }
}

TEST(EciTrackerTest, DEciIsDifferenceToPreviousFrame) {
  EciTracker tracker;
  EXPECT_EQ(tracker.Update(0.3), 0.0) << "no previous frame yet";
  EXPECT_DOUBLE_EQ(tracker.Update(0.5), 0.2);
  EXPECT_DOUBLE_EQ(tracker.Update(0.1), -0.4);
  EXPECT_DOUBLE_EQ(tracker.d_eci(), -0.4);
  EXPECT_DOUBLE_EQ(tracker.eci(), 0.1);
  tracker.Reset();
  EXPECT_EQ(tracker.Update(0.9), 0.0);
}

}  // namespace
}  // namespace enavi::navstack
