// The controller feels the wind: QuadrotorSim under the flight controller holding a hover point
// in light and severe Dryden turbulence (X500 body drag on) wanders further than in still air.

#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "navstack/control/controller.h"
#include "tests/unit/sim/mesh_builders.h"
#include "workers/sim/quadrotor.h"
#include "workers/sim/wind.h"

namespace enavi::sim {
namespace {

// RMS distance from the hover point over 20 s at 2 m, control at 200 Hz, physics at 1 kHz.
double HoverRmsError(Turbulence turbulence, std::uint64_t seed) {
  QuadrotorOptions options;
  options.body_drag_cda = kX500BodyDragCdA;
  const Eigen::Vector3d p0(0.0, 0.0, 2.0);
  QuadrotorSim quad(std::make_shared<const StaticCollisionWorld>(worlds::TriangleMesh{}), options,
                    p0, 0.0);
  navstack::Controller controller(options.vehicle);
  api::WindSpec air;
  air.turbulence = TurbulenceName(turbulence);
  WindField wind(air, options.dt, seed);
  navstack::TrajectorySample ref;
  ref.p = p0;
  double sum2 = 0.0;
  const int steps = 20000;
  for (int k = 0; k < steps; ++k) {
    const navstack::VehicleState s = quad.State();
    if (k % 5 == 0) quad.SetCommand(controller.Update(s, ref));
    sum2 += (s.p_WB - p0).squaredNorm();
    quad.SetAirVelocity(wind.Step(s.p_WB.z(), s.v_WB));
    quad.Step();
  }
  return std::sqrt(sum2 / steps);
}

TEST(WindHover, TrackingErrorGrowsFromStillAirToLightToSevere) {
  const double none = HoverRmsError(Turbulence::kNone, 1);
  const double light = HoverRmsError(Turbulence::kLight, 1);
  const double severe = HoverRmsError(Turbulence::kSevere, 1);
  std::printf("hover rms error: none %.4f m, light %.4f m, severe %.4f m\n", none, light, severe);
  EXPECT_LT(none, 1e-3);
  EXPECT_GT(light, 10.0 * none);
  EXPECT_GT(severe, 2.0 * light);
}

}  // namespace
}  // namespace enavi::sim
