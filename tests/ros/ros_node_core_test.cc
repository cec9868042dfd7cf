// Our ROS node's core (ros/node/node_core.h) without ROS or a master: its parameters are checked
// as `enavi fly --set` checks them; the method starts once it has its goal, odometry and camera
// intrinsics; it then runs its jobs in ROS time, set step by step here as /clock sets it, and
// its reference turns into a trajectory towards the goal. Waits are bounded polls.
#include "ros/node/node_core.h"

#include <chrono>
#include <cmath>
#include <regex>
#include <stdexcept>
#include <string>
#include <thread>

#include <gtest/gtest.h>

namespace enavi::rosnode {
namespace {

using namespace std::chrono_literals;

NodeParams Params(const std::string& method = "fixed") {
  NodeParams p;
  p.method = method;
  p.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-5, -5, 0), Eigen::Vector3d(20, 5, 3));
  return p;
}

// What NodeCore's constructor says about `p`, or "" when it accepts it.
std::string Refusal(const NodeParams& p) {
  try {
    NodeCore core(p, std::make_shared<navstack::SteppedClock>());
    return "";
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
}

TEST(RosNodeCoreTest, BadParametersAreRefusedNamingTheParameterAndTheRange) {
  NodeParams p = Params();
  EXPECT_EQ(Refusal(p), "");
  p.method = "nope";
  EXPECT_NE(Refusal(p).find("method: unknown method 'nope' (known: baseline, fixed, enavi"), std::string::npos)
      << Refusal(p);
  p = Params();
  p.overrides = {{"planner.v_max", 20}};
  EXPECT_EQ(Refusal(p), "planner.v_max: 20 is outside [0.2, 10]");
  p.overrides = {{"perception.stride", 2.5}};
  EXPECT_EQ(Refusal(p), "perception.stride: 2.5 is outside [1, 64] or not an integer");
  p.overrides = {{"camera.decimation", 2}};  // the simulator's: it renders the frames
  EXPECT_NE(Refusal(p).find("camera.decimation: unknown parameter for method fixed (known: planner.v_max"), std::string::npos)
      << Refusal(p);
  p.overrides = {{"ego.fsm_hz", 100}};
  EXPECT_NE(Refusal(p).find("ego.fsm_hz: unknown parameter for method fixed"), std::string::npos) << Refusal(p);
  p.method = "baseline";
  EXPECT_EQ(Refusal(p), "") << "the baseline's own tunable";
  p = Params();
  p.overrides = {{"planner.v_max", 1.5}, {"sched.threads", 2}, {"rates.f_per", 20}};
  EXPECT_EQ(Refusal(p), "");
  p = Params();
  p.policy = "/some/policy.json";
  EXPECT_NE(Refusal(p).find("policy: method fixed reads no frequency-adapter policy"), std::string::npos);
  p.method = "enavi";
  EXPECT_NE(Refusal(p).find("/some/policy.json"), std::string::npos) << "a missing policy file is named: " << Refusal(p);
  p = Params();
  p.bounds = Eigen::AlignedBox3d();
  EXPECT_NE(Refusal(p).find("bounds:"), std::string::npos);
  p = Params();
  p.cores = -1;
  EXPECT_NE(Refusal(p).find("cores:"), std::string::npos);
}

TEST(RosNodeCoreTest, TheMethodRunsOnItsSchedulerCappedAtTheCores) {
  NodeParams p = Params("enavi");
  p.cores = 4;
  EXPECT_NE(NodeCore(p, std::make_shared<navstack::SteppedClock>()).Describe().find("on 4 thread(s), global EDF, of 4 core(s)"),
            std::string::npos);
  p = Params("fixed");
  p.cores = 4;
  EXPECT_NE(NodeCore(p, std::make_shared<navstack::SteppedClock>()).Describe().find("on 1 thread(s), FIFO without preemption"),
            std::string::npos);
  p.overrides = {{"sched.threads", 8}, {"sched.global_edf", 1}};
  EXPECT_NE(NodeCore(p, std::make_shared<navstack::SteppedClock>()).Describe().find("on 4 thread(s), global EDF"),
            std::string::npos);
}

// The camera looking along world +x from p (optical frame: z forward, x right, y down).
Eigen::Isometry3d CameraAt(const Eigen::Vector3d& p) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear().col(0) = Eigen::Vector3d(0, -1, 0);
  X.linear().col(1) = Eigen::Vector3d(0, 0, -1);
  X.linear().col(2) = Eigen::Vector3d(1, 0, 0);
  X.translation() = p;
  return X;
}

TEST(RosNodeCoreTest, AMethodStartsWithItsInputsAndPlansTowardsTheGoalInRosTime) {
  const auto clock = std::make_shared<navstack::SteppedClock>();
  NodeCore core(Params("fixed"), clock);
  const Eigen::Vector3d start(0, 0, 1), goal(15, 0, 1);
  navstack::VehicleState state;
  state.p_WB = start;
  const navstack::CameraIntrinsics k = navstack::CameraIntrinsics::DefaultStream();

  EXPECT_FALSE(core.Sample().has_value());
  core.OnGoal(goal);
  core.OnOdometry(state);
  EXPECT_FALSE(core.running()) << "no camera intrinsics yet";
  core.OnCameraInfo(k);
  ASSERT_TRUE(core.running());
  const auto first = core.Sample();
  ASSERT_TRUE(first.has_value());
  EXPECT_FALSE(first->following) << "before its first plan the method holds";
  EXPECT_TRUE(first->reference.p.isApprox(start));

  // Up to 5 s of ROS time in 1 ms steps (paced by wall time, so that the jobs run): odometry at
  // 100 Hz, frames of an empty world at 30 Hz, the image and the pose apart.
  int frames = 0;
  std::optional<CommandSample> planned;
  for (int ms = 1; ms <= 5000 && !planned; ++ms) {
    const double t = 1e-3 * ms;
    clock->Set(t);
    if (ms % 10 == 0) {
      state.t = t;
      core.OnOdometry(state);
    }
    if (ms % 33 == 0) {
      core.OnDepth(t, navstack::DepthImage(k.width, k.height));  // no return anywhere
      core.OnCameraPose(t, CameraAt(start));
      ++frames;
    }
    if (ms == 500) core.OnCameraPose(t + 0.0005, CameraAt(start));  // an unmatched pose: no frame
    std::this_thread::sleep_for(1ms);
    const auto s = core.Sample();
    if (s && s->following && s->trajectory_id > 0) planned = s;
  }
  ASSERT_TRUE(planned.has_value()) << "no trajectory within 5 s of ROS time: " << core.Summary();
  EXPECT_EQ(core.error(), "");
  // Where the plan goes: ahead along it, the reference is nearer the goal than the start is.
  const double later = planned->t + 1.0;
  clock->Set(later);
  const auto ahead = core.Sample();
  ASSERT_TRUE(ahead.has_value());
  EXPECT_LT((ahead->reference.p - goal).norm(), (start - goal).norm()) << ahead->reference.p.transpose();
  core.Stop();
  const std::string summary = core.Summary();
  EXPECT_NE(summary.find("task.perception: released"), std::string::npos) << summary;
  EXPECT_NE(summary.find("task.planning: released"), std::string::npos) << summary;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(summary, m, std::regex("frames (\\d+) of (\\d+) assembled"))) << summary;
  EXPECT_EQ(std::stoi(m[2]), frames) << "the pose without an image made no frame";
}

}  // namespace
}  // namespace enavi::rosnode
