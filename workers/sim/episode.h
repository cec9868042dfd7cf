#pragma once
// One flight episode (docs/design.md, "One episode"): world -> depth camera -> navigation stack under the
// board's executor -> controller -> physics, in sim time, with the measured results.

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "api/episode.h"
#include "navstack/eci/eci.h"
#include "navstack/rl/rollout.h"
#include "navstack/runtime/executor.h"
#include "workers/board/board_profile.h"
#include "workers/emulation/emulation_options.h"
#include "workers/sim/nav_link.h"
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
  std::size_t triangles = 0;
};
std::shared_ptr<const PreparedWorld> PrepareWorld(worlds::World world);

/// The world an episode spec names (id or file, seed, params, start, goal, mesh placement,
/// model path), as a request for worlds::ResolveWorld. Throws worlds::WorldError on a bad
/// placement (unknown unit, up axis, scale out of range).
worlds::WorldRequest WorldRequestOf(const api::EpisodeSpec& spec);

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
  /// The emulated clock (spec.clock == "emulated"): host calibration file and test knobs.
  emulation::EmulationOptions emulation;
  /// ROS methods: where the episode's ROS logs go (empty: a temporary directory, removed), and
  /// the bag to record (empty: spec.rosbag_dir's, or none).
  std::string ros_output_dir;
  std::string ros_bag_file;
};

/// What the ROS bridge's link is built from: the episode as the stack sees it.
struct RosLinkRequest {
  const api::EpisodeSpec* spec = nullptr;
  const board::BoardProfile* board = nullptr;
  Eigen::Vector3d start = Eigen::Vector3d::Zero(), goal = Eigen::Vector3d::Zero();
  double start_yaw = 0;
  Eigen::AlignedBox3d bounds;
  navstack::CameraIntrinsics camera;
  Eigen::Isometry3d X_BC = Eigen::Isometry3d::Identity();  ///< the camera's optical frame in the body
  navstack::VehicleState initial;
  const EpisodeOptions* options = nullptr;
  std::string bag_file;  ///< empty: no recording
};
/// Makes the link of a ROS method (spec.ros). The ROS bridge (workers/ros) sits above this
/// library; the composition root registers it where it was built (RegisterRosLink).
using RosLinkFactory = std::function<std::unique_ptr<NavLink>(const RosLinkRequest&)>;
void SetRosLinkFactory(RosLinkFactory factory);
/// Why ROS methods cannot fly here (the bridge was registered, but ROS is not installed on this
/// host): the error an episode of one gives.
void SetRosLinkUnavailable(std::string reason);
/// Whether ROS methods can fly here: the bridge was built and registered, and ROS is installed.
bool RosLinkAvailable();
/// Why not (empty when they can).
std::string RosLinkUnavailableReason();

/// A clock the navigation stack can run on (docs/design.md, "Time: two clocks").
struct ClockInfo {
  std::string name;     ///< what EpisodeSpec::clock, job specs and `--clock` say
  std::string summary;  ///< one line for help texts
};
/// The registered clocks, in a fixed order: the farm's one list of clocks (the CLI's choices,
/// job validation, a worker's capabilities read it).
const std::vector<ClockInfo>& Clocks();

/// Flies `spec` in `world`. Bad specs (unknown board/method, bad overrides) throw
/// std::invalid_argument; a flight that fails (collision, timeout) is a result, not an error.
api::EpisodeResult RunEpisode(const api::EpisodeSpec& spec, const PreparedWorld& world,
                              const EpisodeOptions& options = {});

/// Resolves the spec's world (generator id, .yaml or .obj), prepares it and flies.
api::EpisodeResult RunEpisode(const api::EpisodeSpec& spec, const EpisodeOptions& options = {});

}  // namespace enavi::sim
