// Quadrotor dynamics and contacts in the per-episode Bullet world.

#include "workers/sim/quadrotor.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <thread>

#include <gtest/gtest.h>

#include "tests/unit/sim/mesh_builders.h"

namespace enavi::sim {
namespace {

using navstack::RotorCommand;
using navstack::VehicleParams;
using navstack::VehicleState;

std::shared_ptr<const StaticCollisionWorld> EmptyWorld() {
  return std::make_shared<const StaticCollisionWorld>(worlds::TriangleMesh{});
}

std::shared_ptr<const StaticCollisionWorld> GroundWorld() {
  worlds::TriangleMesh mesh;
  testing::AddGround(&mesh, 20.0, 2.0);
  return std::make_shared<const StaticCollisionWorld>(mesh);
}

// Geometric attitude + position PD controller with the X-frame mixer from VehicleParams,
// written here independently of the simulator (run at 200 Hz like the farm's controller).
class TestController {
 public:
  explicit TestController(const VehicleParams& p) : p_(p) {
    const auto r = p.RotorPositions();
    // [T, tau_x, tau_y, tau_z] = M * [T_0 .. T_3]
    for (int i = 0; i < 4; ++i) {
      mix_(0, i) = 1.0;
      mix_(1, i) = r[i].y();
      mix_(2, i) = -r[i].x();
      mix_(3, i) = -VehicleParams::kSpin[i] * p.moment_coeff;
    }
    unmix_ = mix_.inverse();
  }

  RotorCommand Compute(const VehicleState& s, const Eigen::Vector3d& p_ref,
                       const Eigen::Vector3d& v_ref, double yaw_ref) const {
    const double g = p_.Gravity();
    const Eigen::Vector3d a_des =
        4.0 * (p_ref - s.p_WB) + 3.5 * (v_ref - s.v_WB) + Eigen::Vector3d(0, 0, g);
    const Eigen::Matrix3d R = s.q_WB.toRotationMatrix();
    const Eigen::Vector3d b3 = a_des.normalized();
    const Eigen::Vector3d b1c(std::cos(yaw_ref), std::sin(yaw_ref), 0);
    const Eigen::Vector3d b2 = b3.cross(b1c).normalized();
    Eigen::Matrix3d R_des;
    R_des << b2.cross(b3), b2, b3;
    const Eigen::Matrix3d E = 0.5 * (R_des.transpose() * R - R.transpose() * R_des);
    const Eigen::Vector3d e_R(E(2, 1), E(0, 2), E(1, 0));
    const Eigen::Vector3d J = p_.inertia_diag;
    const Eigen::Vector3d tau = -J.cwiseProduct(Eigen::Vector3d(120, 120, 4).cwiseProduct(e_R) +
                                                Eigen::Vector3d(20, 20, 4).cwiseProduct(s.w_WB_B)) +
                                s.w_WB_B.cross(J.cwiseProduct(s.w_WB_B));
    const double thrust = p_.mass * a_des.dot(R.col(2));
    const Eigen::Vector4d T = unmix_ * Eigen::Vector4d(thrust, tau.x(), tau.y(), tau.z());
    RotorCommand cmd;
    for (int i = 0; i < 4; ++i) cmd.omega[i] = std::sqrt(std::max(T[i], 0.0) / p_.thrust_coeff);
    return cmd;
  }

 private:
  VehicleParams p_;
  Eigen::Matrix4d mix_, unmix_;
};

double Yaw(const Eigen::Quaterniond& q) {
  const Eigen::Matrix3d R = q.toRotationMatrix();
  return std::atan2(R(1, 0), R(0, 0));
}

TEST(QuadrotorSimTest, FreeFallMatchesClosedForm) {
  QuadrotorOptions options;
  options.vehicle.linear_drag.setZero();
  options.start_at_hover = false;  // rotors at rest, command 0
  const double z0 = 5.0;
  QuadrotorSim sim(EmptyWorld(), options, {1, 2, z0}, 0.3);
  for (int i = 0; i < 1000; ++i) sim.Step();
  const VehicleState s = sim.State();
  const double g = options.vehicle.Gravity();
  EXPECT_DOUBLE_EQ(s.t, 1.0);
  EXPECT_NEAR(s.p_WB.z(), z0 - 0.5 * g * s.t * s.t, 1e-3);
  EXPECT_NEAR(s.p_WB.x(), 1.0, 1e-6);
  EXPECT_NEAR(s.p_WB.y(), 2.0, 1e-6);
  EXPECT_NEAR(s.v_WB.z(), -g * s.t, 1e-4);
  EXPECT_NEAR(s.a_WB.z(), -g, 1e-3);
  EXPECT_FALSE(sim.contact().has_value());
}

TEST(QuadrotorSimTest, HoverCommandAtStartHoldsStill) {
  QuadrotorSim sim(EmptyWorld(), QuadrotorOptions{}, {0, 0, 2}, 0.0);
  const double hover = HoverRotorSpeed(QuadrotorOptions{}.vehicle);
  for (double w : sim.rotor_speeds()) EXPECT_DOUBLE_EQ(w, hover);
  for (int i = 0; i < 1000; ++i) sim.Step();  // the initial command is hover
  const VehicleState s = sim.State();
  EXPECT_LT((s.p_WB - Eigen::Vector3d(0, 0, 2)).norm(), 1e-3) << "drifted: " << s.p_WB.transpose();
  EXPECT_LT(s.v_WB.norm(), 1e-3);
}

TEST(QuadrotorSimTest, WindPushesThroughRotorAndBodyDragAgainstTheRelativeAirspeed) {
  // Level at hover in a 5 m/s wind along +x: the only horizontal force at first is the drag
  // k_x * 5 + 0.5 rho CdA_x 5^2 downwind.
  QuadrotorOptions options;
  options.body_drag_cda = kX500BodyDragCdA;
  QuadrotorSim sim(EmptyWorld(), options, {0, 0, 2}, 0.0);
  sim.SetAirVelocity({5.0, 0.0, 0.0});
  for (int i = 0; i < 10; ++i) sim.Step();
  const VehicleParams& v = options.vehicle;
  const double expected =
      (v.linear_drag.x() * 5.0 + 0.5 * options.air_density * kX500BodyDragCdA.x() * 25.0) / v.mass;
  EXPECT_NEAR(sim.State().a_WB.x(), expected, 0.01 * expected);
  EXPECT_NEAR(sim.State().a_WB.y(), 0.0, 1e-9);
  // Moving with the air: no drag at all.
  QuadrotorSim still(EmptyWorld(), options, {0, 0, 2}, 0.0);
  for (int i = 0; i < 10; ++i) still.Step();
  EXPECT_EQ(still.State().a_WB.x(), 0.0);
  EXPECT_THROW(sim.SetAirVelocity({std::nan(""), 0.0, 0.0}), std::invalid_argument);
}

TEST(QuadrotorSimTest, MotorFollowsFirstOrderLag) {
  QuadrotorOptions options;
  QuadrotorSim sim(EmptyWorld(), options, {0, 0, 50}, 0.0);
  const double w0 = sim.rotor_speeds()[0];
  const VehicleParams& p = options.vehicle;
  RotorCommand cmd;
  cmd.omega = {p.omega_max, 0.0, w0, 2.0 * p.omega_max};  // up, down, hold, clamped
  sim.SetCommand(cmd);
  for (int i = 0; i < 20; ++i) sim.Step();
  const double t = sim.time();
  EXPECT_NEAR(sim.rotor_speeds()[0],
              p.omega_max - (p.omega_max - w0) * std::exp(-t / p.motor_time_constant_up), 1e-6);
  EXPECT_NEAR(sim.rotor_speeds()[1], w0 * std::exp(-t / p.motor_time_constant_down), 1e-6);
  EXPECT_DOUBLE_EQ(sim.rotor_speeds()[2], w0);
  EXPECT_NEAR(sim.rotor_speeds()[3], sim.rotor_speeds()[0], 1e-9) << "command clamped to omega_max";
}

TEST(QuadrotorSimTest, SpinImbalanceYawsTheRightWay) {
  // Speeding up the counter-clockwise rotors (kSpin = +1) twists the body clockwise (-z).
  QuadrotorSim sim(EmptyWorld(), QuadrotorOptions{}, {0, 0, 50}, 0.0);
  RotorCommand cmd;
  const double hover = sim.rotor_speeds()[0];
  for (int i = 0; i < 4; ++i) {
    cmd.omega[i] = hover * (VehicleParams::kSpin[i] > 0 ? 1.05 : 0.95);
  }
  sim.SetCommand(cmd);
  for (int i = 0; i < 200; ++i) sim.Step();
  EXPECT_LT(sim.State().w_WB_B.z(), -0.1);
  EXPECT_NEAR(sim.State().w_WB_B.x(), 0.0, 1e-3);
  EXPECT_NEAR(sim.State().w_WB_B.y(), 0.0, 1e-3);
}

TEST(QuadrotorSimTest, PdLoopHoldsAltitudeAndTurnsToYawForTenSeconds) {
  const QuadrotorOptions options;
  const Eigen::Vector3d p_ref(0, 0, 2);
  QuadrotorSim sim(GroundWorld(), options, p_ref, 0.4);  // must turn from 0.4 rad to 0
  const TestController controller(options.vehicle);
  double max_dz = 0.0, max_dxy = 0.0;
  for (int i = 0; i < 10000; ++i) {
    if (i % 5 == 0) sim.SetCommand(controller.Compute(sim.State(), p_ref, {0, 0, 0}, 0.0));
    sim.Step();
    const VehicleState s = sim.State();
    max_dz = std::max(max_dz, std::abs(s.p_WB.z() - p_ref.z()));
    max_dxy = std::max(max_dxy, (s.p_WB - p_ref).head<2>().norm());
  }
  const VehicleState s = sim.State();
  EXPECT_NEAR(s.t, 10.0, 1e-9);
  EXPECT_LT(max_dz, 0.03) << "altitude not held";
  EXPECT_LT(max_dxy, 0.05) << "position not held";
  EXPECT_NEAR(Yaw(s.q_WB), 0.0, 0.01) << "did not turn to the commanded yaw";
  EXPECT_FALSE(sim.contact().has_value()) << "hovering 2 m up must not touch the ground";
}

//   top view:  start (0,0,1.5) --- 2 m/s ---> |wall| face x = 3
TEST(QuadrotorSimTest, FlyingIntoAWallIsACollisionOnTheWallFace) {
  worlds::TriangleMesh mesh;
  testing::AddGround(&mesh, 20.0, 2.0);
  testing::AddAlignedBox(&mesh, {3.0, -5, 0}, {3.2, 5, 5});
  const QuadrotorOptions options;
  QuadrotorSim sim(std::make_shared<const StaticCollisionWorld>(mesh), options, {0, 0, 1.5}, 0.0);
  const TestController controller(options.vehicle);
  const double speed = 2.0;
  std::vector<VehicleState> history{sim.State()};
  while (!sim.contact() && sim.time() < 5.0) {
    if (sim.step_count() % 5 == 0) {
      const double t = sim.time();
      sim.SetCommand(controller.Compute(sim.State(), {speed * t, 0, 1.5}, {speed, 0, 0}, 0.0));
    }
    sim.Step();
    history.push_back(sim.State());
  }
  ASSERT_TRUE(sim.contact().has_value()) << "no collision reported; x = " << sim.State().p_WB.x();
  const ContactEvent c = *sim.contact();
  EXPECT_NEAR(c.point_W.x(), 3.0, 0.02) << "contact point should lie on the wall face";
  EXPECT_LT(std::abs(c.point_W.y()), options.vehicle.collision_radius);
  EXPECT_NEAR(c.point_W.z(), 1.5, 0.15);
  EXPECT_GT(c.normal_W.dot(Eigen::Vector3d(-1, 0, 0)), 0.95) << c.normal_W.transpose();
  EXPECT_LE(c.distance, options.contact_tolerance);

  // The body's front (cylinder radius) reaches the wall at the reported time.
  const double h = options.collision_half_height, r = options.vehicle.collision_radius;
  const double reach = std::sqrt(r * r - h * h);
  const auto at = std::find_if(history.begin(), history.end(),
                               [&](const VehicleState& s) { return s.t >= c.t - 1e-9; });
  ASSERT_NE(at, history.end());
  EXPECT_NEAR(at->p_WB.x() + reach, 3.0, 0.03) << "touching state at t = " << c.t;
  // Roughly the straight-line time (the vehicle lags its reference a little).
  EXPECT_GT(c.t, (3.0 - reach) / speed);
  EXPECT_LT(c.t, (3.0 - reach) / speed + 0.6);

  // Flight has ended: the event is kept as it was.
  for (int i = 0; i < 50; ++i) sim.Step();
  ASSERT_TRUE(sim.contact().has_value());
  EXPECT_EQ(sim.contact()->t, c.t);
}

TEST(QuadrotorSimTest, StartingOnTheGroundIsAContactAtTimeZero) {
  QuadrotorSim sim(GroundWorld(), QuadrotorOptions{}, {0, 0, 0.05}, 0.0);
  sim.Step();
  ASSERT_TRUE(sim.contact().has_value());
  EXPECT_EQ(sim.contact()->t, 0.0);
  EXPECT_NEAR(sim.contact()->point_W.z(), 0.0, 1e-4);
  EXPECT_GT(sim.contact()->normal_W.z(), 0.99);
}

TEST(QuadrotorSimTest, IdenticalRunsAreBitIdentical) {
  auto run = [] {
    QuadrotorSim sim(GroundWorld(), QuadrotorOptions{}, {0.3, -0.2, 1.0}, 0.2);
    const TestController controller(QuadrotorOptions{}.vehicle);
    std::vector<double> trace;
    for (int i = 0; i < 3000; ++i) {
      const double t = sim.time();
      if (i % 5 == 0) {
        sim.SetCommand(controller.Compute(sim.State(), {std::sin(t), std::cos(2 * t) - 1, 1.0 + 0.3 * t},
                                          {std::cos(t), -2 * std::sin(2 * t), 0.3}, 0.5 * t));
      }
      sim.Step();
      const VehicleState s = sim.State();
      trace.insert(trace.end(), {s.p_WB.x(), s.p_WB.y(), s.p_WB.z(), s.v_WB.x(), s.q_WB.w(),
                                 s.q_WB.z(), s.w_WB_B.x(), s.a_WB.z(), sim.rotor_speeds()[2]});
    }
    return trace;
  };
  const std::vector<double> a = run(), b = run();
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(double)))
      << "two identical runs diverged";
}

// Episodes run in parallel threads of one worker, each with its own QuadrotorSim over the one
// shared static world; they must not disturb each other. One flies with its rim 1.5 cm from a
// wall, which keeps the mesh narrow phase busy every step.
TEST(QuadrotorSimTest, EpisodesOnTwoThreadsShareTheStaticWorld) {
  worlds::TriangleMesh mesh = testing::MakeClutteredPark(3, 100, 40);
  const double rim = std::sqrt(0.3 * 0.3 - 0.06 * 0.06);
  testing::AddAlignedBox(&mesh, {-30, rim + 0.015, 0}, {30, rim + 0.1, 2});
  const auto world = std::make_shared<const StaticCollisionWorld>(mesh);
  auto fly = [&world](double y, std::vector<double>* trace) {
    QuadrotorSim sim(world, QuadrotorOptions{}, {-25, y, 1.0}, 0.0);
    const TestController controller(QuadrotorOptions{}.vehicle);
    for (int i = 0; i < 4000 && !sim.contact(); ++i) {
      if (i % 5 == 0) {
        sim.SetCommand(controller.Compute(sim.State(), {-25 + 3 * sim.time(), y, 1.0}, {3, 0, 0}, 0));
      }
      sim.Step();
      trace->push_back(sim.State().p_WB.x());
    }
    trace->push_back(sim.contact() ? sim.contact()->t : -1.0);
  };
  std::vector<double> alone_a, alone_b, a, b;
  fly(0.0, &alone_a);
  fly(-0.7, &alone_b);
  std::thread ta(fly, 0.0, &a), tb(fly, -0.7, &b);
  ta.join();
  tb.join();
  EXPECT_GT(alone_a.size(), 1000u);
  EXPECT_EQ(a, alone_a);
  EXPECT_EQ(b, alone_b);
}

TEST(QuadrotorSimTest, RejectsBadOptionsNamingTheField) {
  QuadrotorOptions options;
  options.dt = 0.0;
  try {
    QuadrotorSim sim(EmptyWorld(), options, {0, 0, 1}, 0.0);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("dt"), std::string::npos) << e.what();
  }
  options = QuadrotorOptions{};
  options.vehicle.omega_max = 100.0;  // cannot carry the weight
  EXPECT_THROW(QuadrotorSim(EmptyWorld(), options, {0, 0, 1}, 0.0), std::invalid_argument);
  EXPECT_THROW(QuadrotorSim(nullptr, QuadrotorOptions{}, {0, 0, 1}, 0.0), std::invalid_argument);
  QuadrotorSim sim(EmptyWorld(), QuadrotorOptions{}, {0, 0, 1}, 0.0);
  RotorCommand nan;
  nan.omega[1] = std::nan("");
  EXPECT_THROW(sim.SetCommand(nan), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::sim
