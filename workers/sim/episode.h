#pragma once
// One flight episode (docs/design.md, "One episode"): world -> depth camera -> navigation stack
// on its link -> controller -> physics, in sim time, with the measured results. Shaped like
// MuJoCo's mjModel / mjData: an EpisodeModel is what is fixed for the episode, built once from
// the spec; an Episode owns its mutable state and advances it one physics step per Step().
// RunEpisode is the loop over Step that `enavi fly`, the farm's episode child, training and the
// tests run; the Python environment (python/env_core.h) steps an Episode itself.

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "api/episode.h"
#include "navstack/control/controller.h"
#include "navstack/eci/eci.h"
#include "navstack/rl/decision_port.h"
#include "navstack/rl/rollout.h"
#include "navstack/runtime/executor.h"
#include "workers/board/board_profile.h"
#include "workers/emulation/emulation_options.h"
#include "workers/sim/depth_camera.h"
#include "workers/sim/episode_config.h"
#include "workers/sim/episode_monitor.h"
#include "workers/sim/episode_movers.h"
#include "workers/sim/link_registry.h"
#include "workers/sim/nav_link.h"
#include "workers/sim/odometry_noise.h"
#include "workers/sim/quadrotor.h"
#include "workers/sim/wind.h"
#include "worlds/resolve.h"
#include "worlds/world.h"

namespace enavi::sim {

class EmbreeScene;
class StaticCollisionWorld;

/// A world ready to fly: its geometry as an Embree scene and a Bullet shape, built once and
/// shared read-only by every episode flown in it.
struct PreparedWorld {
  worlds::World world;
  std::shared_ptr<const EmbreeScene> scene;
  std::shared_ptr<const StaticCollisionWorld> collision;
  std::shared_ptr<const PreparedMovers> movers;  ///< null without movers (workers/sim/episode_movers.h)
  std::size_t triangles = 0;
};
std::shared_ptr<const PreparedWorld> PrepareWorld(worlds::World world);

/// The world an episode spec names (id or file, seed, params, start, goal, mesh placement,
/// model path), as a request for worlds::ResolveWorld. Throws worlds::WorldError on a bad
/// placement (unknown unit, up axis, scale out of range).
worlds::WorldRequest WorldRequestOf(const api::EpisodeSpec& spec);
/// The world `spec` names, resolved (generated or read) and prepared.
/// @throws as WorldRequestOf and worlds::ResolveWorld.
std::shared_ptr<const PreparedWorld> PrepareSpecWorld(const api::EpisodeSpec& spec);

/// One depth frame's eci as the episode computed it (the metric, on every frame at f_sen).
struct EciFrame {
  double t = 0;                 ///< s, sim time of the frame
  navstack::EciResult eci;
  double speed = 0;             ///< m/s, vehicle speed
  double camera_pitch_deg = 0;  ///< optical axis above the horizontal (+: nose up)
  bool in_flight = false;       ///< counts for eci.flight_min / flight_max (after take-off)
};

struct EpisodeOptions {
  double physics_dt = 0.001;  ///< 1 kHz
  double control_dt = 0.005;  ///< 200 Hz, on the flight controller (not the board)
  double series_dt = 0.1;     ///< time-series sampling for plots
  double goal_radius = 0.5;   ///< m
  /// Called about once per simulated second with the sim time and the distance to the goal.
  std::function<void(double t, double distance_to_goal)> progress;
  /// Sees every navstack job (and every eci computation) with its host CPU time: calibration.
  navstack::JobObserver job_observer;
  /// Sees the eci of every depth frame (`enavi fly --out` writes them to eci_frames.csv).
  std::function<void(const EciFrame&)> eci_observer;
  /// E-Navi training: when set, the Strategy Controller records its decisions and rewards here.
  navstack::rl::Rollout* rollout = nullptr;
  /// E-Navi's sampled decisions are taken outside the stack, one at a time (the Python
  /// environment): Step() returns kAwaitingDecision with one pending here. Virtual clock only.
  navstack::rl::DecisionPort* decisions = nullptr;
  /// The emulated clock (spec.clock == "emulated"): host calibration file and test knobs.
  emulation::EmulationOptions emulation;
  /// ROS methods: where the episode's ROS logs go (empty: a temporary directory, removed), and
  /// the bag to record (empty: spec.rosbag_dir's, or none).
  std::string ros_output_dir;
  std::string ros_bag_file;
};

/// What is fixed for one episode, built once from its spec and read-only while it flies.
struct EpisodeModel {
  api::EpisodeSpec spec;
  const PreparedWorld* world = nullptr;  ///< outlives the episode
  board::BoardProfile board;
  EpisodeConfig config;  ///< the method, its options (goal, bounds, radius set), scheduler, noise
  navstack::VehicleParams vehicle;
  DepthCamera camera;
  EpisodeOptions options;
  std::string scenario = {};  ///< the world's scenario id, or "custom"
  double straight_line_m = 0;
  double start_yaw = 0;  ///< facing the goal
  double timeout_s = 0;  ///< the spec's, else 20 s + 6 x straight line / v_max
  double frame_dt = 0;   ///< 1 / f_sen
  long control_every = 1, record_every = 1, series_every = 1;  ///< in physics steps
  int threads = 1;       ///< threads the stack's jobs may use
  std::map<std::string, std::string> notes = {};  ///< how the result is produced, known before it flies
};

/// Builds the model of `spec` in `world`. Bad specs (unknown board/method, bad overrides) throw
/// std::invalid_argument.
EpisodeModel MakeEpisodeModel(const api::EpisodeSpec& spec, const PreparedWorld& world,
                              const EpisodeOptions& options = {});

/// How an episode ended: a value, applied to the result when it finishes.
struct EpisodeEnd {
  std::string reason;  ///< goal_reached, collision, timeout, or the link's (stack_exited, ...)
  bool success = false, collided = false, timed_out = false;
  std::optional<ContactEvent> contact = {};  ///< a collision's first contact
  std::optional<std::string> detail = {};  ///< what the link that ended it said (notes["end_detail"])
};

/// One way a flight ends, checked after every step in registration order (end_conditions.cc).
struct EndCondition {
  std::string name;
  std::function<std::optional<EpisodeEnd>(const EpisodeModel&, const StepView&, const QuadrotorSim&)> check;
};
/// Goal reached, collision, timeout: the conditions every episode ends on.
std::vector<EndCondition> EndConditions();

enum class StepStatus {
  kRunning,           ///< the step is done; call Step() again
  kAwaitingDecision,  ///< a decision waits in EpisodeOptions::decisions: supply it, then Step() again
  kEnded,             ///< the episode ended (end()); call Finish()
};

/// One episode in flight: the model and its mutable state (time, vehicle, controller, the stack
/// on its link, the monitors that measure it).
class Episode {
 public:
  /// Builds the model and the state at t = 0: the vehicle hovering at the start facing the goal,
  /// the stack started on its link (emulated: its process running in the board's groups).
  /// `world` must outlive the episode. Throws as MakeEpisodeModel and the link's factory do.
  Episode(const api::EpisodeSpec& spec, const PreparedWorld& world, const EpisodeOptions& options = {});
  ~Episode();
  Episode(const Episode&) = delete;
  Episode& operator=(const Episode&) = delete;

  /// Advances one physics step: odometry and (at f_sen) a depth frame to the stack, the stack to
  /// this instant, the controller (every control_dt), the monitors, the end conditions, then
  /// physics. After kAwaitingDecision the next Step goes on from the same instant.
  /// @throws std::logic_error after the end, or when a decision is still waiting for its action.
  StepStatus Step();
  /// Closes the stack (rollouts get their last reward) and writes the results. Once, after
  /// Step() returned kEnded. @throws std::logic_error before the end.
  api::EpisodeResult Finish();
  /// Ends the flight from outside at its current step (the navigation environment's flight
  /// bounds); then Finish(). @throws std::logic_error after the end or with a decision pending.
  void Stop(EpisodeEnd end);

  const EpisodeModel& model() const { return model_; }
  double t() const;                                     ///< sim time of the next step
  const navstack::VehicleState& vehicle() const { return vehicle_; }  ///< at the last step
  const NavLink& link() const { return *link_; }
  const std::optional<EpisodeEnd>& end() const { return end_; }

 private:
  void Sense(double t);

  const EpisodeModel model_;
  // Mutable state.
  QuadrotorSim quad_;
  navstack::Controller controller_;
  std::unique_ptr<NavLink> link_;
  std::vector<std::unique_ptr<EpisodeMonitor>> monitors_;
  std::vector<EndCondition> end_conditions_;
  long k_ = 0;                 ///< physics steps taken
  bool resuming_ = false;      ///< step k_ stopped in the stack, waiting for a decision
  navstack::VehicleState vehicle_;   ///< the truth
  navstack::VehicleState estimate_;  ///< what the stack and the controller are told (odometry_)
  std::optional<WindField> wind_;    ///< the spec's air; none in still air
  std::optional<OdometryNoise> odometry_;  ///< the spec's odometry noise; none: the truth
  std::optional<EpisodeMovers> movers_;    ///< the world's movers; none in a static world
  Eigen::Vector3d p_ref_;      ///< the reference position the controller tracks
  double next_frame_t_ = 0;
  std::int64_t frame_index_ = 0;
  std::optional<EpisodeEnd> end_;
  bool finished_ = false;
};

/// Flies `spec` in `world`: Episode's Step until it ends, then Finish. Bad specs (unknown
/// board/method, bad overrides) throw std::invalid_argument; a flight that fails (collision,
/// timeout) is a result, not an error.
api::EpisodeResult RunEpisode(const api::EpisodeSpec& spec, const PreparedWorld& world,
                              const EpisodeOptions& options = {});

/// Resolves the spec's world (generator id, .yaml or .obj), prepares it and flies.
api::EpisodeResult RunEpisode(const api::EpisodeSpec& spec, const EpisodeOptions& options = {});

}  // namespace enavi::sim
