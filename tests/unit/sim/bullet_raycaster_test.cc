// The Bullet reference renderer agrees with the Embree camera on the same triangles.

#include "workers/sim/bullet_raycaster.h"

#include <cmath>

#include <gtest/gtest.h>

#include "server/bench/raycast_bench.h"
#include "tests/unit/sim/mesh_builders.h"
#include "workers/sim/depth_camera.h"

namespace enavi::sim {
namespace {

using navstack::CameraIntrinsics;
using navstack::DepthImage;
using namespace bench;  // the raycast core of `enavi bench raycast` (server/bench)

//   top view, camera at the origin looking +x over a floor:
//        [box]    (cyl)      [tilted box]
//   C ->      (cyl)   [tall box]       (cyl)
worlds::TriangleMesh BoxesAndCylinders() {
  worlds::TriangleMesh mesh;
  testing::AddGround(&mesh, 15.0, 1.0);
  testing::AddAlignedBox(&mesh, {3, -2, 0}, {4, -0.5, 2});
  testing::AddAlignedBox(&mesh, {6, 0.5, 0}, {6.5, 3, 3});
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = Eigen::Vector3d(8, -1, 1.5);
  X.linear() = Eigen::AngleAxisd(0.6, Eigen::Vector3d(0.2, 0.3, 1).normalized()).matrix();
  testing::AddBox(&mesh, {0.7, 0.4, 1.2}, X);
  testing::AddCylinder(&mesh, {2.5, 1.2, 0}, 0.3, 2.5, 24);
  testing::AddCylinder(&mesh, {5, -0.2, 0}, 0.5, 1.2, 32);
  testing::AddCylinder(&mesh, {9.5, 2.5, 0}, 0.8, 4.0, 12);
  return mesh;
}

Eigen::Isometry3d Camera(const Eigen::Vector3d& p_WB, double yaw) {
  Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
  X_WB.translation() = p_WB;
  X_WB.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).matrix();
  return CameraPoseInWorld(X_WB, navstack::VehicleParams{});
}

// Both renderers shoot the same rays at the same triangles. They agree to well under 1 mm
// wherever the ray meets a surface away from a silhouette edge. Rays grazing a silhouette may
// differ: Bullet's triangle test is widened by a relative edge tolerance (~1e-4), so it can hit
// an edge that the exact (Embree) test passes by, and return the object instead of what lies
// behind it. Those pixels must stay a tiny fraction.
TEST(BulletRayCasterTest, AgreesWithEmbreeOnBoxesAndCylinders) {
  const worlds::TriangleMesh mesh = BoxesAndCylinders();
  const EmbreeScene scene(mesh);
  const CameraIntrinsics k = CameraIntrinsics::Default();
  const DepthCamera camera(k);
  BulletRayCaster bullet(std::make_shared<const StaticCollisionWorld>(mesh), k);
  const std::size_t pixels = static_cast<std::size_t>(k.width) * k.height;
  for (const Eigen::Isometry3d& X_WC :
       {Camera({0, 0, 1.2}, 0.0), Camera({1, 0.5, 0.8}, -0.3), Camera({-2, 1, 2.0}, 0.25)}) {
    DepthImage e, b;
    camera.Render(scene, X_WC, &e);
    bullet.Render(X_WC, &b);
    const DepthComparison c = CompareDepthImages(e, b);
    EXPECT_GT(c.both_hit, static_cast<std::int64_t>(pixels / 3)) << "the scene should fill the view";
    EXPECT_LT(c.max_diff_interior, 1e-3) << "z-depths differ by " << c.max_diff_interior << " m";
    EXPECT_LT(c.disagreeing + c.one_sided, static_cast<std::int64_t>(pixels / 10000))
        << c.disagreeing << " pixels differ by > 1 mm, " << c.one_sided << " hit in one only";
  }
}

TEST(CompareDepthImagesTest, SeparatesSilhouettePixelsFromInteriorOnes) {
  //  a: 5x5 image, a 3 m square in the middle of a 6 m background; b differs by 2 cm inside the
  //  square's centre pixel and by 3 m on one silhouette pixel.
  DepthImage a(5, 5), b(5, 5);
  for (int v = 0; v < 5; ++v) {
    for (int u = 0; u < 5; ++u) {
      const bool inner = u >= 1 && u <= 3 && v >= 1 && v <= 3;
      a.at(u, v) = b.at(u, v) = inner ? 3.0f : 6.0f;
    }
  }
  b.at(1, 1) = 6.0f;   // silhouette: b missed the square's corner
  b.at(2, 2) = 3.02f;  // interior: b is 2 cm off
  b.at(4, 4) = DepthImage::kNoReturn;
  const DepthComparison c = CompareDepthImages(a, b);
  EXPECT_EQ(c.both_hit, 24);
  EXPECT_EQ(c.one_sided, 1);
  EXPECT_EQ(c.disagreeing, 2);
  EXPECT_NEAR(c.max_diff, 3.0, 1e-6);
  EXPECT_NEAR(c.max_diff_interior, 0.02, 1e-6);
}

TEST(RaycastBenchTest, ReportsConsistentCountsAndAgreement) {
  RaycastBenchOptions options;
  options.intrinsics = CameraIntrinsics::FromFov(64, 48, 87, 58, 0.2, 10);
  options.frames = 6;
  options.bullet_frames = 3;
  options.compare_modes = {EmbreeRayMode::kSingle};
  const RaycastBenchResult r =
      RunRaycastBench(BoxesAndCylinders(), {-1, 0, 1.2}, {9, 0.5, 3.0}, options);
  EXPECT_EQ(r.triangles, BoxesAndCylinders().triangle_count());
  EXPECT_EQ(r.embree_rays, 64 * 48 * 6);
  EXPECT_EQ(r.bullet_rays, 64 * 48 * 3);
  EXPECT_EQ(r.both_hit_pixels + r.one_sided_pixels <= r.bullet_rays, true);
  EXPECT_GT(r.both_hit_pixels, r.bullet_rays / 2);
  EXPECT_LT(r.max_depth_disagreement_interior_m, 1e-3);
  EXPECT_LE(r.max_depth_disagreement_interior_m, r.max_depth_disagreement_m);
  EXPECT_GT(r.embree_valid_fraction, 0.5);
  ASSERT_EQ(r.modes.size(), 2u);
  EXPECT_EQ(r.modes[0].mode, "packet16");
  EXPECT_EQ(r.modes[1].mode, "single");

  const nlohmann::json j = ToJson(r);
  for (const char* key : {"embree_mrays_per_s_per_core", "bullet_mrays_per_s_per_core",
                          "speedup_vs_bullet", "max_depth_disagreement_m", "one_sided_pixels",
                          "frames", "embree_rays", "bullet_rays", "triangles"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["embree_rays"].get<std::int64_t>(), r.embree_rays);
}

TEST(RaycastBenchTest, RejectsBadArguments) {
  RaycastBenchOptions options;
  options.frames = 0;
  EXPECT_THROW(RunRaycastBench(BoxesAndCylinders(), {0, 0, 1}, {5, 0, 1}, options),
               std::invalid_argument);
  options = RaycastBenchOptions{};
  options.bullet_frames = options.frames + 1;
  EXPECT_THROW(RunRaycastBench(BoxesAndCylinders(), {0, 0, 1}, {5, 0, 1}, options),
               std::invalid_argument);
  EXPECT_THROW(RunRaycastBench(BoxesAndCylinders(), {0, 0, 1}, {0, 0, 3}, RaycastBenchOptions{}),
               std::invalid_argument)
      << "start and goal on one vertical give no viewing direction";
}

}  // namespace
}  // namespace enavi::sim
