#pragma once
// Quadrotor rigid body in a per-episode Bullet world over the shared static collision world.

#include <array>
#include <cstdint>
#include <memory>
#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "navstack/common/state.h"
#include "navstack/control/vehicle.h"
#include "workers/sim/static_world.h"

namespace enavi::sim {

struct QuadrotorOptions {
  navstack::VehicleParams vehicle;
  double dt = 0.001;  ///< s; every Step() advances exactly this much (1 kHz physics)
  /// Rotors spinning at hover speed and a hover command at t = 0, so the vehicle hangs still
  /// until the controller takes over; false starts with rotors at rest (free fall).
  bool start_at_hover = true;
  /// The vehicle collides as a cylinder (axis = body z) of this half height whose rim lies on
  /// the sphere of radius vehicle.collision_radius, i.e. radius sqrt(r^2 - h^2): frame and
  /// propellers, never larger than the radius the planner inflates obstacles by.
  double collision_half_height = 0.06;
  /// A contact point with signed separation below this (m) is a collision.
  double contact_tolerance = 1e-3;
  /// Body (parasitic) drag 0.5 rho Cd A |v_rel| v_rel, per body axis, as Cd * A in m^2; zero
  /// (off) unless set. kX500BodyDragCdA is what the episode uses when it flies in wind.
  Eigen::Vector3d body_drag_cda = Eigen::Vector3d::Zero();
  double air_density = 1.225;  ///< kg/m^3, ISA sea level
};

/// Cd * A of an X500-class airframe, body axes (m^2). ESTIMATES, not measurements: the X500's
/// centre plates, battery and arms seen from the side are about 0.03 m^2 and from above about
/// 0.05 m^2 (500 mm wheelbase, 0.14 m centre plates); Cd about 1.0 sideways (bluff body) and 1.2
/// from above (flat plate, Hoerner, "Fluid-Dynamic Drag", 1965, ch. 3).
inline const Eigen::Vector3d kX500BodyDragCdA{0.03, 0.03, 0.06};

/// First touch of the vehicle with the world. Flight ends there; the episode runner stops.
struct ContactEvent {
  double t = 0.0;                                       ///< s, sim time of the touching state
  Eigen::Vector3d point_W = Eigen::Vector3d::Zero();    ///< on the world's surface
  Eigen::Vector3d normal_W = Eigen::Vector3d::UnitZ();  ///< surface normal, world -> vehicle
  double distance = 0.0;  ///< m, signed separation (< 0: penetration)
  int body = -1;          ///< what was touched: -1 the static world, i >= 0 kinematic body i (a mover)
};

/// Rotor speed at which the four rotors together carry the vehicle's weight.
double HoverRotorSpeed(const navstack::VehicleParams& vehicle);

/// Quadrotor flight dynamics (MuJoCo-style split: the static world is the shared model, this is
/// one episode's mutable data). A btRigidBody with the vehicle's mass and diagonal inertia in
/// its own btDiscreteDynamicsWorld, which also holds the shared static triangle mesh and the
/// movers as kinematic collision objects.
///
/// Per Step(): each rotor's speed follows its command through a first-order lag (time constant
/// up/down) and is clamped to [0, omega_max]; rotor i pushes thrust_coeff * omega_i^2 along
/// body +z at its position and twists the body by -kSpin[i] * moment_coeff * thrust_i about
/// body z; rotor drag -linear_drag (body axes) * v_rel_B, the linear rotor-drag model of
/// Faessler, Franchi and Scaramuzza, "Differential flatness of quadrotor dynamics subject to
/// rotor drag", RA-L 2018 (F = -R D R^T v, D diagonal, with VehicleParams' coefficients); body
/// drag -0.5 rho CdA |v_rel| v_rel_B; v_rel is the velocity relative to the air (SetAirVelocity,
/// still air by default); gravity 9.81 m/s^2. Bullet integrates
/// one step of exactly dt (no substeps, no interpolation). Bullet's integrator is symplectic
/// Euler; the body's velocities are read as mid-step values (leapfrog), so positions are
/// second-order accurate: a free fall matches z0 - g t^2 / 2 up to float rounding.
/// Deterministic: the same inputs give bit-identical states.
class QuadrotorSim {
 public:
  /// Starts at rest at p0 (body origin in W) with heading yaw0 (rad, about world z).
  /// @throws std::invalid_argument naming the field for non-positive mass, inertia, dt, time
  /// constants or omega_max, non-finite p0/yaw0, a collision shape that does not fit, or a
  /// vehicle that cannot hover when start_at_hover is set.
  QuadrotorSim(std::shared_ptr<const StaticCollisionWorld> world, const QuadrotorOptions& options,
               const Eigen::Vector3d& p0, double yaw0);
  ~QuadrotorSim();
  QuadrotorSim(QuadrotorSim&&) noexcept;
  QuadrotorSim& operator=(QuadrotorSim&&) noexcept;
  QuadrotorSim(const QuadrotorSim&) = delete;
  QuadrotorSim& operator=(const QuadrotorSim&) = delete;

  /// Adds a kinematic obstacle (a mover: moved by SetKinematicPose, never pushed) of this shape,
  /// posed at X_WM; returns its index, which ContactEvent::body names when it is touched.
  int AddKinematicBody(std::shared_ptr<const StaticCollisionWorld> shape, const Eigen::Isometry3d& X_WM);
  /// Moves kinematic body `index` to X_WM: call before Step() with its pose at time().
  void SetKinematicPose(int index, const Eigen::Isometry3d& X_WM);

  /// Commanded rotor speeds (rad/s), held until the next call; clamped to [0, omega_max].
  /// @throws std::invalid_argument if a command is not finite.
  void SetCommand(const navstack::RotorCommand& command);
  /// Velocity of the air at the vehicle (world frame, m/s), held until the next call: the drag
  /// acts against the velocity relative to it.
  /// @throws std::invalid_argument if not finite.
  void SetAirVelocity(const Eigen::Vector3d& air_W);
  /// Advances the simulation by exactly dt.
  void Step();

  /// Ground truth at time(): position, velocity, acceleration (finite difference of velocity
  /// over the last step), orientation and body rates.
  navstack::VehicleState State() const;
  double time() const;
  std::int64_t step_count() const;
  /// Current rotor speeds, rad/s, in the order of VehicleParams::RotorPositions().
  const std::array<double, 4>& rotor_speeds() const;
  const navstack::RotorCommand& command() const;
  /// The first contact with the world, if any; kept once set (flight has ended).
  std::optional<ContactEvent> contact() const;
  const QuadrotorOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace enavi::sim
