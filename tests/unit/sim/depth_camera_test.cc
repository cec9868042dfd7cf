// Embree depth camera: geometry of z-depth, ranges, noise, ray modes, camera mount.

#include "workers/sim/depth_camera.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "tests/unit/sim/mesh_builders.h"
#include "workers/sim/embree_scene.h"

namespace enavi::sim {
namespace {

using navstack::CameraIntrinsics;
using navstack::DepthImage;
using testing::AddAlignedBox;
using testing::AddBox;
using testing::AddCylinder;

// Camera at (0, 0, 1) looking along world +x (body at the origin of the camera, level).
Eigen::Isometry3d CameraLookingAlongX(const Eigen::Vector3d& p_WC = {0, 0, 1}, double yaw = 0) {
  navstack::VehicleParams mount;
  mount.p_BC.setZero();
  Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
  X_WB.translation() = p_WC;
  X_WB.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).matrix();
  return CameraPoseInWorld(X_WB, mount);
}

// z-depth of pixel (u, v) on the plane {p : n.(p - p0) = 0}, in double precision.
double ExpectedDepthOnPlane(const CameraIntrinsics& k, const Eigen::Isometry3d& X_WC, int u,
                            int v, const Eigen::Vector3d& p0, const Eigen::Vector3d& n) {
  const Eigen::Vector3d d_W = X_WC.linear() * k.PixelRay(u, v);  // unit z in C
  return n.dot(p0 - X_WC.translation()) / n.dot(d_W);
}

//   top view            camera at (0,0,1) -> +x
//   C  ---->   |####|   wall face at x = 4, spanning y in [-5, 5], z in [-2, 4]
TEST(DepthCameraTest, FrontoParallelWallGivesZDepthNotRayLength) {
  worlds::TriangleMesh mesh;
  AddAlignedBox(&mesh, {4, -5, -2}, {5, 5, 4});
  const EmbreeScene scene(mesh);
  const DepthCamera camera(CameraIntrinsics::Default());
  DepthImage image;
  camera.Render(scene, CameraLookingAlongX(), &image);
  ASSERT_EQ(image.width, 640);
  ASSERT_EQ(image.height, 480);

  EXPECT_NEAR(image.at(320, 240), 4.0, 1e-3) << "centre pixel";
  // Off-centre: ray length would be 4 * |PixelRay| = ~4.6 m here; z-depth stays 4.
  const CameraIntrinsics k = CameraIntrinsics::Default();
  ASSERT_GT(k.PixelRay(60, 300).norm(), 1.1);
  EXPECT_NEAR(image.at(60, 300), 4.0, 1e-3) << "off-centre pixel must be z-depth";
}

// A wall turned 35 deg about z, so z-depth varies across the image.
TEST(DepthCameraTest, ObliqueWallMatchesRayPlaneGeometry) {
  const double yaw = 35.0 * M_PI / 180.0;
  Eigen::Isometry3d X_WBox = Eigen::Isometry3d::Identity();
  X_WBox.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).matrix();
  X_WBox.translation() = Eigen::Vector3d(5.0, 0.5, 1.0);
  worlds::TriangleMesh mesh;
  AddBox(&mesh, {0.5, 8.0, 6.0}, X_WBox);
  // The face the camera sees: box-local x = -0.5, normal -x_box.
  const Eigen::Vector3d n = -X_WBox.linear().col(0);
  const Eigen::Vector3d p0 = X_WBox * Eigen::Vector3d(-0.5, 0, 0);

  const CameraIntrinsics k = CameraIntrinsics::Default();
  const Eigen::Isometry3d X_WC = CameraLookingAlongX();
  DepthImage image;
  DepthCamera(k).Render(EmbreeScene(mesh), X_WC, &image);
  for (auto [u, v] : {std::pair{320, 240}, std::pair{40, 420}, std::pair{520, 60}}) {
    const double expected = ExpectedDepthOnPlane(k, X_WC, u, v, p0, n);
    ASSERT_GT(expected, k.min_range);
    ASSERT_LT(expected, k.max_range);
    EXPECT_NEAR(image.at(u, v), expected, 1e-3) << "pixel (" << u << ", " << v << ")";
  }
  EXPECT_GT(std::abs(image.at(40, 420) - image.at(520, 60)), 0.5) << "depth should vary";
}

// On a plane, 1/depth is affine in pixel coordinates, so a decimated pixel (one ray through the
// centre of its 2 x 2 block) sees the harmonic mean of the block's four full-resolution depths.
TEST(DepthCameraTest, DecimatedStreamSamplesTheCentreOfEachBlock) {
  Eigen::Isometry3d X_WBox = Eigen::Isometry3d::Identity();
  X_WBox.linear() = Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ()).matrix();
  X_WBox.translation() = Eigen::Vector3d(5.0, 0.5, 1.0);
  worlds::TriangleMesh mesh;
  AddBox(&mesh, {0.5, 12.0, 8.0}, X_WBox);
  const EmbreeScene scene(mesh);
  const CameraIntrinsics full = CameraIntrinsics::Default();
  const CameraIntrinsics stream = CameraIntrinsics::DefaultStream();
  ASSERT_EQ(stream.width, 320);
  ASSERT_EQ(stream.height, 240);
  DepthImage big, small;
  DepthCamera(full).Render(scene, CameraLookingAlongX(), &big);
  DepthCamera(stream).Render(scene, CameraLookingAlongX(), &small);
  ASSERT_EQ(small.width, 320);
  for (auto [u, v] : {std::pair{160, 120}, std::pair{20, 210}, std::pair{260, 30}, std::pair{0, 0}}) {
    double inv = 0;
    for (int du = 0; du < 2; ++du) {
      for (int dv = 0; dv < 2; ++dv) {
        ASSERT_TRUE(DepthImage::Valid(big.at(2 * u + du, 2 * v + dv)));
        inv += 0.25 / big.at(2 * u + du, 2 * v + dv);
      }
    }
    EXPECT_NEAR(small.at(u, v), 1.0 / inv, 1e-3) << "pixel (" << u << ", " << v << ")";
  }
  EXPECT_THROW(full.Decimated(0), std::invalid_argument);
  EXPECT_THROW(full.Decimated(481), std::invalid_argument);
}

TEST(DepthCameraTest, NothingWithinRangeIsNoReturn) {
  worlds::TriangleMesh mesh;
  AddAlignedBox(&mesh, {4, -1, 0}, {5, 1, 1.5});  // low, narrow block straight ahead
  AddAlignedBox(&mesh, {12, -50, -50}, {13, 50, 50});  // wall beyond max_range (10 m)
  DepthImage image;
  DepthCamera(CameraIntrinsics::Default()).Render(EmbreeScene(mesh), CameraLookingAlongX(),
                                                  &image);
  EXPECT_NEAR(image.at(320, 240), 4.0, 1e-3) << "block ahead is seen";
  EXPECT_EQ(image.at(320, 5), DepthImage::kNoReturn) << "above the block only the far wall";
  EXPECT_EQ(image.at(5, 240), DepthImage::kNoReturn) << "left of the block only the far wall";
}

TEST(DepthCameraTest, EmptySceneIsAllNoReturn) {
  DepthImage image;
  DepthCamera(CameraIntrinsics::Default())
      .Render(EmbreeScene(worlds::TriangleMesh{}), CameraLookingAlongX(), &image);
  for (float d : image.data) ASSERT_EQ(d, DepthImage::kNoReturn);
}

//   C  [] ---- |wall|      a small plate in front of the camera hides the wall behind it
TEST(DepthCameraTest, SurfaceNearerThanMinRangeHidesWhatIsBehind) {
  const CameraIntrinsics k = CameraIntrinsics::Default();  // min_range 0.2
  for (double plate_x : {0.1, 0.3}) {
    worlds::TriangleMesh mesh;
    AddAlignedBox(&mesh, {4, -3, -2}, {5, 3, 4});
    AddAlignedBox(&mesh, {plate_x, -0.02, 0.98}, {plate_x + 0.01, 0.02, 1.02});
    DepthImage image;
    DepthCamera(k).Render(EmbreeScene(mesh), CameraLookingAlongX(), &image);
    if (plate_x < k.min_range) {
      EXPECT_EQ(image.at(320, 240), DepthImage::kNoReturn)
          << "plate at " << plate_x << " m is inside min_range: no return, not the wall";
    } else {
      EXPECT_NEAR(image.at(320, 240), plate_x, 1e-3);
    }
    EXPECT_NEAR(image.at(100, 100), 4.0, 1e-3) << "wall seen around the plate";
  }
}

TEST(DepthCameraTest, RejectsUnusableIntrinsicsNamingTheField) {
  CameraIntrinsics k = CameraIntrinsics::Default();
  k.fx = 0;
  try {
    DepthCamera camera(k);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fx"), std::string::npos) << e.what();
  }
  k = CameraIntrinsics::Default();
  k.max_range = k.min_range;
  EXPECT_THROW(DepthCamera{k}, std::invalid_argument);
  EXPECT_THROW(DepthCamera(CameraIntrinsics::Default(), DepthNoise{-1.0}), std::invalid_argument);
}

TEST(DepthCameraTest, RejectsMeshWithIndexOutOfRange) {
  worlds::TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 3}};
  try {
    EmbreeScene scene(mesh);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("triangles[0][2]"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// Noise

DepthImage RenderWall(double distance, const DepthNoise& noise, std::uint64_t seed) {
  worlds::TriangleMesh mesh;
  AddAlignedBox(&mesh, {distance, -50, -50}, {distance + 1, 50, 50});
  DepthImage image;
  DepthCamera(CameraIntrinsics::Default(), noise).Render(EmbreeScene(mesh), CameraLookingAlongX(),
                                                         &image, seed);
  return image;
}

// The kernel class decides the flight (embree_scene.h), so it is read from CPUID by the compiler's
// builtins; the kernel's view of the same flags (/proc/cpuinfo) must agree.
TEST(EmbreeDeviceTest, RayKernelsNameTheClassTheCpuFlagsGive) {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  std::set<std::string> flags;
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("flags", 0) != 0) continue;
    std::istringstream words(line.substr(line.find(':') + 1));
    for (std::string w; words >> w;) flags.insert(w);
    break;
  }
  if (flags.empty()) GTEST_SKIP() << "no flags line in /proc/cpuinfo on this host";
  // /proc/cpuinfo calls LZCNT "abm" on both vendors. Some hypervisors' kernels leave that one
  // name out of the list while CPUID has the bit (seen on an AMD EPYC VM: avx2, fma, bmi1, bmi2
  // listed, no abm): there the kernel has no view of it to compare with.
  if (flags.count("avx2") && flags.count("fma") && flags.count("bmi1") && flags.count("bmi2") && !flags.count("abm"))
    GTEST_SKIP() << "this host's /proc/cpuinfo names no abm (LZCNT) flag at all: nothing to compare CPUID with";
  const bool avx2 = flags.count("avx2") && flags.count("fma") && flags.count("bmi1") &&
                    flags.count("bmi2") && flags.count("abm");
  EXPECT_EQ(RayKernels(), avx2 ? "avx2" : "sse-avx");
  EXPECT_EQ(EmbreeDevice::Get().Info().ray_kernels, RayKernels());
}

TEST(DepthNoiseTest, SameSeedSameImageDifferentSeedDifferentImage) {
  const DepthNoise noise{0.01};
  const DepthImage a = RenderWall(3.0, noise, 7);
  const DepthImage b = RenderWall(3.0, noise, 7);
  const DepthImage c = RenderWall(3.0, noise, 8);
  EXPECT_EQ(a.data, b.data) << "same seed must give a bit-identical image";
  std::size_t differing = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) differing += a.data[i] != c.data[i] ? 1 : 0;
  EXPECT_GT(differing, a.data.size() * 9 / 10) << "different seeds should change most pixels";
}

TEST(DepthNoiseTest, SigmaGrowsWithSquareOfDepth) {
  const DepthNoise noise{0.01};
  for (double d : {2.0, 6.0}) {
    const DepthImage noisy = RenderWall(d, noise, 42);
    double sum = 0, sum2 = 0;
    for (float z : noisy.data) {
      ASSERT_TRUE(DepthImage::Valid(z));
      sum += z - d;
      sum2 += (z - d) * (z - d);
    }
    const double n = static_cast<double>(noisy.data.size());
    const double mean = sum / n;
    const double sigma = std::sqrt(sum2 / n - mean * mean);
    const double expected = noise.k * d * d;
    EXPECT_NEAR(sigma, expected, 0.02 * expected) << "at " << d << " m";
    EXPECT_NEAR(mean, 0.0, 0.01 * expected) << "noise should be zero-mean at " << d << " m";
  }
}

TEST(DepthNoiseTest, OffByDefault) {
  const DepthImage image = RenderWall(3.0, DepthNoise{}, 123);
  for (float z : image.data) ASSERT_NEAR(z, 3.0f, 1e-4f);
}

// ---------------------------------------------------------------------------------------------
// Ray modes and threads

worlds::TriangleMesh BoxesAndCylinders() {
  worlds::TriangleMesh mesh;
  testing::AddGround(&mesh, 15.0, 1.0);
  AddAlignedBox(&mesh, {3, -2, 0}, {4, -0.5, 2});
  AddAlignedBox(&mesh, {6, 0.5, 0}, {6.5, 3, 3});
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = Eigen::Vector3d(8, -1, 1.5);
  X.linear() = Eigen::AngleAxisd(0.6, Eigen::Vector3d(0.2, 0.3, 1).normalized()).matrix();
  AddBox(&mesh, {0.7, 0.4, 1.2}, X);
  AddCylinder(&mesh, {2.5, 1.2, 0}, 0.3, 2.5, 24);
  AddCylinder(&mesh, {5, -0.2, 0}, 0.5, 1.2, 32);
  AddCylinder(&mesh, {9.5, 2.5, 0}, 0.8, 4.0, 12);
  return mesh;
}

// Embree's kernels for each instruction set build and traverse the BVH their own way and compute
// a hit's distance with the CPU's approximate reciprocal, whose last bits differ between CPU
// vendors (embree_scene.h). The image must depend on none of that, nor on how rays are handed
// over, or a flight would depend on the host it was flown on.
TEST(DepthCameraTest, EveryKernelAndRayModeRendersTheSameImageBitForBit) {
  const worlds::TriangleMesh mesh = BoxesAndCylinders();
  const worlds::TriangleMesh park = testing::MakeClutteredPark(3);
  // Odd size so packet tiles hang over the image edges.
  const CameraIntrinsics k = CameraIntrinsics::FromFov(203, 117, 87, 58, 0.2, 10);
  const std::vector<Eigen::Isometry3d> poses = {
      CameraLookingAlongX({0, 0.2, 1.3}, 0.1), CameraLookingAlongX({-20, 0, 1.5}, 0.0),
      CameraLookingAlongX({-5, 0.5, 1.2}, 0.7), CameraLookingAlongX({10, -0.8, 2.0}, -2.5)};
  struct World {
    const worlds::TriangleMesh* mesh;
    std::vector<Eigen::Isometry3d> poses;
  };
  const std::vector<World> worlds = {{&mesh, {poses[0]}}, {&park, {poses[1], poses[2], poses[3]}}};
  const EmbreeRayMode modes[] = {EmbreeRayMode::kSingle, EmbreeRayMode::kPacket4,
                                 EmbreeRayMode::kPacket8, EmbreeRayMode::kPacket16,
                                 EmbreeRayMode::kStream};
  std::vector<std::vector<float>> reference;  // per world and pose: SSE2 kernels, single rays
  for (const std::string isa : {"sse2", "sse4.2", "avx", "avx2", "avx512"}) {
    const EmbreeDevice device(isa);
    std::size_t image = 0;
    for (const World& w : worlds) {
      const EmbreeScene scene(*w.mesh, {}, device);
      for (const Eigen::Isometry3d& X_WC : w.poses) {
        for (EmbreeRayMode mode : modes) {
          DepthImage out;
          DepthCamera(k, {}, mode).Render(scene, X_WC, &out);
          if (reference.size() == image) {
            int valid = 0;
            for (float d : out.data) valid += DepthImage::Valid(d) ? 1 : 0;
            ASSERT_GT(valid, static_cast<int>(out.data.size()) / 2) << "scene should fill the view";
            reference.push_back(out.data);
            continue;
          }
          std::size_t differing = 0;
          for (std::size_t i = 0; i < out.data.size(); ++i) {
            differing += std::memcmp(&out.data[i], &reference[image][i], sizeof(float)) != 0;
          }
          EXPECT_EQ(differing, 0u) << isa << " kernels, " << ToString(mode) << ", image " << image
                                   << ": pixels that differ from SSE2's single rays";
        }
        ++image;
      }
    }
  }
}

TEST(DepthCameraTest, SharedSceneRendersIdenticallyFromTwoThreads) {
  const EmbreeScene scene(BoxesAndCylinders());
  const DepthCamera camera(CameraIntrinsics::Default());
  const Eigen::Isometry3d X_WC = CameraLookingAlongX({0, 0, 1.2});
  DepthImage expected;
  camera.Render(scene, X_WC, &expected);
  DepthImage a, b;
  std::thread ta([&] { for (int i = 0; i < 5; ++i) camera.Render(scene, X_WC, &a); });
  std::thread tb([&] { for (int i = 0; i < 5; ++i) camera.Render(scene, X_WC, &b); });
  ta.join();
  tb.join();
  EXPECT_EQ(a.data, expected.data);
  EXPECT_EQ(b.data, expected.data);
}

// ---------------------------------------------------------------------------------------------
// Mount

TEST(CameraPoseInWorldTest, PointStraightAheadOfBodyProjectsToImageCentre) {
  const navstack::VehicleParams vehicle;  // p_BC = (0.15, 0, 0.05)
  Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
  X_WB.translation() = Eigen::Vector3d(3, -2, 1.5);
  X_WB.linear() = (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitX()))
                      .matrix();
  const Eigen::Isometry3d X_WC = CameraPoseInWorld(X_WB, vehicle);
  const CameraIntrinsics k = CameraIntrinsics::Default();

  const Eigen::Vector3d p_W = X_WB * (vehicle.p_BC + Eigen::Vector3d(5, 0, 0));
  const Eigen::Vector3d p_C = X_WC.inverse() * p_W;
  EXPECT_NEAR(p_C.z(), 5.0, 1e-12) << "ahead of the body is along the optical axis";
  EXPECT_NEAR(k.fx * p_C.x() / p_C.z() + k.cx, k.cx, 1e-9);
  EXPECT_NEAR(k.fy * p_C.y() / p_C.z() + k.cy, k.cy, 1e-9);

  // Body left (+y) is image left (x < 0); body up (+z) is image up (y < 0).
  const Eigen::Vector3d left_C = X_WC.inverse() * (X_WB * (vehicle.p_BC + Eigen::Vector3d(5, 1, 0)));
  const Eigen::Vector3d up_C = X_WC.inverse() * (X_WB * (vehicle.p_BC + Eigen::Vector3d(5, 0, 1)));
  EXPECT_LT(left_C.x(), 0.0);
  EXPECT_LT(up_C.y(), 0.0);
  EXPECT_NEAR(X_WC.linear().determinant(), 1.0, 1e-12);
}

TEST(CameraPoseInWorldTest, RenderedPostAheadOfBodyIsInImageCentre) {
  const navstack::VehicleParams vehicle;
  Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
  X_WB.translation() = Eigen::Vector3d(1, 1, 1);
  X_WB.linear() = Eigen::AngleAxisd(-0.9, Eigen::Vector3d::UnitZ()).matrix();
  // A thin post 4 m straight ahead of the camera.
  const Eigen::Vector3d p_W = X_WB * (vehicle.p_BC + Eigen::Vector3d(4, 0, 0));
  worlds::TriangleMesh mesh;
  AddAlignedBox(&mesh, p_W - Eigen::Vector3d(0.05, 0.05, 2), p_W + Eigen::Vector3d(0.05, 0.05, 2));
  DepthImage image;
  DepthCamera(CameraIntrinsics::Default())
      .Render(EmbreeScene(mesh), CameraPoseInWorld(X_WB, vehicle), &image);
  EXPECT_NEAR(image.at(320, 240), 4.0, 0.08) << "post at the image centre";
  EXPECT_NEAR(image.at(319, 100), 4.0, 0.08) << "post is vertical in the image";
  EXPECT_EQ(image.at(100, 240), DepthImage::kNoReturn) << "nothing left of the post";
}

}  // namespace
}  // namespace enavi::sim
