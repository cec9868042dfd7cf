#include "navstack/perception/points.h"

#include <cmath>

#include <gtest/gtest.h>

#include "tests/unit/perception/synthetic_depth.h"

namespace enavi::navstack {
namespace {

using testing::BoxAt;
using testing::CameraPose;
using testing::RenderFrame;
using testing::Scene;

const CameraIntrinsics kCam = CameraIntrinsics::DefaultStream();  // what the stack reads

// A 4 x 3 m wall, face at x = d, seen from a camera at height 1 m looking along +x:
//   cam (0,0,1) ---- d ----> |wall|
Scene WallAt(double d) { return Scene{{BoxAt({d + 0.2, 0, 1}, {0.4, 4, 3})}, {}}; }

TEST(BackProjectTest, WallPointsLieOnTheWallInWorld) {
  const Eigen::Isometry3d X_WC = CameraPose({0, 0, 1});
  WorkCounts work;
  const ScanPoints scan = BackProject(RenderFrame(WallAt(3.05), kCam, X_WC), kCam, {}, &work);
  EXPECT_EQ(work.Get(WorkUnit::kBackProjection), 160 * 120) << "stride 2 on 320 x 240";
  EXPECT_TRUE(scan.origin_W.isApprox(Eigen::Vector3d(0, 0, 1)));
  ASSERT_GT(scan.hits_W.size(), 1000u);
  for (const Eigen::Vector3f& p : scan.hits_W) {
    EXPECT_NEAR(p.x(), 3.05, 1e-4);
    EXPECT_LE(std::abs(p.y()), 2.0 + 1e-4);
    EXPECT_LE(std::abs(p.z() - 1.0), 1.5 + 1e-4);
  }
  EXPECT_TRUE(scan.far_W.empty());
  EXPECT_EQ(scan.hits_W.size() + scan.no_return_W.size(), 160u * 120u)
      << "every sampled pixel sees the wall or nothing";
}

TEST(BackProjectTest, FollowsTheCameraPose) {
  // Camera yawed 90 deg to look along +y: the wall must come out ahead along +y.
  const Scene wall{{BoxAt({0, 3.25, 1}, {4, 0.4, 3})}, {}};
  const Eigen::Isometry3d X_WC = CameraPose({0, 0, 1}, M_PI / 2);
  const ScanPoints scan = BackProject(RenderFrame(wall, kCam, X_WC), kCam);
  ASSERT_FALSE(scan.hits_W.empty());
  for (const Eigen::Vector3f& p : scan.hits_W) EXPECT_NEAR(p.y(), 3.05, 1e-4);
}

TEST(BackProjectTest, RangeFilterSortsReturns) {
  const Eigen::Isometry3d X_WC = CameraPose({0, 0, 1});
  PerceptionOptions o;
  o.max_range = 5.0;
  // Beyond max_range: rays cut at z = max_range, no surface.
  const ScanPoints far = BackProject(RenderFrame(WallAt(6.0), kCam, X_WC), kCam, o);
  EXPECT_TRUE(far.hits_W.empty());
  ASSERT_FALSE(far.far_W.empty());
  for (const Eigen::Vector3f& p : far.far_W) EXPECT_NEAR(p.x(), 5.0, 1e-4);
  // Nearer than min_range: dropped altogether.
  o.min_range = 1.0;
  const ScanPoints near = BackProject(RenderFrame(WallAt(0.5), kCam, X_WC), kCam, o);
  EXPECT_TRUE(near.hits_W.empty());
  EXPECT_TRUE(near.far_W.empty());
  EXPECT_TRUE(near.no_return_W.empty()) << "the 4 x 3 m wall at 0.5 m fills the view";
  // Nothing in view: every sample is a no-return at z = max_range.
  const ScanPoints empty = BackProject(RenderFrame(Scene{}, kCam, X_WC), kCam, o);
  EXPECT_EQ(empty.no_return_W.size(), 160u * 120u);
  for (const Eigen::Vector3f& p : empty.no_return_W) EXPECT_NEAR(p.x(), 5.0, 1e-4);
}

TEST(BackProjectTest, StrideSetsTheSampleCount) {
  const DepthFrame frame = RenderFrame(WallAt(3.0), kCam, CameraPose({0, 0, 1}));
  for (int stride : {1, 3, 7}) {
    PerceptionOptions o;
    o.stride = stride;
    WorkCounts work;
    BackProject(frame, kCam, o, &work);
    EXPECT_EQ(work.Get(WorkUnit::kBackProjection), ((kCam.width + stride - 1) / stride) * ((kCam.height + stride - 1) / stride));
  }
}

TEST(BackProjectTest, RejectsBadOptions) {
  const DepthFrame frame = RenderFrame(WallAt(3.0), kCam, CameraPose({0, 0, 1}));
  PerceptionOptions o;
  o.stride = 0;
  try {
    BackProject(frame, kCam, o);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("PerceptionOptions.stride"), std::string::npos) << e.what();
  }
  o = {};
  o.min_range = 6.0;  // above max_range
  EXPECT_THROW(BackProject(frame, kCam, o), std::invalid_argument);
  CameraIntrinsics wrong = kCam;
  wrong.width = kCam.width / 2;
  EXPECT_THROW(BackProject(frame, wrong), std::logic_error);
}

}  // namespace
}  // namespace enavi::navstack
