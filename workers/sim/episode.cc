#include "workers/sim/episode.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "navstack/common/cpu_time.h"
#include "workers/sim/embree_scene.h"
#include "workers/sim/episode_monitors.h"
#include "workers/sim/episode_movers.h"
#include "workers/sim/episode_provenance.h"
#include "workers/sim/static_world.h"
#include "worlds/mesh.h"
#include "worlds/resolve.h"

namespace enavi::sim {
namespace {

using navstack::TaskId;

void CheckSpeedProbeMode(const std::string& mode) {
  for (const char* known : api::kSpeedProbeModes)
    if (mode == known) return;
  throw std::invalid_argument("speed_probe: unknown mode '" + mode + "' (known: check, use, off)");
}

// The spec's speed-probe mode applied to the probe the command supplied (options.emulation).
emulation::EmulationOptions WithSpeedProbe(const api::EpisodeSpec& spec, emulation::EmulationOptions e) {
  if (spec.speed_probe == "off") e.probe_host_speed = nullptr;
  e.use_probed_speed = spec.speed_probe == "use";
  return e;
}

// How the result was produced, as far as it is known before the flight.
std::map<std::string, std::string> ModelNotes(const EpisodeModel& m) {
  const api::EpisodeSpec& spec = m.spec;
  std::map<std::string, std::string> notes;
  notes["clock"] = spec.clock;
  notes["board_cores"] = std::to_string(m.board.cores);
  if (!spec.ros)
    notes["scheduler"] = std::string(m.config.scheduler.policy == navstack::SchedulingPolicy::kGlobalEdf
                                         ? "global EDF"
                                         : "FIFO, no preemption") +
                         " on " + std::to_string(m.threads) + " thread(s)";
  notes["triangles"] = std::to_string(m.world->triangles);
  if (m.world->movers) notes["movers"] = std::to_string(m.world->world.movers.size());
  if (!m.world->world.metadata.import_note.empty()) notes["world_import"] = m.world->world.metadata.import_note;
  notes["depth_stream"] = std::to_string(m.config.nav.camera.width) + "x" + std::to_string(m.config.nav.camera.height);
  notes.merge(EpisodeProvenance(spec, m.board, m.config.method ? m.config.method->cost_family : "",
                                m.config.method && (m.config.method->uses_policy || m.config.method->uses_nav_policy)));
  return notes;
}

// The link the stack runs on, from the registry (link_registry.h).
std::unique_ptr<NavLink> MakeEpisodeLink(const EpisodeModel& m, const navstack::VehicleState& initial,
                                         const emulation::EmulationOptions& emulation) {
  LinkRequest r;
  r.spec = &m.spec;
  r.board = &m.board;
  r.method = m.config.method;
  r.nav = &m.config.nav;
  r.threads = m.threads;
  r.policy = m.config.scheduler.policy;
  r.initial = initial;
  r.start = m.world->world.start;
  r.goal = m.world->world.goal;
  r.start_yaw = m.start_yaw;
  r.bounds = m.world->world.bounds;
  r.camera = m.config.nav.camera;
  r.X_BC = CameraPoseInWorld(Eigen::Isometry3d::Identity(), m.vehicle);
  r.job_observer = m.options.job_observer;
  r.emulation = &emulation;
  r.output_dir = m.options.ros_output_dir;
  r.bag_file = m.options.ros_bag_file;
  if (r.bag_file.empty() && !m.spec.rosbag_dir.empty())
    r.bag_file = m.spec.rosbag_dir + "/" + m.scenario + "-" + m.spec.board + "-" + m.spec.method + "-s" +
                 std::to_string(m.spec.seed) + ".bag";
  return MakeLink(r);
}

Eigen::Isometry3d BodyPose(const navstack::VehicleState& s) {
  Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
  X_WB.linear() = s.q_WB.toRotationMatrix();
  X_WB.translation() = s.p_WB;
  return X_WB;
}

constexpr std::uint64_t kWindStream = 0x77696e64;      // "wind"
constexpr std::uint64_t kOdometryStream = 0x6f646f6d;  // "odom"

QuadrotorOptions QuadOptions(const EpisodeModel& m) {
  QuadrotorOptions o;
  o.vehicle = m.vehicle;
  o.dt = m.options.physics_dt;
  // Body drag only in wind: in still air the episode keeps the drag-free airframe its flights
  // were measured with (the controller then flies the same as before the wind came).
  if (m.spec.wind.Active()) o.body_drag_cda = kX500BodyDragCdA;
  return o;
}

}  // namespace

std::shared_ptr<const PreparedWorld> PrepareWorld(worlds::World world) {
  auto prepared = std::make_shared<PreparedWorld>();
  const worlds::TriangleMesh mesh = worlds::BuildWorldMesh(world);
  prepared->scene = std::make_shared<const EmbreeScene>(mesh);
  prepared->collision = std::make_shared<const StaticCollisionWorld>(mesh);
  prepared->movers = PrepareMovers(world);
  prepared->triangles = mesh.triangle_count();
  prepared->world = std::move(world);
  return prepared;
}

worlds::WorldRequest WorldRequestOf(const api::EpisodeSpec& spec) {
  worlds::WorldRequest request;
  request.world = spec.world;
  request.seed = spec.seed;
  request.params = spec.world_params;
  if (spec.start) request.start = Eigen::Vector3d((*spec.start)[0], (*spec.start)[1], (*spec.start)[2]);
  if (spec.goal) request.goal = Eigen::Vector3d((*spec.goal)[0], (*spec.goal)[1], (*spec.goal)[2]);
  request.placement = worlds::ParsePlacement(spec.units, spec.scale, spec.up, spec.recenter);
  request.model_path.assign(spec.model_path.begin(), spec.model_path.end());
  return request;
}

EpisodeModel MakeEpisodeModel(const api::EpisodeSpec& spec, const PreparedWorld& world,
                              const EpisodeOptions& options) {
  CheckSpeedProbeMode(spec.speed_probe);
  board::BoardProfile board = board::LoadBoard(spec.board);
  EpisodeConfig config = MakeEpisodeConfig(spec, options.rollout != nullptr, options.decisions);
  const navstack::VehicleParams vehicle;
  DepthCamera camera(config.nav.camera, config.noise);
  EpisodeModel m{.spec = spec,
                 .world = &world,
                 .board = std::move(board),
                 .config = std::move(config),
                 .vehicle = vehicle,
                 .camera = std::move(camera),
                 .options = options};
  const worlds::World& w = world.world;
  m.scenario = w.metadata.scenario.empty() ? "custom" : w.metadata.scenario;
  m.straight_line_m = (w.goal - w.start).norm();
  const Eigen::Vector3d to_goal = w.goal - w.start;
  m.start_yaw = std::atan2(to_goal.y(), to_goal.x());
  // The method's mission: this world's goal and bounds, obstacles inflated by at least the body.
  navstack::MethodOptions& nav = m.config.nav;
  nav.goal = w.goal;
  nav.flight_bounds = w.bounds;
  nav.planner.robot_radius = std::max(nav.planner.robot_radius, vehicle.collision_radius);
  m.timeout_s = spec.timeout_s > 0 ? spec.timeout_s : 20.0 + 6.0 * m.straight_line_m / nav.planner.v_max;
  m.frame_dt = 1.0 / nav.f_sen;
  m.control_every = std::max(1L, std::lround(options.control_dt / options.physics_dt));
  m.record_every = std::max(1L, std::lround(0.01 / options.physics_dt));
  m.series_every = std::max(1L, std::lround(options.series_dt / options.physics_dt));
  m.threads = m.config.scheduler.threads > 0 ? std::min(m.config.scheduler.threads, m.board.cores) : m.board.cores;
  m.notes = ModelNotes(m);
  return m;
}

Episode::Episode(const api::EpisodeSpec& spec, const PreparedWorld& world, const EpisodeOptions& options)
    : model_(MakeEpisodeModel(spec, world, options)),
      quad_(world.collision, QuadOptions(model_), world.world.start, model_.start_yaw),
      controller_(model_.vehicle),
      vehicle_(quad_.State()),
      estimate_(vehicle_),
      p_ref_(world.world.start) {
  // Their own random streams, from the episode's seed (the camera's is seed * 1000003 + frame).
  if (model_.spec.wind.Active()) wind_.emplace(model_.spec.wind, model_.options.physics_dt, model_.spec.seed ^ kWindStream);
  if (model_.spec.odometry_noise != "none")
    odometry_.emplace(OdometryNoisePreset(model_.spec.odometry_noise), model_.spec.seed ^ kOdometryStream);
  // Movers: kinematic bodies for the physics, a moving scene for the camera (none: the static path).
  if (world.movers) movers_.emplace(world.movers, world.scene, &quad_);
  link_ = MakeEpisodeLink(model_, quad_.State(), WithSpeedProbe(spec, options.emulation));
  monitors_ = EpisodeMonitors(model_);
  end_conditions_ = EndConditions();
}

Episode::~Episode() = default;

double Episode::t() const { return k_ * model_.options.physics_dt; }

// The sensor at t: a depth frame rendered with Embree (noise seeded by the episode seed and the
// frame index) from the true pose, its eci computed for the metrics, handed to the stack with the
// pose the odometry gives (the truth, or the VIO-like estimate).
void Episode::Sense(double t) {
  next_frame_t_ += model_.frame_dt;
  auto frame = std::make_shared<navstack::DepthFrame>();
  frame->index = frame_index_++;
  frame->t = t;
  frame->X_WC = CameraPoseInWorld(BodyPose(vehicle_), model_.vehicle);
  frame->v_W = vehicle_.v_WB;
  const std::uint64_t noise_seed = model_.spec.seed * 1000003ULL + frame->index;
  if (movers_) model_.camera.Render(movers_->SceneAt(t), frame->X_WC, &frame->image, noise_seed);
  else model_.camera.Render(*model_.world->scene, frame->X_WC, &frame->image, noise_seed);
  navstack::WorkCounts eci_work;
  const Eigen::Vector3d v_C = frame->X_WC.linear().transpose() * vehicle_.v_WB;
  const double eci_cpu0 = navstack::ThreadCpuSeconds();
  const navstack::EciResult eci =
      navstack::ComputeEci(frame->image, model_.config.nav.camera, v_C, navstack::EciOptions{}, &eci_work);
  const double eci_cpu = navstack::ThreadCpuSeconds() - eci_cpu0;
  if (model_.options.job_observer) model_.options.job_observer(TaskId::kEci, eci_work, eci_cpu);
  const double board_s = link_->OffBoardSeconds(TaskId::kEci, eci_work, eci_cpu);
  for (const auto& m : monitors_) m->OnFrame({*frame, eci, vehicle_}, board_s);
  if (odometry_) {
    frame->X_WC = CameraPoseInWorld(BodyPose(estimate_), model_.vehicle);
    frame->v_W = estimate_.v_WB;
  }
  link_->OnFrame(std::move(frame));
}

StepStatus Episode::Step() {
  if (end_) throw std::logic_error("Step: the episode has ended");
  const double t = this->t();
  if (!resuming_) {
    // Odometry to the stack, and a frame at f_sen. A VIO's error moves when it delivers a pose
    // (at the camera's frames); between them the IMU carries it unchanged.
    vehicle_ = quad_.State();
    const bool frame_due = t >= next_frame_t_ - 1e-9;
    if (odometry_) {
      if (frame_due) odometry_->Update(t);
      estimate_ = odometry_->Apply(vehicle_);
    }
    link_->OnState(odometry_ ? estimate_ : vehicle_);
    if (frame_due) Sense(t);
  } else if (model_.options.decisions && model_.options.decisions->pending()) {
    throw std::logic_error("Step: the pending decision has no action yet (DecisionPort::Supply)");
  }

  // The board runs the stack's jobs up to t; a decision taken outside stops it at its instant.
  link_->AdvanceTo(t);
  resuming_ = link_->paused();
  if (resuming_) return StepStatus::kAwaitingDecision;
  const std::vector<navstack::NavEvent> events = link_->TakeEvents();
  for (const auto& m : monitors_) m->OnEvents(events);

  // A stack that runs as processes may end the episode itself (it exited, misbehaved).
  if (const std::optional<LinkFailure> failure = link_->failure()) {
    end_ = EpisodeEnd{.reason = failure->reason, .detail = failure->detail};
    return StepStatus::kEnded;
  }

  // The flight controller tracks the stack's reference every control_dt (it costs no board time).
  if (k_ % model_.control_every == 0) {
    const navstack::TrajectorySample ref = link_->Reference(t);
    p_ref_ = ref.p;
    quad_.SetCommand(controller_.Update(odometry_ ? estimate_ : vehicle_, ref));
  }
  const StepView step{.k = k_, .t = t, .vehicle = vehicle_, .p_ref = p_ref_, .link = *link_,
                      .estimate = odometry_ ? &estimate_ : nullptr,
                      .air_W = wind_ ? &wind_->air_velocity_W() : nullptr};
  for (const auto& m : monitors_) m->OnStep(step);
  for (const EndCondition& c : end_conditions_) {
    if ((end_ = c.check(model_, step, quad_))) return StepStatus::kEnded;
  }
  // The air at the vehicle for this step (the stack is never told; the drag feels it).
  if (wind_) quad_.SetAirVelocity(wind_->Step(vehicle_.p_WB.z(), vehicle_.v_WB));
  if (movers_) movers_->PoseBodies(t, &quad_);
  quad_.Step();
  ++k_;
  return StepStatus::kRunning;
}

void Episode::Stop(EpisodeEnd end) {
  if (end_) throw std::logic_error("Stop: the episode has ended");
  if (resuming_) throw std::logic_error("Stop: a decision is pending");
  end_ = std::move(end);
}

api::EpisodeResult Episode::Finish() {
  if (!end_) throw std::logic_error("Finish: the episode has not ended");
  if (finished_) throw std::logic_error("Finish: called twice");
  finished_ = true;
  link_->FinishEpisode(end_->collided, end_->success);
  if (model_.options.rollout) {
    if (const navstack::rl::Rollout* r = link_->rollout()) *model_.options.rollout = *r;
  }

  // Results (README.md, "One flight" and api/episode.h).
  api::EpisodeResult result;
  result.spec = model_.spec;
  result.scenario = model_.scenario;
  result.straight_line_m = model_.straight_line_m;
  result.notes = model_.notes;
  const NavAccounting acc = link_->Accounting();
  const double T = quad_.time();
  result.sim_time_s = T;
  result.flight_time_s = T;
  for (const auto& m : monitors_) m->Write({T, acc}, &result);
  result.end_reason = end_->reason;
  result.success = end_->success;
  result.collided = end_->collided;
  result.timed_out = end_->timed_out;
  if (end_->detail) result.notes["end_detail"] = *end_->detail;
  if (end_->contact) {
    const Eigen::Vector3d& p = end_->contact->point_W;
    result.collision_point = api::Vec3{p.x(), p.y(), p.z()};
    result.collided_with = movers_ ? movers_->Touched(end_->contact->body) : "static";
    result.events.push_back({end_->contact->t, "collision", result.collided_with});
  }
  for (const auto& [k, v] : acc.notes) result.notes[k] = v;
  return result;
}

api::EpisodeResult RunEpisode(const api::EpisodeSpec& spec, const PreparedWorld& world,
                              const EpisodeOptions& options) {
  Episode episode(spec, world, options);
  StepStatus status;
  while ((status = episode.Step()) == StepStatus::kRunning) {
  }
  if (status != StepStatus::kEnded)
    throw std::logic_error("RunEpisode: a decision waits for an action from outside; step the Episode instead");
  return episode.Finish();
}

std::shared_ptr<const PreparedWorld> PrepareSpecWorld(const api::EpisodeSpec& spec) {
  return PrepareWorld(worlds::ResolveWorld(WorldRequestOf(spec)));
}

api::EpisodeResult RunEpisode(const api::EpisodeSpec& spec, const EpisodeOptions& options) {
  return RunEpisode(spec, *PrepareSpecWorld(spec), options);
}

}  // namespace enavi::sim
