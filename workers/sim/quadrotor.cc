#include "workers/sim/quadrotor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "workers/sim/bullet_impl.h"

namespace enavi::sim {
namespace {

btVector3 ToBt(const Eigen::Vector3d& v) {
  return btVector3(static_cast<btScalar>(v.x()), static_cast<btScalar>(v.y()),
                   static_cast<btScalar>(v.z()));
}
Eigen::Vector3d ToEigen(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

void Require(bool ok, const std::string& field, const std::string& reason) {
  if (!ok) throw std::invalid_argument("QuadrotorOptions." + field + ": " + reason);
}

void CheckOptions(const QuadrotorOptions& o) {
  const navstack::VehicleParams& v = o.vehicle;
  auto positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  Require(positive(o.dt), "dt", "must be finite and > 0, got " + std::to_string(o.dt));
  Require(positive(v.mass), "vehicle.mass", "must be finite and > 0");
  Require(positive(v.inertia_diag.x()) && positive(v.inertia_diag.y()) &&
              positive(v.inertia_diag.z()),
          "vehicle.inertia_diag", "all three moments must be finite and > 0");
  Require(std::isfinite(v.thrust_coeff) && v.thrust_coeff >= 0.0, "vehicle.thrust_coeff",
          "must be finite and >= 0");
  Require(std::isfinite(v.moment_coeff), "vehicle.moment_coeff", "must be finite");
  Require(positive(v.motor_time_constant_up), "vehicle.motor_time_constant_up",
          "must be finite and > 0");
  Require(positive(v.motor_time_constant_down), "vehicle.motor_time_constant_down",
          "must be finite and > 0");
  Require(positive(v.omega_max), "vehicle.omega_max", "must be finite and > 0");
  Require(v.linear_drag.allFinite() && (v.linear_drag.array() >= 0.0).all(),
          "vehicle.linear_drag", "must be finite and >= 0");
  Require(v.arm_length >= 0.0 && std::isfinite(v.arm_length), "vehicle.arm_length",
          "must be finite and >= 0");
  Require(positive(o.collision_half_height), "collision_half_height", "must be finite and > 0");
  Require(std::isfinite(v.collision_radius) && v.collision_radius > o.collision_half_height,
          "vehicle.collision_radius",
          "must exceed collision_half_height (" + std::to_string(o.collision_half_height) +
              "), got " + std::to_string(v.collision_radius));
  Require(std::isfinite(o.contact_tolerance) && o.contact_tolerance >= 0.0, "contact_tolerance",
          "must be finite and >= 0");
  Require(o.body_drag_cda.allFinite() && (o.body_drag_cda.array() >= 0.0).all(), "body_drag_cda",
          "must be finite and >= 0");
  Require(positive(o.air_density), "air_density", "must be finite and > 0");
}

// Bullet's cylinder margin rounds the rim; the outer extents stay as given.
constexpr btScalar kVehicleMargin = 0.01f;

}  // namespace

double HoverRotorSpeed(const navstack::VehicleParams& vehicle) {
  return std::sqrt(vehicle.mass * vehicle.Gravity() / (4.0 * vehicle.thrust_coeff));
}

struct QuadrotorSim::Impl {
  QuadrotorOptions options;
  std::shared_ptr<const StaticCollisionWorld> static_world;
  std::array<Eigen::Vector3d, 4> rotor_positions_B;
  double lag_up = 0.0, lag_down = 0.0;  // 1 - exp(-dt / tau): exact first-order lag per step

  std::unique_ptr<btDefaultCollisionConfiguration> configuration;
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  std::unique_ptr<btDbvtBroadphase> broadphase;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
  std::unique_ptr<btDiscreteDynamicsWorld> world;
  std::unique_ptr<btCylinderShapeZ> vehicle_shape;
  std::unique_ptr<btRigidBody> body;
  std::unique_ptr<btCollisionObject> static_object;
  std::vector<std::shared_ptr<const StaticCollisionWorld>> kinematic_shapes;
  std::vector<std::unique_ptr<btCollisionObject>> kinematic_objects;

  std::int64_t steps = 0;
  std::array<double, 4> omega{};
  navstack::RotorCommand command;
  Eigen::Vector3d air_W = Eigen::Vector3d::Zero();
  // Acceleration over the last step (W). Bullet's velocities are those of the middle of the
  // last step, half a step behind time().
  Eigen::Vector3d a_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d alpha_W = Eigen::Vector3d::Zero();
  std::optional<ContactEvent> contact;

  ~Impl() {
    // Bullet objects must leave the world before they are destroyed.
    if (world && body) world->removeRigidBody(body.get());
    if (world && static_object) world->removeCollisionObject(static_object.get());
    for (auto& o : kinematic_objects) world->removeCollisionObject(o.get());
  }

  double dt() const { return options.dt; }
  Eigen::Matrix3d R_WB() const {
    const btQuaternion q = body->getWorldTransform().getRotation();
    return Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized().toRotationMatrix();
  }
  // Velocities at time(): Bullet's mid-step values carried forward by half a step.
  Eigen::Vector3d v_W() const {
    return ToEigen(body->getLinearVelocity()) + 0.5 * dt() * a_W;
  }
  Eigen::Vector3d w_W() const {
    return ToEigen(body->getAngularVelocity()) + 0.5 * dt() * alpha_W;
  }

  // Rotor thrust, yaw reaction and drag at the current state and rotor speeds, as a total force
  // and torque in W (gravity is Bullet's).
  void RotorAndDragWrench(Eigen::Vector3d* F_W, Eigen::Vector3d* tau_W) const {
    const navstack::VehicleParams& p = options.vehicle;
    const Eigen::Matrix3d R = R_WB();
    Eigen::Vector3d F_B = Eigen::Vector3d::Zero();
    Eigen::Vector3d tau_B = Eigen::Vector3d::Zero();
    for (int i = 0; i < 4; ++i) {
      const double thrust = p.thrust_coeff * omega[i] * omega[i];
      const Eigen::Vector3d f_B(0.0, 0.0, thrust);
      F_B += f_B;
      tau_B += rotor_positions_B[i].cross(f_B);
      tau_B.z() += -navstack::VehicleParams::kSpin[i] * p.moment_coeff * thrust;
    }
    const Eigen::Vector3d v_rel_B = R.transpose() * (v_W() - air_W);
    F_B -= p.linear_drag.cwiseProduct(v_rel_B);
    F_B -= 0.5 * options.air_density * v_rel_B.norm() * options.body_drag_cda.cwiseProduct(v_rel_B);
    *F_W = R * F_B;
    *tau_W = R * tau_B;
  }

  // Motor lag over one step toward the clamped command.
  void UpdateRotors() {
    const double omega_max = options.vehicle.omega_max;
    for (int i = 0; i < 4; ++i) {
      const double target = std::clamp(command.omega[i], 0.0, omega_max);
      const double gain = target > omega[i] ? lag_up : lag_down;
      omega[i] = std::clamp(omega[i] + gain * (target - omega[i]), 0.0, omega_max);
    }
  }

  // Deepest vehicle-world manifold point under the tolerance, from the collision pass of the
  // last step (run at the state before the step's integration).
  std::optional<ContactEvent> FindContact(double t) const {
    std::optional<ContactEvent> best;
    btDispatcher* d = world->getDispatcher();
    for (int i = 0; i < d->getNumManifolds(); ++i) {
      const btPersistentManifold* m = d->getManifoldByIndexInternal(i);
      const bool vehicle_is_a = m->getBody0() == body.get();
      if (!vehicle_is_a && m->getBody1() != body.get()) continue;
      const btCollisionObject* other = vehicle_is_a ? m->getBody1() : m->getBody0();
      for (int j = 0; j < m->getNumContacts(); ++j) {
        const btManifoldPoint& pt = m->getContactPoint(j);
        const double distance = pt.getDistance();
        if (!(distance < options.contact_tolerance)) continue;
        if (best && distance >= best->distance) continue;
        ContactEvent e;
        e.t = t;
        e.distance = distance;
        // Bullet's normal lies on body B and points from B to A.
        e.point_W = ToEigen(vehicle_is_a ? pt.getPositionWorldOnB() : pt.getPositionWorldOnA());
        e.normal_W = (vehicle_is_a ? 1.0 : -1.0) * ToEigen(pt.m_normalWorldOnB);
        e.body = other->getUserIndex();  // -1 for the static world
        best = e;
      }
    }
    return best;
  }
};

QuadrotorSim::QuadrotorSim(std::shared_ptr<const StaticCollisionWorld> world,
                           const QuadrotorOptions& options, const Eigen::Vector3d& p0,
                           double yaw0)
    : impl_(std::make_unique<Impl>()) {
  if (!world) throw std::invalid_argument("QuadrotorSim: static world is null");
  CheckOptions(options);
  if (!p0.allFinite()) throw std::invalid_argument("QuadrotorSim: p0 is not finite");
  if (!std::isfinite(yaw0)) throw std::invalid_argument("QuadrotorSim: yaw0 is not finite");
  Impl& s = *impl_;
  s.options = options;
  s.static_world = std::move(world);
  const navstack::VehicleParams& p = options.vehicle;
  s.rotor_positions_B = p.RotorPositions();
  s.lag_up = -std::expm1(-options.dt / p.motor_time_constant_up);
  s.lag_down = -std::expm1(-options.dt / p.motor_time_constant_down);

  if (options.start_at_hover) {
    const double hover = HoverRotorSpeed(p);
    if (!(p.thrust_coeff > 0.0) || !(hover <= p.omega_max)) {
      throw std::invalid_argument(
          "QuadrotorOptions.vehicle: cannot hover (hover rotor speed " + std::to_string(hover) +
          " rad/s exceeds omega_max " + std::to_string(p.omega_max) +
          "); set start_at_hover = false or fix mass/thrust_coeff/omega_max");
    }
    s.omega.fill(hover);
    s.command.omega.fill(hover);
  }

  // Per-episode Bullet world.
  s.configuration = std::make_unique<btDefaultCollisionConfiguration>();
  s.dispatcher = std::make_unique<btCollisionDispatcher>(s.configuration.get());
  s.broadphase = std::make_unique<btDbvtBroadphase>();
  s.solver = std::make_unique<btSequentialImpulseConstraintSolver>();
  s.world = std::make_unique<btDiscreteDynamicsWorld>(s.dispatcher.get(), s.broadphase.get(),
                                                      s.solver.get(), s.configuration.get());
  s.world->setGravity(btVector3(0, 0, static_cast<btScalar>(-p.Gravity())));

  // The shared static triangles, through a collision object of this world.
  if (btCollisionShape* shape = s.static_world->impl().mutable_shape()) {
    s.static_object = std::make_unique<btCollisionObject>();
    s.static_object->setCollisionShape(shape);
    s.static_object->setCollisionFlags(btCollisionObject::CF_STATIC_OBJECT);
    s.static_object->setUserIndex(-1);
    s.world->addCollisionObject(s.static_object.get(), btBroadphaseProxy::StaticFilter,
                                btBroadphaseProxy::AllFilter ^ btBroadphaseProxy::StaticFilter);
  }

  // The vehicle: mass and inertia from VehicleParams, a flat cylinder inside collision_radius.
  const double h = options.collision_half_height;
  const double r = std::sqrt(p.collision_radius * p.collision_radius - h * h);
  s.vehicle_shape = std::make_unique<btCylinderShapeZ>(
      btVector3(static_cast<btScalar>(r), static_cast<btScalar>(r), static_cast<btScalar>(h)));
  s.vehicle_shape->setMargin(kVehicleMargin);
  btRigidBody::btRigidBodyConstructionInfo info(static_cast<btScalar>(p.mass), nullptr,
                                                s.vehicle_shape.get(), ToBt(p.inertia_diag));
  info.m_linearDamping = 0;
  info.m_angularDamping = 0;
  btTransform X_WB;
  X_WB.setIdentity();
  X_WB.setOrigin(ToBt(p0));
  X_WB.setRotation(btQuaternion(btVector3(0, 0, 1), static_cast<btScalar>(yaw0)));
  info.m_startWorldTransform = X_WB;
  s.body = std::make_unique<btRigidBody>(info);
  s.body->setActivationState(DISABLE_DEACTIVATION);
  s.world->addRigidBody(s.body.get());

  // Leapfrog start: the velocities Bullet holds are those at -dt/2, i.e. zero minus half a
  // step of the initial acceleration (zero when hovering).
  Eigen::Vector3d F_W, tau_W;
  s.RotorAndDragWrench(&F_W, &tau_W);
  s.a_W = F_W / p.mass + Eigen::Vector3d(0, 0, -p.Gravity());
  const Eigen::Matrix3d R = s.R_WB();
  s.alpha_W = R * (R.transpose() * tau_W).cwiseQuotient(p.inertia_diag);
  s.body->setLinearVelocity(ToBt(-0.5 * options.dt * s.a_W));
  s.body->setAngularVelocity(ToBt(-0.5 * options.dt * s.alpha_W));
}

QuadrotorSim::~QuadrotorSim() = default;
QuadrotorSim::QuadrotorSim(QuadrotorSim&&) noexcept = default;
QuadrotorSim& QuadrotorSim::operator=(QuadrotorSim&&) noexcept = default;

int QuadrotorSim::AddKinematicBody(std::shared_ptr<const StaticCollisionWorld> shape, const Eigen::Isometry3d& X_WM) {
  Impl& s = *impl_;
  if (!shape || !shape->impl().mutable_shape()) throw std::invalid_argument("QuadrotorSim::AddKinematicBody: no shape");
  const int index = static_cast<int>(s.kinematic_objects.size());
  auto object = std::make_unique<btCollisionObject>();
  object->setCollisionShape(shape->impl().mutable_shape());
  object->setCollisionFlags(btCollisionObject::CF_KINEMATIC_OBJECT);
  object->setActivationState(DISABLE_DEACTIVATION);
  object->setUserIndex(index);
  s.kinematic_shapes.push_back(std::move(shape));
  // Movers touch only the vehicle, not the static world or each other.
  s.world->addCollisionObject(object.get(), btBroadphaseProxy::KinematicFilter,
                              btBroadphaseProxy::AllFilter ^ (btBroadphaseProxy::StaticFilter | btBroadphaseProxy::KinematicFilter));
  s.kinematic_objects.push_back(std::move(object));
  SetKinematicPose(index, X_WM);
  return index;
}

void QuadrotorSim::SetKinematicPose(int index, const Eigen::Isometry3d& X_WM) {
  Impl& s = *impl_;
  if (index < 0 || index >= static_cast<int>(s.kinematic_objects.size())) {
    throw std::invalid_argument("QuadrotorSim::SetKinematicPose: no kinematic body " + std::to_string(index));
  }
  btTransform X;
  const Eigen::Matrix3d R = X_WM.linear();
  X.setBasis(btMatrix3x3(static_cast<btScalar>(R(0, 0)), static_cast<btScalar>(R(0, 1)), static_cast<btScalar>(R(0, 2)),
                         static_cast<btScalar>(R(1, 0)), static_cast<btScalar>(R(1, 1)), static_cast<btScalar>(R(1, 2)),
                         static_cast<btScalar>(R(2, 0)), static_cast<btScalar>(R(2, 1)), static_cast<btScalar>(R(2, 2))));
  X.setOrigin(ToBt(X_WM.translation()));
  s.kinematic_objects[index]->setWorldTransform(X);
}

void QuadrotorSim::SetCommand(const navstack::RotorCommand& command) {
  for (int i = 0; i < 4; ++i) {
    if (!std::isfinite(command.omega[i])) {
      throw std::invalid_argument("QuadrotorSim::SetCommand: omega[" + std::to_string(i) +
                                  "] is not finite");
    }
  }
  impl_->command = command;
}

void QuadrotorSim::SetAirVelocity(const Eigen::Vector3d& air_W) {
  if (!air_W.allFinite()) throw std::invalid_argument("air velocity must be finite");
  impl_->air_W = air_W;
}

void QuadrotorSim::Step() {
  Impl& s = *impl_;
  const double dt = s.dt();
  const double t_before = time();

  // Forces at the current state and rotor speeds, then the rotors move on to the next instant.
  Eigen::Vector3d F_W, tau_W;
  s.RotorAndDragWrench(&F_W, &tau_W);
  s.UpdateRotors();
  s.body->applyCentralForce(ToBt(F_W));
  s.body->applyTorque(ToBt(tau_W));

  const Eigen::Vector3d v_half_before = ToEigen(s.body->getLinearVelocity());
  const Eigen::Vector3d w_half_before = ToEigen(s.body->getAngularVelocity());
  // maxSubSteps = 0: one step of exactly dt, no fixed-step accumulator, no interpolation.
  s.world->stepSimulation(static_cast<btScalar>(dt), 0);
  ++s.steps;
  s.a_W = (ToEigen(s.body->getLinearVelocity()) - v_half_before) / dt;
  s.alpha_W = (ToEigen(s.body->getAngularVelocity()) - w_half_before) / dt;

  // The collision pass of this step ran at the state of t_before.
  if (!s.contact) s.contact = s.FindContact(t_before);
}

navstack::VehicleState QuadrotorSim::State() const {
  const Impl& s = *impl_;
  navstack::VehicleState state;
  state.t = time();
  const btTransform& X = s.body->getWorldTransform();
  state.p_WB = ToEigen(X.getOrigin());
  const btQuaternion q = X.getRotation();
  state.q_WB = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized();
  state.v_WB = s.v_W();
  state.a_WB = s.a_W;
  state.w_WB_B = state.q_WB.toRotationMatrix().transpose() * s.w_W();
  return state;
}

double QuadrotorSim::time() const { return static_cast<double>(impl_->steps) * impl_->dt(); }
std::int64_t QuadrotorSim::step_count() const { return impl_->steps; }
const std::array<double, 4>& QuadrotorSim::rotor_speeds() const { return impl_->omega; }
const navstack::RotorCommand& QuadrotorSim::command() const { return impl_->command; }
std::optional<ContactEvent> QuadrotorSim::contact() const { return impl_->contact; }
const QuadrotorOptions& QuadrotorSim::options() const { return impl_->options; }

}  // namespace enavi::sim
