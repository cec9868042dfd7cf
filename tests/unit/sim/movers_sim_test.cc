// Movers in the simulation: the depth camera sees them where they are at each frame (MovingScene)
// and the vehicle collides with them as kinematic bodies, told apart from the static world.

#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "tests/unit/sim/mesh_builders.h"
#include "workers/sim/depth_camera.h"
#include "workers/sim/embree_scene.h"
#include "workers/sim/moving_scene.h"
#include "workers/sim/quadrotor.h"
#include "workers/sim/static_world.h"

namespace enavi::sim {
namespace {

using navstack::CameraIntrinsics;
using navstack::DepthImage;

Eigen::Isometry3d At(double x, double y, double z, double yaw = 0.0) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).matrix();
  X.translation() = Eigen::Vector3d(x, y, z);
  return X;
}

// Camera at (0, 0, 1) looking along +x.
Eigen::Isometry3d Camera() {
  navstack::VehicleParams mount;
  mount.p_BC.setZero();
  return CameraPoseInWorld(At(0, 0, 1), mount);
}

// A 1 m cube (in its own frame, centred on its origin) as a mover's shape.
worlds::TriangleMesh Cube() {
  worlds::TriangleMesh m;
  testing::AddBox(&m, {0.5, 0.5, 0.5});
  return m;
}

//   top view:  C (0,0,1) ---->  [mover]  ...  |wall| face x = 8
TEST(MovingSceneTest, TheCameraSeesAMoverWhereItWasLastPosed) {
  worlds::TriangleMesh wall;
  testing::AddAlignedBox(&wall, {8, -20, -5}, {9, 20, 5});
  const auto world = std::make_shared<const EmbreeScene>(wall);
  MovingScene scene(world, {Cube()});
  const DepthCamera camera(CameraIntrinsics::Default());
  DepthImage image;

  scene.SetPoses({At(4, 0, 1)});
  camera.Render(scene, Camera(), &image);
  EXPECT_NEAR(image.at(320, 240), 3.5, 1e-4) << "the cube's near face";

  scene.SetPoses({At(4, 30, 1)});
  camera.Render(scene, Camera(), &image);
  EXPECT_NEAR(image.at(320, 240), 8.0, 1e-4) << "the mover walked off: the wall behind";
  // With the mover out of view, the image is the static world's, pixel for pixel.
  DepthImage alone;
  camera.Render(*world, Camera(), &alone);
  EXPECT_EQ(image.data, alone.data);

  // Turned by 45 degrees about z, its near edge is sqrt(2) / 2 m from its centre.
  scene.SetPoses({At(4, 0, 1, M_PI / 4)});
  camera.Render(scene, Camera(), &image);
  EXPECT_NEAR(image.at(320, 240), 4.0 - std::sqrt(0.5), 0.01) << "(the pixel is half a pixel off the edge)";
}

// The movers are traced over the static world's frame: against open sky, behind a wall and
// nearer than the camera's minimum range, each pixel is what a surface there would give.
TEST(MovingSceneTest, AMoverIsSeenAgainstTheSkyHiddenBehindAWallAndBlindsTheCameraUpClose) {
  worlds::TriangleMesh wall;  // a wall left of the view's centre only: open sky at the centre
  testing::AddAlignedBox(&wall, {6, 1, -5}, {7, 20, 5});
  const auto world = std::make_shared<const EmbreeScene>(wall);
  MovingScene scene(world, {Cube()});
  const DepthCamera camera(CameraIntrinsics::Default());
  const CameraIntrinsics k = CameraIntrinsics::Default();
  DepthImage image;

  scene.SetPoses({At(4, 0, 1)});
  camera.Render(scene, Camera(), &image);
  EXPECT_NEAR(image.at(320, 240), 3.5, 1e-4) << "the cube against open sky";

  scene.SetPoses({At(10, 3, 1)});  // behind the wall, in the wall's part of the view
  camera.Render(scene, Camera(), &image);
  DepthImage alone;
  camera.Render(*world, Camera(), &alone);
  EXPECT_EQ(image.data, alone.data) << "a mover behind the wall changes no pixel";

  scene.SetPoses({At(0.5 + 0.5 * k.min_range, 0, 1)});  // near face at min_range / 2
  camera.Render(scene, Camera(), &image);
  EXPECT_EQ(image.at(320, 240), DepthImage::kNoReturn) << "too near to measure, and it hides the sky";
}

TEST(MovingSceneTest, EveryRayModeSeesTheSameImage) {
  worlds::TriangleMesh park = testing::MakeClutteredPark(3, 120);
  const auto world = std::make_shared<const EmbreeScene>(park);
  worlds::TriangleMesh person;
  testing::AddCylinder(&person, {0, 0, 0}, 0.25, 1.75);
  MovingScene scene(world, {Cube(), person});
  scene.SetPoses({At(3, 0.4, 1.2), At(2, -0.5, 0, 0.3)});
  DepthImage reference;
  DepthCamera(CameraIntrinsics::Default(), {}, EmbreeRayMode::kSingle).Render(scene, Camera(), &reference);
  for (const EmbreeRayMode mode :
       {EmbreeRayMode::kPacket4, EmbreeRayMode::kPacket8, EmbreeRayMode::kPacket16, EmbreeRayMode::kStream}) {
    DepthImage image;
    DepthCamera(CameraIntrinsics::Default(), {}, mode).Render(scene, Camera(), &image);
    EXPECT_EQ(image.data, reference.data) << ToString(mode);
  }
}

TEST(MovingSceneTest, RefusesAPoseCountThatIsNotTheMovers) {
  worlds::TriangleMesh wall;
  testing::AddAlignedBox(&wall, {8, -20, -5}, {9, 20, 5});
  MovingScene scene(std::make_shared<const EmbreeScene>(wall), {Cube()});
  EXPECT_THROW(scene.SetPoses({}), std::invalid_argument);
}

//   top view:  vehicle hovering at (0,0,1.5);  cube sliding in from x = 3 at 2 m/s
TEST(KinematicMoverTest, AMoverThatHitsTheVehicleIsTheContactsBody) {
  worlds::TriangleMesh ground;
  testing::AddGround(&ground, 20.0, 2.0);
  QuadrotorSim sim(std::make_shared<const StaticCollisionWorld>(ground), QuadrotorOptions{}, {0, 0, 1.5}, 0.0);
  const auto cube = std::make_shared<const StaticCollisionWorld>(Cube());
  const int far = sim.AddKinematicBody(cube, At(0, 15, 1.5));
  const int near = sim.AddKinematicBody(cube, At(3, 0, 1.5));
  EXPECT_EQ(far, 0);
  EXPECT_EQ(near, 1);
  while (!sim.contact() && sim.time() < 3.0) {
    sim.SetKinematicPose(near, At(3 - 2.0 * sim.time(), 0, 1.5));
    sim.Step();
  }
  ASSERT_TRUE(sim.contact().has_value());
  EXPECT_EQ(sim.contact()->body, near);
  // The cube's face (x - 0.5) meets the vehicle's rim (about 0.3 m) after ~1.1 s.
  const double reach = std::sqrt(std::pow(QuadrotorOptions{}.vehicle.collision_radius, 2) - std::pow(0.06, 2));
  EXPECT_NEAR(sim.contact()->t, (3 - 0.5 - reach) / 2.0, 0.02);
  EXPECT_NEAR(sim.contact()->point_W.x(), reach, 0.03);
}

TEST(KinematicMoverTest, TheGroundIsTheStaticWorld) {
  worlds::TriangleMesh ground;
  testing::AddGround(&ground, 20.0, 2.0);
  QuadrotorOptions options;
  options.start_at_hover = false;
  QuadrotorSim sim(std::make_shared<const StaticCollisionWorld>(ground), options, {0, 0, 1.0}, 0.0);
  sim.AddKinematicBody(std::make_shared<const StaticCollisionWorld>(Cube()), At(5, 5, 1));
  while (!sim.contact() && sim.time() < 3.0) sim.Step();
  ASSERT_TRUE(sim.contact().has_value());
  EXPECT_EQ(sim.contact()->body, -1);
}

}  // namespace
}  // namespace enavi::sim
