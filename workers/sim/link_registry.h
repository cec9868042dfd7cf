#pragma once
// The links an episode can run its stack on (STYLE.md rule 13: registered once, by name). A link
// is chosen by the kind of method (a method of navstack's registry, or a user's ROS stack) and
// the spec's clock; a library above workers/sim registers its own (the emulated clock's,
// emulation::RegisterEmulatedLink; the ROS bridge's, ros::RegisterRosLink) without an edit here.
// The virtual clock's link (in process, virtual_nav_link.h) is built in. The farm's list of clocks
// (Clocks()) is the clocks the registered methods' links run on.

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "api/episode.h"
#include "navstack/common/camera.h"
#include "navstack/common/state.h"
#include "navstack/methods/method.h"
#include "navstack/runtime/executor.h"
#include "workers/board/board_profile.h"
#include "workers/emulation/emulation_options.h"
#include "workers/sim/nav_link.h"

namespace enavi::sim {

/// Kinds of method (LinkInfo::kind): a method of navstack's registry, run on a TaskExecutor of
/// the link's clock; and a user's ROS stack (spec.ros), which runs as processes of its own.
inline constexpr const char* kNavstackMethod = "navstack";
inline constexpr const char* kRosMethod = "ros";

/// The kind of method `spec` flies.
std::string MethodKindOf(const api::EpisodeSpec& spec);

/// What a link is built from: the episode as the stack sees it. Pointers are valid while the
/// factory runs; a link copies what it keeps.
struct LinkRequest {
  const api::EpisodeSpec* spec = nullptr;
  const board::BoardProfile* board = nullptr;
  /// kNavstackMethod: the method and its options (null for a stack of its own processes).
  const navstack::MethodInfo* method = nullptr;
  const navstack::MethodOptions* nav = nullptr;
  int threads = 1;  ///< threads the jobs may use, at most the board's cores
  navstack::SchedulingPolicy policy = navstack::SchedulingPolicy::kGlobalEdf;
  navstack::VehicleState initial;  ///< hovering at the start
  // The mission as an outside stack is told it (kRosMethod).
  Eigen::Vector3d start = Eigen::Vector3d::Zero(), goal = Eigen::Vector3d::Zero();
  double start_yaw = 0;
  Eigen::AlignedBox3d bounds;
  navstack::CameraIntrinsics camera;
  Eigen::Isometry3d X_BC = Eigen::Isometry3d::Identity();  ///< the camera's optical frame in the body
  /// Sees every job with its host CPU time (calibration; the in-process links).
  navstack::JobObserver job_observer;
  /// The emulated clock's knobs, the spec's speed_probe applied (links that run on wall time).
  const emulation::EmulationOptions* emulation = nullptr;
  std::string output_dir;  ///< where an outside stack's logs go (empty: a temporary directory)
  std::string bag_file;    ///< the bag an outside stack's episode records (empty: none)
};

using LinkFactory = std::function<std::unique_ptr<NavLink>(const LinkRequest&)>;

struct LinkInfo {
  std::string kind;     ///< kNavstackMethod, kRosMethod, ...
  std::string clock;    ///< what EpisodeSpec::clock, job specs and `--clock` say
  std::string summary;  ///< one line for help texts (the clock's, for kNavstackMethod)
  LinkFactory make;  ///< may be empty when `unavailable` says why
  /// Why it cannot run in this process although known (this enavi was built without the ROS
  /// bridge; ROS is not installed on this host); empty: it can.
  std::string unavailable;
};

/// Adds a link. A second registration of the same kind and clock replaces the first (the ROS
/// bridge replaces the built-in entry that says it was not built).
/// @throws std::invalid_argument for an empty kind or clock, or a link without a factory that
///   does not say why it cannot run.
void RegisterLink(LinkInfo link);
/// The registered links: the built-in ones first (the virtual clock's; the ROS bridge's, marked
/// not built until ros::RegisterRosLink replaces it), then in registration order.
std::vector<LinkInfo> Links();
/// The link for `kind` on `clock`, or an empty optional.
std::optional<LinkInfo> FindLink(const std::string& kind, const std::string& clock);
/// Why a method of `kind` cannot fly on `clock` in this process (no such link, or its
/// `unavailable`); empty when it can. A worker offers what can fly (WorkerStatus::features).
std::string LinkUnavailableReason(const std::string& kind, const std::string& clock);
/// Builds the link `spec` runs on. @throws std::invalid_argument for a clock no link of the
/// spec's kind runs on (naming those that do), or a link that cannot run here (its reason).
std::unique_ptr<NavLink> MakeLink(const LinkRequest& request);

/// A clock the navigation stack can run on (docs/design.md, "Time: two clocks").
struct ClockInfo {
  std::string name;
  std::string summary;
};
/// The clocks registered methods can run on, in registration order: the farm's one list of
/// clocks (the CLI's choices, job validation, a worker's capabilities read it).
std::vector<ClockInfo> Clocks();

}  // namespace enavi::sim
