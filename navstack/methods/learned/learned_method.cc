#include "navstack/methods/learned/learned_method.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "navstack/methods/method_util.h"
#include "navstack/rl/decision_port.h"
#include "navstack/rl/nav_policy.h"
#include "navstack/rl/random.h"

namespace enavi::navstack {
namespace {

constexpr TaskId kInference = TaskId::kPerception;

// A velocity setpoint in the yaw frame at the instant it landed, and where it was anchored.
struct Command {
  double t = 0;
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_W = Eigen::Vector3d::Zero();
  double yaw = 0, yaw_rate = 0;
};

class LearnedNavigator final : public Navigator {
 public:
  LearnedNavigator(const MethodOptions& o, TaskExecutor* exec, const VehicleState& s0)
      : options_(o), exec_(exec), state_(s0), hold_(HoldAt(s0.p_WB, YawOf(s0.q_WB))),
        zero_latency_(o.Param("learned.zero_latency") > 0), explore_(o.Param("learned.explore") > 0),
        rng_(rl::NavExploreSeed(o.seed)) {
    if (o.nav_policy) {
      // The file's network: its image size, range and action scale, also when its actions are
      // taken outside (a collection job's worker draws them from it).
      net_ = o.nav_policy;
      width_ = net_->width();
      height_ = net_->height();
      max_depth_ = net_->max_depth_m();
      scale_ = net_->action_scale();
      if (o.Param("learned.multiply_adds") > 0)
        throw std::invalid_argument("learned.multiply_adds: the policy file's network has its own count (" +
                                    std::to_string(net_->multiply_adds()) + "); set it only for actions from outside");
      multiply_adds_ = net_->multiply_adds();
      if (explore_ && !net_->log_std())
        throw std::invalid_argument("learned.explore: the policy file has no log_std to sample with");
    } else {
      // Actions from outside (the Python environment): the observation at the stream's own size,
      // the default scales.
      width_ = o.camera.width;
      height_ = o.camera.height;
      max_depth_ = o.camera.max_range;
      scale_ = {o.planner.v_max, o.planner.v_max, 1.0, 1.0};
      multiply_adds_ = static_cast<std::int64_t>(o.Param("learned.multiply_adds"));
    }
    if (o.camera.width % width_ != 0 || o.camera.width / width_ != o.camera.height / height_ ||
        o.camera.height % height_ != 0)
      throw std::invalid_argument("policy: the network reads " + std::to_string(width_) + "x" +
                                  std::to_string(height_) + " images, the depth stream is " +
                                  std::to_string(o.camera.width) + "x" + std::to_string(o.camera.height) +
                                  " (set camera.decimation to a multiple, or leave it to the policy)");
    exec_->Register(kInference, [this] { return Infer(); });
    exec_->SetRate(kInference, 0.0);
  }

  void OnFrame(DepthFramePtr frame) override {
    frame_ = std::move(frame);
    exec_->Trigger(kInference, 1.0 / options_.f_sen);
  }
  void OnState(const VehicleState& s) override { state_ = s; }

  TrajectorySample Reference(double t) const override {
    if (!command_) return hold_;
    const Command& c = *command_;
    const double dt = std::max(0.0, t - c.t);
    TrajectorySample s;
    s.p = c.p_W + c.v_W * dt;
    s.v = c.v_W;
    s.yaw = WrapAngle(c.yaw + c.yaw_rate * dt);
    s.yaw_rate = c.yaw_rate;
    return s;
  }
  std::vector<NavEvent> TakeEvents() override { return {}; }
  TaskRates rates() const override {
    TaskRates r;
    r.f_per = options_.f_sen;  // an inference per frame
    r.f_plan = 0;
    r.collision_on_map_update = false;
    r.resolution = 0;
    return r;
  }
  double map_resolution() const override { return 0; }
  std::shared_ptr<const Trajectory> trajectory() const override { return nullptr; }
  std::int64_t plan_failures() const override { return 0; }

 private:
  JobOutput Infer() {
    JobOutput out;
    if (!frame_) return out;
    const rl::NavObservation obs = rl::MakeNavObservation(frame_->image, state_, options_.goal, width_, height_,
                                                          max_depth_, scale_);
    if (!zero_latency_) {
      out.work.Add(WorkUnit::kPixel, static_cast<std::int64_t>(frame_->image.data.size()));
      out.work.Add(WorkUnit::kPolicyFlop, multiply_adds_);
    }
    if (options_.decisions != nullptr) {
      Eigen::VectorXd flat(static_cast<Eigen::Index>(obs.depth.size()) + rl::kNavStateSize);
      for (std::size_t i = 0; i < obs.depth.size(); ++i) flat[static_cast<Eigen::Index>(i)] = obs.depth[i];
      flat.tail<rl::kNavStateSize>() = obs.state;
      options_.decisions->OpenContinuous(flat, rl::kNavActionSize);
      out.awaits_decision = true;
      out.commit = [this] { Apply(options_.decisions->TakeVector()); };
    } else {
      const Eigen::VectorXd action = explore_ ? Eigen::VectorXd(rl::SampleNavAction(*net_, obs, &rng_).action)
                                              : Eigen::VectorXd(net_->Forward(obs));
      out.commit = [this, action] { Apply(action); };
    }
    return out;
  }

  // The action (each in [-1, 1], clipped) as a setpoint from the vehicle's pose when it lands.
  void Apply(const Eigen::VectorXd& action) {
    const Eigen::Vector4d a = action.head<4>().cwiseMax(-1.0).cwiseMin(1.0);
    Command c;
    c.t = exec_->now();
    c.p_W = state_.p_WB;
    c.yaw = YawOf(state_.q_WB);
    const Eigen::Vector3d v_Y(a[0] * scale_[0], a[1] * scale_[1], a[2] * scale_[2]);
    c.v_W = Eigen::AngleAxisd(c.yaw, Eigen::Vector3d::UnitZ()) * v_Y;
    c.yaw_rate = a[3] * scale_[3];
    command_ = c;
  }

  MethodOptions options_;
  TaskExecutor* exec_;
  VehicleState state_;
  TrajectorySample hold_;  ///< before the first action: hover at the start
  bool zero_latency_;
  bool explore_;  ///< sample the file's Gaussian instead of taking its mean
  rl::Rng rng_;
  std::shared_ptr<const rl::NavPolicyNet> net_;  ///< null: actions from outside, no file
  std::int64_t multiply_adds_ = 0;
  int width_ = 0, height_ = 0;
  double max_depth_ = 10;
  std::array<double, rl::kNavActionSize> scale_{};
  DepthFramePtr frame_;
  std::optional<Command> command_;
};

}  // namespace

MethodInfo LearnedMethod() {
  MethodInfo m;
  m.name = "learned";
  m.summary = "a trained navigation policy (--policy FILE): depth and state in, velocity out, at the board's latency";
  m.scheduler = {SchedulingPolicy::kGlobalEdf, 1};
  // Its one job runs our network code (nav_policy.cc), priced per multiply-add as the frequency
  // adapter's network.
  m.cost_family = "navstack";
  m.uses_nav_policy = true;
  m.external_decisions = true;
  m.task_keys[static_cast<int>(kInference)] = "inference";
  m.task_labels[static_cast<int>(kInference)] = "policy inference";
  m.tunables = {{"learned.zero_latency", 0, 1, 0, true,
                 "1: the inference is free and its action applies at the frame's instant (no board in the loop)"},
                {"learned.multiply_adds", 0, 1e9, 0, true,
                 "multiply-adds per inference when the actions come from outside (the Python environment's network); "
                 "a policy file counts its own"},
                {"learned.explore", 0, 1, 0, true,
                 "1: each action drawn from the policy file's Gaussian (its log_std), seeded by the episode's seed; "
                 "a collection job sets it from `sample`"}};
  m.configure = [](const MethodSetup& setup, MethodOptions* o) {
    if (!setup.nav_policy && setup.decisions) return;  // the Python environment sets the camera
    if (!setup.nav_policy)
      throw std::invalid_argument("policy: method learned needs a nav policy file (--policy FILE; "
                                  "examples/torch_nav_ppo.py trains one)");
    // The depth stream at the network's resolution (a whole decimation of the 640x480 sensor).
    const rl::NavPolicyNet& net = *setup.nav_policy;
    const CameraIntrinsics sensor = CameraIntrinsics::Default();
    if (sensor.width % net.width() == 0 && sensor.width / net.width() == sensor.height / net.height() &&
        sensor.height % net.height() == 0)
      o->camera = sensor.Decimated(sensor.width / net.width());
  };
  m.make = [](const MethodOptions& o, TaskExecutor* e, const VehicleState& s) {
    return std::unique_ptr<Navigator>(std::make_unique<LearnedNavigator>(o, e, s));
  };
  return m;
}

}  // namespace enavi::navstack
