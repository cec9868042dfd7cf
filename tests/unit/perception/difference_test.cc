#include "navstack/perception/difference.h"

#include <gtest/gtest.h>

#include "tests/unit/perception/synthetic_depth.h"

namespace enavi::navstack {
namespace {

using testing::BoxAt;
using testing::CameraPose;
using testing::RenderFrame;
using testing::Scene;

const CameraIntrinsics kCam = CameraIntrinsics::DefaultStream();  // what the stack reads

// Ground, a wall on the left, pillars ahead: depth edges and a grazing ground plane, where a
// careless warp would report change.
Scene Street() {
  Scene s;
  s.planes.push_back({Eigen::Vector3d::UnitZ(), 0.0});
  s.boxes.push_back(BoxAt({6, 3, 2}, {8, 0.5, 4}));
  s.boxes.push_back(BoxAt({4, -1, 1.5}, {0.4, 0.4, 3}));
  s.boxes.push_back(BoxAt({7, 0.5, 1.5}, {0.6, 0.6, 3}));
  s.boxes.push_back(BoxAt({9, -2, 2}, {1, 1, 4}));
  return s;
}

// Two poses 1/10 s apart at 3 m/s with a little yaw and climb.
const Eigen::Isometry3d kBefore = CameraPose({0, 0, 1.5}, 0.0);
const Eigen::Isometry3d kAfter = CameraPose({0.3, 0.05, 1.55}, 0.06);

TEST(DifferenceTest, StaticSceneUnderEgoMotionDoesNotTrigger) {
  WorkCounts work;
  const DifferenceResult r =
      DetectDifference(RenderFrame(Street(), kCam, kBefore), RenderFrame(Street(), kCam, kAfter),
                       kCam, {}, &work);
  EXPECT_FALSE(r.trigger) << "changed fraction " << r.changed_fraction;
  EXPECT_LT(r.changed_fraction, 0.001);
  EXPECT_GT(r.compared, r.sampled * 8 / 10) << "most of the view has a prediction";
  EXPECT_EQ(r.sampled, 160 * 120);
  EXPECT_EQ(work.Get(WorkUnit::kWarpPixel), 2 * 160 * 120);
}

TEST(DifferenceTest, IdenticalFramesDoNotTrigger) {
  const DepthFrame f = RenderFrame(Street(), kCam, kBefore);
  const DifferenceResult r = DetectDifference(f, f, kCam);
  EXPECT_EQ(r.changed, 0);
  EXPECT_FALSE(r.trigger);
}

TEST(DifferenceTest, NewBoxAheadTriggers) {
  Scene changed = Street();
  changed.boxes.push_back(BoxAt({3.0, 0.2, 1.5}, {0.6, 0.6, 0.6}));  // appears 2.7 m ahead
  const DifferenceResult r =
      DetectDifference(RenderFrame(Street(), kCam, kBefore), RenderFrame(changed, kCam, kAfter), kCam);
  EXPECT_TRUE(r.trigger) << "changed fraction " << r.changed_fraction;
  EXPECT_GT(r.changed_fraction, 0.01);
}

TEST(DifferenceTest, NewBoxInFreeSkyTriggers) {
  // Where the previous frame saw nothing at all.
  Scene changed = Street();
  changed.boxes.push_back(BoxAt({3.5, 0.0, 3.0}, {0.5, 0.5, 0.5}));
  const DifferenceResult r =
      DetectDifference(RenderFrame(Street(), kCam, kBefore), RenderFrame(changed, kCam, kAfter), kCam);
  EXPECT_TRUE(r.trigger) << "changed fraction " << r.changed_fraction;
}

TEST(DifferenceTest, FarOrVanishingChangesDoNotTrigger) {
  // A box beyond relevant_depth (5 m) appearing, and a pillar disappearing: neither is a
  // threat to the current plan.
  Scene far = Street();
  far.boxes.push_back(BoxAt({8.5, 1.5, 1.0}, {0.6, 0.6, 0.6}));
  Scene vanished = Street();
  vanished.boxes.erase(vanished.boxes.begin() + 1);
  const DepthFrame before = RenderFrame(Street(), kCam, kBefore);
  EXPECT_FALSE(DetectDifference(before, RenderFrame(far, kCam, kAfter), kCam).trigger);
  EXPECT_FALSE(DetectDifference(before, RenderFrame(vanished, kCam, kAfter), kCam).trigger);
}

TEST(DifferenceTest, RejectsBadOptions) {
  const DepthFrame f = RenderFrame(Street(), kCam, kBefore);
  DifferenceOptions o;
  o.trigger_fraction = 0.0;
  EXPECT_THROW(DetectDifference(f, f, kCam, o), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::navstack
