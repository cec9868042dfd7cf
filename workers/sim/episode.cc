#include "workers/sim/episode.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "api/fixed.h"
#include "navstack/common/cpu_time.h"
#include "navstack/control/controller.h"
#include "navstack/eci/eci.h"
#include "workers/board/board_profile.h"
#include "workers/emulation/emulated_nav_link.h"
#include "workers/sim/depth_camera.h"
#include "workers/sim/embree_scene.h"
#include "workers/sim/episode_config.h"
#include "workers/sim/episode_provenance.h"
#include "workers/sim/flight_recorder.h"
#include "workers/sim/quadrotor.h"
#include "workers/sim/static_world.h"
#include "workers/sim/virtual_nav_link.h"
#include "worlds/mesh.h"
#include "worlds/resolve.h"

namespace enavi::sim {
namespace {

using navstack::TaskId;

api::Vec3 ToVec3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

std::unique_ptr<navstack::CostModel> MakeCostModel(const api::EpisodeSpec& spec, const board::BoardProfile& b,
                                                   const std::string& cost_family) {
  if (spec.cost == "model")
    return std::make_unique<navstack::WorkCountCostModel>(
        board::BoardCoefficients(b, board::LoadReferenceCosts(), cost_family));
  if (spec.cost == "measured") return std::make_unique<navstack::MeasuredCostModel>(1.0 / b.per_core_speed);
  throw std::invalid_argument("cost: unknown cost mode '" + spec.cost + "' (known: model, measured)");
}

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

// Navigation busy time: the four tasks the paper counts as navigation workload, or every process
// of a stack that runs as processes (the paper's figure is the planner process's CPU).
double NavBusy(const NavAccounting& acc) {
  double busy = 0;
  if (!acc.process_cpu_board_s.empty()) {
    for (const auto& [name, board_s] : acc.process_cpu_board_s) busy += board_s;
    return busy;
  }
  for (int i = 0; i < navstack::kTaskCount; ++i)
    if (navstack::IsNavigationTask(static_cast<TaskId>(i))) busy += acc.tasks[i].busy_s;
  return busy;
}

}  // namespace

std::shared_ptr<const PreparedWorld> PrepareWorld(worlds::World world) {
  auto prepared = std::make_shared<PreparedWorld>();
  const worlds::TriangleMesh mesh = worlds::BuildWorldMesh(world);
  prepared->scene = std::make_shared<const EmbreeScene>(mesh);
  prepared->collision = std::make_shared<const StaticCollisionWorld>(mesh);
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

api::EpisodeResult RunEpisode(const api::EpisodeSpec& spec, const EpisodeOptions& options) {
  const auto world = PrepareWorld(worlds::ResolveWorld(WorldRequestOf(spec)));
  return RunEpisode(spec, *world, options);
}

namespace {

// The clock registry: each clock's name, help line and the link that runs the stack on it.
struct ClockEntry {
  ClockInfo info;
  std::unique_ptr<NavLink> (*make)(const api::EpisodeSpec& spec, const EpisodeConfig& config,
                                   const board::BoardProfile& board, int threads,
                                   const navstack::VehicleState& initial, const EpisodeOptions& options);
};

const std::vector<ClockEntry>& ClockEntries() {
  static const std::vector<ClockEntry> entries = {
      {{"virtual", "sim-time EDF on the board's cores, job costs from the cost model (deterministic)"},
       [](const api::EpisodeSpec& spec, const EpisodeConfig& config, const board::BoardProfile& board, int threads,
          const navstack::VehicleState& initial, const EpisodeOptions& options) -> std::unique_ptr<NavLink> {
         return std::make_unique<VirtualNavLink>(*config.method, config.nav, threads, config.scheduler.policy,
                                                 MakeCostModel(spec, board, config.method->cost_family), initial, options.job_observer);
       }},
      {{"emulated", "the stack in its own process, throttled by cgroups to the board's speed, in dilated wall time"},
       [](const api::EpisodeSpec& spec, const EpisodeConfig& config, const board::BoardProfile& board, int threads,
          const navstack::VehicleState& initial, const EpisodeOptions& options) -> std::unique_ptr<NavLink> {
         return std::make_unique<emulation::EmulatedNavLink>(*config.method, config.nav, threads, config.scheduler.policy, board,
                                                  spec.dilation, initial, WithSpeedProbe(spec, options.emulation));
       }},
  };
  return entries;
}

RosLinkFactory& RosFactory() {
  static RosLinkFactory factory;
  return factory;
}

std::unique_ptr<NavLink> MakeNavLink(const api::EpisodeSpec& spec, const EpisodeConfig& config,
                                     const board::BoardProfile& board, const navstack::VehicleState& initial,
                                     const EpisodeOptions& options) {
  const int threads = config.scheduler.threads > 0 ? std::min(config.scheduler.threads, board.cores) : board.cores;
  std::string known;
  for (const ClockEntry& c : ClockEntries()) {
    if (c.info.name == spec.clock) return c.make(spec, config, board, threads, initial, options);
    known += (known.empty() ? "" : ", ") + c.info.name;
  }
  throw std::invalid_argument("clock: unknown clock '" + spec.clock + "' (known: " + known + ")");
}

}  // namespace

std::string& RosUnavailable() {
  static std::string reason = "this enavi was built without the ROS bridge (Debian's ROS packages: "
                              "scripts/install-deps.sh, then rebuild)";
  return reason;
}

void SetRosLinkFactory(RosLinkFactory factory) {
  RosFactory() = std::move(factory);
  RosUnavailable().clear();
}

void SetRosLinkUnavailable(std::string reason) { RosUnavailable() = std::move(reason); }

bool RosLinkAvailable() { return static_cast<bool>(RosFactory()) && RosUnavailable().empty(); }

std::string RosLinkUnavailableReason() { return RosUnavailable(); }

const std::vector<ClockInfo>& Clocks() {
  static const std::vector<ClockInfo> infos = [] {
    std::vector<ClockInfo> v;
    for (const ClockEntry& c : ClockEntries()) v.push_back(c.info);
    return v;
  }();
  return infos;
}

api::EpisodeResult RunEpisode(const api::EpisodeSpec& spec, const PreparedWorld& prepared,
                              const EpisodeOptions& options) {
  const worlds::World& world = prepared.world;
  CheckSpeedProbeMode(spec.speed_probe);
  const board::BoardProfile board = board::LoadBoard(spec.board);
  EpisodeConfig config = MakeEpisodeConfig(spec);
  if (options.rollout && config.nav.strategy) config.nav.strategy->record = true;

  api::EpisodeResult result;
  result.spec = spec;
  result.scenario = world.metadata.scenario.empty() ? "custom" : world.metadata.scenario;
  result.straight_line_m = (world.goal - world.start).norm();
  result.notes["clock"] = spec.clock;
  result.notes["board_cores"] = std::to_string(board.cores);
  if (!spec.ros) result.notes["scheduler"] =
      std::string(config.scheduler.policy == navstack::SchedulingPolicy::kGlobalEdf ? "global EDF" : "FIFO, no preemption") +
      " on " + std::to_string(config.scheduler.threads > 0 ? std::min(config.scheduler.threads, board.cores) : board.cores) +
      " thread(s)";
  result.notes["triangles"] = std::to_string(prepared.triangles);
  if (!world.metadata.import_note.empty()) result.notes["world_import"] = world.metadata.import_note;
  result.notes["depth_stream"] = std::to_string(config.nav.camera.width) + "x" + std::to_string(config.nav.camera.height);
  result.notes.merge(EpisodeProvenance(spec, board, config.method ? config.method->cost_family : "",
                                       config.nav.strategy.has_value()));

  // Vehicle: hovering at the start, facing the goal.
  const navstack::VehicleParams vehicle;
  const Eigen::Vector3d to_goal = world.goal - world.start;
  QuadrotorOptions quad_options;
  quad_options.vehicle = vehicle;
  quad_options.dt = options.physics_dt;
  QuadrotorSim quad(prepared.collision, quad_options, world.start, std::atan2(to_goal.y(), to_goal.x()));
  navstack::Controller controller(vehicle);
  const DepthCamera camera(config.nav.camera, config.noise);

  // The navigation stack under the board's emulation.
  config.nav.goal = world.goal;
  config.nav.flight_bounds = world.bounds;
  config.nav.planner.robot_radius = std::max(config.nav.planner.robot_radius, vehicle.collision_radius);
  std::unique_ptr<NavLink> nav;
  if (spec.ros) {
    if (!RosLinkAvailable())
      throw std::invalid_argument("method: '" + spec.method + "' is a ROS stack, and " + RosLinkUnavailableReason());
    RosLinkRequest request;
    request.spec = &spec;
    request.board = &board;
    request.start = world.start;
    request.goal = world.goal;
    request.start_yaw = std::atan2(to_goal.y(), to_goal.x());
    request.bounds = world.bounds;
    request.camera = config.nav.camera;
    request.X_BC = CameraPoseInWorld(Eigen::Isometry3d::Identity(), vehicle);
    request.initial = quad.State();
    request.options = &options;
    request.bag_file = options.ros_bag_file;
    if (request.bag_file.empty() && !spec.rosbag_dir.empty())
      request.bag_file = spec.rosbag_dir + "/" + result.scenario + "-" + spec.board + "-" + spec.method + "-s" +
                         std::to_string(spec.seed) + ".bag";
    nav = RosFactory()(request);
  } else {
    nav = MakeNavLink(spec, config, board, quad.State(), options);
  }

  const double timeout = spec.timeout_s > 0 ? spec.timeout_s
                                            : 20.0 + 6.0 * result.straight_line_m / config.nav.planner.v_max;
  const double frame_dt = 1.0 / config.nav.f_sen;
  const long control_every = std::max(1L, std::lround(options.control_dt / options.physics_dt));
  const long record_every = std::max(1L, std::lround(0.01 / options.physics_dt));
  const long series_every = std::max(1L, std::lround(options.series_dt / options.physics_dt));

  FlightRecorder recorder(record_every * options.physics_dt);
  Eigen::Vector3d p_ref = world.start;
  double next_frame_t = 0.0;
  std::int64_t frame_index = 0;
  double eci_latest = 0, eci_sum = 0, eci_min = std::numeric_limits<double>::infinity(), eci_max = 0;
  // eci along the flight itself: from the first frame at take-off speed on (api::EciSummary).
  bool took_off = false;
  double flight_eci_min = std::numeric_limits<double>::infinity(), flight_eci_max = 0;
  std::int64_t flight_frames = 0;
  double eci_cost_sum = 0;
  double last_busy = 0;
  std::string interval_events;
  double next_progress = 1.0;

  for (long k = 0;; ++k) {
    const double t = k * options.physics_dt;
    const navstack::VehicleState state = quad.State();
    nav->OnState(state);

    // Sensor: a depth frame at f_sen; eci of every frame for the metrics.
    if (t >= next_frame_t - 1e-9) {
      next_frame_t += frame_dt;
      auto frame = std::make_shared<navstack::DepthFrame>();
      frame->index = frame_index++;
      frame->t = t;
      Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
      X_WB.linear() = state.q_WB.toRotationMatrix();
      X_WB.translation() = state.p_WB;
      frame->X_WC = CameraPoseInWorld(X_WB, vehicle);
      frame->v_W = state.v_WB;
      camera.Render(*prepared.scene, frame->X_WC, &frame->image, spec.seed * 1000003ULL + frame->index);
      navstack::WorkCounts eci_work;
      const Eigen::Vector3d v_C = frame->X_WC.linear().transpose() * state.v_WB;
      const double eci_cpu0 = navstack::ThreadCpuSeconds();
      const navstack::EciResult eci_frame = navstack::ComputeEci(frame->image, config.nav.camera, v_C, config.nav.eci,
                                                                 &eci_work);
      eci_latest = eci_frame.eci;
      const double eci_cpu = navstack::ThreadCpuSeconds() - eci_cpu0;
      if (options.job_observer) options.job_observer(TaskId::kEci, eci_work, eci_cpu);
      eci_cost_sum += nav->OffBoardSeconds(TaskId::kEci, eci_work, eci_cpu);
      eci_sum += eci_latest;
      eci_min = std::min(eci_min, eci_latest);
      eci_max = std::max(eci_max, eci_latest);
      took_off = took_off || state.v_WB.norm() > FlightRecorder::kMovingSpeed;
      if (took_off) {
        ++flight_frames;
        flight_eci_min = std::min(flight_eci_min, eci_latest);
        flight_eci_max = std::max(flight_eci_max, eci_latest);
      }
      if (options.eci_observer) {
        const double up = std::clamp(frame->X_WC.linear().col(2).z(), -1.0, 1.0);  // optical axis, world z
        options.eci_observer(
            {t, eci_frame, state.v_WB.norm(), std::asin(up) * 180.0 / std::numbers::pi, took_off});
      }
      nav->OnFrame(std::move(frame));
    }

    nav->AdvanceTo(t);
    for (const auto& e : nav->TakeEvents()) {
      if (e.kind == "replan") {
        ++result.replans;
        ++result.replans_by_trigger[e.detail.empty() ? "unspecified" : e.detail];
      }
      if (e.kind == "emergency_stop") ++result.emergency_stops;
      interval_events += (interval_events.empty() ? "" : ";") + e.kind;
      if (result.events.size() < 5000) result.events.push_back({e.t, e.kind, e.detail});
    }

    // A stack that runs as processes may end the episode itself (it exited, misbehaved).
    if (const std::optional<LinkFailure> failure = nav->failure()) {
      result.end_reason = failure->reason;
      result.notes["end_detail"] = failure->detail;
      break;
    }

    if (k % control_every == 0) {
      const navstack::TrajectorySample ref = nav->Reference(t);
      p_ref = ref.p;
      quad.SetCommand(controller.Update(state, ref));
    }
    if (k % record_every == 0) recorder.Sample(state.p_WB, state.v_WB, p_ref);
    if (k % series_every == 0) {
      api::TimeSeries& s = result.series;
      const double busy = NavBusy(nav->Accounting());
      s.t.push_back(t);
      s.position.push_back(ToVec3(state.p_WB));
      s.velocity.push_back(ToVec3(state.v_WB));
      s.eci.push_back(eci_latest);
      const navstack::TaskRates r = nav->rates();
      s.f_per.push_back(r.f_per);
      s.f_col.push_back(r.collision_on_map_update ? r.f_per : r.f_col);
      s.f_dif.push_back(r.f_dif);
      s.res.push_back(nav->map_resolution());
      s.utilisation.push_back(k == 0 ? 0.0 : 100.0 * (busy - last_busy) / options.series_dt);
      last_busy = busy;
      s.events.push_back(std::exchange(interval_events, {}));
    }
    if (options.progress && t >= next_progress) {
      next_progress += 1.0;
      options.progress(t, (state.p_WB - world.goal).norm());
    }

    // End conditions: goal reached, collision, timeout.
    if ((state.p_WB - world.goal).norm() < options.goal_radius) {
      result.success = true;
      result.end_reason = "goal_reached";
      break;
    }
    if (const auto contact = quad.contact()) {
      result.collided = true;
      result.end_reason = "collision";
      result.collision_point = ToVec3(contact->point_W);
      result.events.push_back({contact->t, "collision", ""});
      break;
    }
    if (t >= timeout) {
      result.timed_out = true;
      result.end_reason = "timeout";
      break;
    }
    quad.Step();
  }

  nav->FinishEpisode(result.collided, result.success);
  if (options.rollout) {
    if (const navstack::rl::Rollout* r = nav->rollout()) *options.rollout = *r;
  }

  // Results (README.md, "One flight" and api/episode.h).
  const NavAccounting acc = nav->Accounting();
  const double T = quad.time();
  result.sim_time_s = T;
  result.flight_time_s = T;
  result.path_length_m = recorder.path_length();
  result.velocity_mean_mps = recorder.speed_mean();
  result.velocity_std_mps = recorder.speed_std();
  result.accel_peak_mps2 = recorder.accel_peak();
  result.time_stopped_s = recorder.time_stopped();
  result.setpoint_lag_p95_m = recorder.setpoint_lag_p95();
  result.plan_failures = acc.plan_failures;
  auto util = [&](TaskId id) { return T > 0 ? 100.0 * acc[id].busy_s / T : 0.0; };
  result.task_cpu_util_pct = {util(TaskId::kPerception), util(TaskId::kPlanning), util(TaskId::kCollision),
                              util(TaskId::kDifference)};
  result.nav_cpu_util_pct = acc.process_cpu_board_s.empty() ? result.task_cpu_util_pct.Sum()
                                                              : (T > 0 ? 100.0 * NavBusy(acc) / T : 0.0);
  for (const auto& [name, board_s] : acc.process_cpu_board_s)
    result.notes["process." + name] = api::Fixed(T > 0 ? 100.0 * board_s / T : 0.0, 2) + " % of a board core";
  for (int i = 0; i < navstack::kTaskCount; ++i) {
    const auto id = static_cast<TaskId>(i);
    if (!navstack::IsNavigationTask(id)) continue;
    const navstack::TaskStats& st = acc[id];
    result.jobs_released += st.released;
    result.deadline_misses += st.misses();
    if (!config.method) continue;  // a stack of its own processes: no tasks of ours
    const std::string& label = config.method->task_labels[i];
    if (label != navstack::TaskName(id)) result.notes["task." + std::string(navstack::TaskName(id)) + ".is"] = label;
    result.notes["task." + std::string(navstack::TaskName(id))] =
        "released " + std::to_string(st.released) + ", late " + std::to_string(st.late) + ", skipped " +
        std::to_string(st.skipped) + ", mean job " + std::to_string(1e3 * st.MeanCost()) + " ms, max " +
        std::to_string(1e3 * st.cost_max_s) + " ms";
  }
  result.deadline_miss_ratio =
      result.jobs_released > 0 ? static_cast<double>(result.deadline_misses) / result.jobs_released : 0.0;
  result.eci = {frame_index > 0 ? eci_min : 0.0, frame_index > 0 ? eci_sum / frame_index : 0.0, eci_max,
                flight_frames > 0 ? flight_eci_min : 0.0, flight_eci_max, flight_frames};
  // E-Navi runs the eci on the board (a task); for the baseline it is what it would cost there.
  result.eci_time_ms_mean = acc[TaskId::kEci].started > 0 ? 1e3 * acc[TaskId::kEci].MeanCost()
                            : frame_index > 0             ? 1e3 * eci_cost_sum / frame_index
                                                          : 0.0;
  result.adapter_time_ms_mean = 1e3 * acc[TaskId::kAdapter].MeanCost();
  for (const auto& [k, v] : acc.notes) result.notes[k] = v;
  return result;
}

}  // namespace enavi::sim
