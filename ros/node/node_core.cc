#include "ros/node/node_core.h"

#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>

#include "api/fixed.h"
#include "navstack/control/vehicle.h"
#include "navstack/methods/method_config.h"
#include "navstack/methods/reference_tracker.h"
#include "navstack/methods/registry.h"
#include "navstack/rl/shipped_policy.h"
#include "navstack/runtime/realtime_executor.h"

namespace enavi::rosnode {
namespace {

using api::Fixed;
using navstack::TaskId;

std::string KnownMethods() {
  std::string known;
  for (const std::string& n : navstack::MethodNames()) known += (known.empty() ? "" : ", ") + n;
  return known;
}

}  // namespace

struct NodeCore::Impl {
  NodeParams params;
  std::shared_ptr<navstack::SteppedClock> clock;
  const navstack::MethodInfo* method = nullptr;
  navstack::MethodConfig config;
  int cores = 1, threads = 1;

  // Inputs: what the method is built from, the newest odometry, the frame being assembled.
  std::mutex in_mutex;
  std::optional<Eigen::Vector3d> goal;
  std::optional<navstack::CameraIntrinsics> intrinsics;
  std::optional<navstack::VehicleState> state;          // the newest odometry
  std::optional<navstack::VehicleState> pending_state;  // not yet handed to the running method
  std::optional<std::pair<double, navstack::DepthImage>> image;
  std::optional<std::pair<double, Eigen::Isometry3d>> pose;
  navstack::DepthFramePtr early_frame;  // the newest frame before the method ran
  std::int64_t frames_assembled = 0, frames_delivered = 0, odometry_applied = 0;
  double started_at = -1;

  std::unique_ptr<navstack::RealtimeExecutor> exec;
  std::unique_ptr<navstack::Navigator> nav;
  std::atomic<bool> running{false};

  // What the controller tracks, looked at after each commit and each frame (exclusive job lock).
  navstack::ReferenceTracker tracker;
  mutable std::mutex out_mutex;
  navstack::PublishedReference published;
  std::uint32_t trajectory_id = 0;
  std::map<std::string, std::int64_t> events;

  ~Impl() {
    if (exec) exec->Stop();  // the jobs use the method: they end first
    nav.reset();
    exec.reset();
  }

  // Caller holds the exclusive job lock.
  void Look() {
    const double now = exec->now();
    const bool changed = tracker.Update(*nav, now);
    std::vector<navstack::NavEvent> new_events = nav->TakeEvents();
    std::lock_guard g(out_mutex);
    published = tracker.reference();
    if (changed && published.current) ++trajectory_id;
    for (const navstack::NavEvent& e : new_events) ++events[e.kind + (e.kind == "replan" ? " (" + e.detail + ")" : "")];
  }

  // Caller holds in_mutex. Builds and starts the method once everything it needs has arrived.
  void TryStartLocked() {
    if (running || !goal || !intrinsics || !state) return;
    navstack::MethodOptions options = config.nav;
    options.goal = *goal;
    options.flight_bounds = params.bounds;
    options.camera = *intrinsics;
    options.camera.min_range = params.depth_min;
    options.camera.max_range = params.depth_max;
    // As the farm's episode: plans keep the vehicle's frame and propellers clear.
    options.planner.robot_radius = std::max(options.planner.robot_radius, navstack::VehicleParams{}.collision_radius);

    navstack::RealtimeExecutorOptions eo;
    eo.threads = threads;
    eo.policy = config.scheduler.policy;
    eo.clock = clock;
    eo.timing = navstack::JobTiming::kElapsed;
    eo.on_worker_start = [](int w) { pthread_setname_np(pthread_self(), ("nav-worker-" + std::to_string(w)).c_str()); };
    eo.after_commit = [this](TaskId) { Look(); };
    exec = std::make_unique<navstack::RealtimeExecutor>(eo);
    nav = method->make(options, exec.get(), *state);
    exec->Launch();
    std::ofstream("/proc/self/task/" + std::to_string(exec->ReleaseThreadTid()) + "/comm") << "nav-release";
    if (early_frame && early_frame->image.width == options.camera.width && early_frame->image.height == options.camera.height) {
      nav->OnFrame(early_frame);
      ++frames_delivered;
    }
    early_frame.reset();
    Look();
    exec->Start();
    started_at = exec->now();
    running = true;
  }

  // A frame whose image and pose have both arrived (caller holds in_mutex); null otherwise.
  navstack::DepthFramePtr MatchLocked() {
    if (!image || !pose || image->first != pose->first) return nullptr;
    auto frame = std::make_shared<navstack::DepthFrame>();
    frame->index = frames_assembled++;
    frame->t = image->first;
    frame->image = std::move(image->second);
    frame->X_WC = pose->second;
    frame->v_W = state ? state->v_WB : Eigen::Vector3d::Zero();
    image.reset();
    pose.reset();
    return frame;
  }

  void Deliver(navstack::DepthFramePtr frame) {
    if (!frame) return;
    {
      std::lock_guard g(in_mutex);
      if (!running) {
        early_frame = std::move(frame);
        return;
      }
    }
    // As the emulated clock's navstack process: a frame waits for running jobs (they read the
    // state at their start), with the odometry that could not be applied before it.
    std::unique_lock lock(exec->job_lock());
    std::optional<navstack::VehicleState> odom;
    {
      std::lock_guard g(in_mutex);
      odom = std::exchange(pending_state, std::nullopt);
      if (odom) ++odometry_applied;
      ++frames_delivered;
    }
    if (odom) nav->OnState(*odom);
    nav->OnFrame(std::move(frame));
    Look();
  }
};

NodeCore::NodeCore(const NodeParams& params, std::shared_ptr<navstack::SteppedClock> clock)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.params = params;
  m.clock = std::move(clock);
  m.method = navstack::FindMethod(params.method);
  if (!m.method)
    throw std::invalid_argument("method: unknown method '" + params.method + "' (known: " + KnownMethods() + ")");
  navstack::MethodSetup setup;
  setup.seed = params.seed;
  if (m.method->uses_policy) {
    setup.policy = navstack::rl::LoadPolicyOrShipped(params.policy);
  } else if (!params.policy.empty()) {
    throw std::invalid_argument("policy: method " + params.method + " reads no frequency-adapter policy");
  }
  m.config = navstack::ConfigureMethodWithOverrides(*m.method, setup, params.overrides);
  if (params.cores < 0) throw std::invalid_argument("cores: " + std::to_string(params.cores) + " is negative");
  m.cores = params.cores > 0 ? params.cores : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  m.threads = m.config.scheduler.threads > 0 ? std::min(m.config.scheduler.threads, m.cores) : m.cores;
  if (params.bounds.isEmpty()) throw std::invalid_argument("bounds: the flight bounds are empty (bounds_min > bounds_max)");
  if (!(params.depth_min >= 0 && params.depth_min < params.depth_max))
    throw std::invalid_argument("depth_min, depth_max: " + Fixed(params.depth_min, 3) + ", " + Fixed(params.depth_max, 3) +
                                " is not a range 0 <= min < max");
}

NodeCore::~NodeCore() = default;

void NodeCore::OnGoal(const Eigen::Vector3d& goal) {
  std::lock_guard g(impl_->in_mutex);
  if (impl_->running) return;  // a method's goal is fixed when it is built
  impl_->goal = goal;
  impl_->TryStartLocked();
}

void NodeCore::OnCameraInfo(const navstack::CameraIntrinsics& intrinsics) {
  std::lock_guard g(impl_->in_mutex);
  if (impl_->running) return;
  impl_->intrinsics = intrinsics;
  impl_->TryStartLocked();
}

void NodeCore::OnOdometry(const navstack::VehicleState& state) {
  Impl& m = *impl_;
  {
    std::lock_guard g(m.in_mutex);
    m.state = state;
    if (!m.running) {
      m.TryStartLocked();
      return;
    }
    m.pending_state = state;
  }
  // Odometry does not wait for running jobs; what cannot be applied now goes with the next frame
  // or odometry.
  if (!m.exec->job_lock().try_lock()) return;
  std::optional<navstack::VehicleState> odom;
  {
    std::lock_guard g(m.in_mutex);
    odom = std::exchange(m.pending_state, std::nullopt);
    if (odom) ++m.odometry_applied;
  }
  if (odom) m.nav->OnState(*odom);
  m.exec->job_lock().unlock();
}

void NodeCore::OnDepth(double stamp, navstack::DepthImage image) {
  navstack::DepthFramePtr frame;
  {
    std::lock_guard g(impl_->in_mutex);
    Impl& m = *impl_;
    if (m.pose && m.pose->first < stamp) m.pose.reset();  // its image never came
    m.image.emplace(stamp, std::move(image));
    frame = m.MatchLocked();
  }
  impl_->Deliver(std::move(frame));
}

void NodeCore::OnCameraPose(double stamp, const Eigen::Isometry3d& X_WC) {
  navstack::DepthFramePtr frame;
  {
    std::lock_guard g(impl_->in_mutex);
    Impl& m = *impl_;
    if (m.image && m.image->first < stamp) m.image.reset();  // its pose never came
    m.pose.emplace(stamp, X_WC);
    frame = m.MatchLocked();
  }
  impl_->Deliver(std::move(frame));
}

std::optional<CommandSample> NodeCore::Sample() {
  const Impl& m = *impl_;
  if (!m.running) return std::nullopt;
  CommandSample s;
  s.t = std::max(0.0, m.clock->Now());
  std::lock_guard g(m.out_mutex);
  s.reference = m.published.Sample(s.t);
  s.trajectory_id = m.trajectory_id;
  s.following = m.published.following && m.published.current;
  return s;
}

std::string NodeCore::error() const {
  std::lock_guard g(impl_->in_mutex);
  return impl_->exec ? impl_->exec->error() : std::string();
}

bool NodeCore::running() const { return impl_->running; }

std::string NodeCore::Describe() const {
  const Impl& m = *impl_;
  const bool edf = m.config.scheduler.policy == navstack::SchedulingPolicy::kGlobalEdf;
  return "method " + m.method->name + " (seed " + std::to_string(m.params.seed) + ") on " + std::to_string(m.threads) +
         " thread(s), " + (edf ? "global EDF" : "FIFO without preemption") + ", of " + std::to_string(m.cores) +
         " core(s)" + (m.params.cores > 0 ? "" : " (this machine's)") + "; releases and job times in ROS time";
}

std::string NodeCore::Summary() const {
  Impl& m = *impl_;
  std::lock_guard g(m.in_mutex);
  if (!m.exec) return "the method never ran (it needs the goal, odometry and camera_info)";
  std::string out = "started at t = " + Fixed(m.started_at, 3) + " s; frames " + std::to_string(m.frames_delivered) +
                    " of " + std::to_string(m.frames_assembled) + " assembled handed over, odometry applied " +
                    std::to_string(m.odometry_applied) + ", plan failures " + std::to_string(m.nav->plan_failures());
  {
    std::lock_guard o(m.out_mutex);
    out += "; trajectories " + std::to_string(m.trajectory_id) + "; events:";
    for (const auto& [kind, n] : m.events) out += " " + kind + " " + std::to_string(n) + ";";
  }
  const auto all = m.exec->AllStats();
  for (int i = 0; i < navstack::kTaskCount; ++i) {
    const navstack::TaskStats& s = all[i];
    if (s.released == 0) continue;
    out += "\ntask." + std::string(navstack::TaskName(static_cast<TaskId>(i))) + ": released " +
           std::to_string(s.released) + ", late " + std::to_string(s.late) + ", skipped " + std::to_string(s.skipped) +
           ", mean job " + Fixed(1e3 * s.MeanCost(), 3) + " ms, max " + Fixed(1e3 * s.cost_max_s, 3) +
           " ms (ROS time), host CPU " + Fixed(s.host_cpu_s, 3) + " s";
  }
  return out;
}

void NodeCore::Stop() {
  Impl& m = *impl_;
  navstack::RealtimeExecutor* exec = nullptr;
  {
    std::lock_guard g(m.in_mutex);
    exec = m.exec.get();
  }
  if (exec) exec->Stop();
}

}  // namespace enavi::rosnode
