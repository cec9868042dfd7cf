// The navigation stack reads the 640x480 sensor decimated 2 x 2 (320x240, CameraIntrinsics::
// DefaultStream) so that rendering stays a small part of an episode's CPU. This checks that the
// eci it computes from that stream (min_pixels 12) is the eci of the full frame (min_pixels 50,
// the same solid angle), on views of the paper's five scenarios.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "navstack/eci/eci.h"
#include "workers/sim/depth_camera.h"
#include "workers/sim/episode.h"
#include "worlds/resolve.h"

namespace enavi::integration {
namespace {

using navstack::CameraIntrinsics;

class EciStreamTest : public ::testing::TestWithParam<std::string> {};

TEST_P(EciStreamTest, DecimatedStreamGivesTheFullFramesEci) {
  worlds::WorldRequest request;
  request.world = GetParam();
  request.seed = 1;
  const auto prepared = sim::PrepareWorld(worlds::ResolveWorld(request));
  const worlds::World& world = prepared->world;

  const CameraIntrinsics full = CameraIntrinsics::Default();
  const CameraIntrinsics stream = CameraIntrinsics::DefaultStream();
  navstack::EciOptions full_options;
  full_options.min_pixels = 50;
  const navstack::EciOptions stream_options;  // the stack's default
  ASSERT_EQ(stream_options.min_pixels, 12);

  // Views from random points of the start-goal corridor at flight height, heading roughly to the
  // goal, velocity within 25 deg of the optical axis; views from inside an obstacle are skipped.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> along(0.0, 1.0), side(-3.0, 3.0), dyaw(-0.6, 0.6), dvel(-0.45, 0.45);
  const Eigen::Vector3d line = world.goal - world.start;
  const double heading = std::atan2(line.y(), line.x());
  const navstack::VehicleParams vehicle;
  navstack::DepthImage a, b;
  int views = 0;
  double max_diff = 0, sum_diff = 0, eci_max = 0;
  for (int i = 0; i < 400 && views < 60; ++i) {
    Eigen::Vector3d p = world.start + along(rng) * line;
    p += side(rng) * Eigen::Vector3d(-std::sin(heading), std::cos(heading), 0);
    Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
    X_WB.linear() = Eigen::AngleAxisd(heading + dyaw(rng), Eigen::Vector3d::UnitZ()).matrix();
    X_WB.translation() = p;
    const Eigen::Isometry3d X_WC = sim::CameraPoseInWorld(X_WB, vehicle);
    const Eigen::Vector3d v_C =
        2.0 * Eigen::AngleAxisd(dvel(rng), Eigen::Vector3d::UnitY()).matrix() * Eigen::Vector3d::UnitZ();
    sim::DepthCamera(full).Render(*prepared->scene, X_WC, &a);
    const navstack::EciResult e_full = navstack::ComputeEci(a, full, v_C, full_options);
    if (e_full.status == navstack::EciResult::Status::kOk && e_full.d0 <= 0.5) continue;  // inside
    sim::DepthCamera(stream).Render(*prepared->scene, X_WC, &b);
    const navstack::EciResult e_stream = navstack::ComputeEci(b, stream, v_C, stream_options);
    const double diff = std::abs(e_stream.eci - e_full.eci);
    EXPECT_LE(diff, 0.1) << GetParam() << " view " << i << ": full " << e_full.eci << ", stream " << e_stream.eci;
    max_diff = std::max(max_diff, diff);
    sum_diff += diff;
    eci_max = std::max(eci_max, e_full.eci);
    ++views;
  }
  ASSERT_GE(views, 30) << "too few views outside obstacles";
  EXPECT_GT(eci_max, 0.3) << "views should include cluttered ones";
  EXPECT_LE(sum_diff / views, 0.01);
  std::printf("%s: %d views, |eci(stream) - eci(full)| mean %.4f max %.4f (eci up to %.2f)\n",
              GetParam().c_str(), views, sum_diff / views, max_diff, eci_max);
}

INSTANTIATE_TEST_SUITE_P(PaperScenarios, EciStreamTest, ::testing::Values("s1", "s2", "s3", "s4", "s5"));

}  // namespace
}  // namespace enavi::integration
