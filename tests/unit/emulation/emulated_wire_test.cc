// What crosses the process boundary of an emulated episode: trajectories as control points,
// the sim side's rebuild of NavStack::Reference, and the seqlock slots.
#include "workers/emulation/emulated_wire.h"

#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

namespace enavi::emulation {
namespace {

using navstack::PlannerOptions;
using navstack::Trajectory;
using navstack::TrajectorySample;
using navstack::UniformBspline;

// A wiggly climb of `n` control points starting at t0 with heading yaw0 turning at yaw_rate0.
std::shared_ptr<const Trajectory> MakeTrajectory(int n, double t0, double yaw0, const PlannerOptions& options,
                                                 unsigned seed = 7, double yaw_rate0 = 0.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.15, 0.15);
  Eigen::Matrix3Xd q(3, n);
  for (int i = 0; i < n; ++i) q.col(i) = Eigen::Vector3d(0.4 * i + jitter(rng), 0.3 * std::sin(0.5 * i) + jitter(rng), 1.0 + 0.02 * i);
  return std::make_shared<const Trajectory>(UniformBspline(q, 0.2), t0, yaw0, options, yaw_rate0);
}

void ExpectSameSample(const TrajectorySample& a, const TrajectorySample& b, double t) {
  EXPECT_LT((a.p - b.p).norm(), 1e-12) << "t = " << t;
  EXPECT_LT((a.v - b.v).norm(), 1e-12) << "t = " << t;
  EXPECT_LT((a.a - b.a).norm(), 1e-12) << "t = " << t;
  EXPECT_LT((a.j - b.j).norm(), 1e-12) << "t = " << t;
  EXPECT_NEAR(a.yaw, b.yaw, 1e-9) << "t = " << t;
  EXPECT_NEAR(a.yaw_rate, b.yaw_rate, 1e-6) << "t = " << t;
}

TEST(EmulatedWireTest, TrajectoryRoundTripSamplesLikeTheOriginal) {
  PlannerOptions options;
  options.yaw_rate_max = 1.0;
  for (double yaw0 : {0.0, 2.9, -3.1, 3.14159}) {
    // A start rate against the turn the path asks for, so the rebuilt profile differs unless
    // the wire carries it.
    const auto traj = MakeTrajectory(30, 12.5, yaw0, options, 7, -0.8);
    auto wire = std::make_unique<TrajectoryWire>();
    ToWire(*traj, wire.get());
    EXPECT_EQ(wire->count, 30);
    EXPECT_EQ(wire->t0, 12.5);
    EXPECT_EQ(wire->dt, 0.2);
    EXPECT_EQ(wire->yaw_rate0, -0.8);
    const auto back = FromWire(*wire, options);
    ASSERT_NE(back, nullptr);
    EXPECT_EQ(back->spline().control_points(), traj->spline().control_points()) << "control points are exact";
    EXPECT_EQ(back->start_time(), traj->start_time());
    EXPECT_EQ(back->end_time(), traj->end_time());
    for (double t = 11.0; t < traj->end_time() + 1.0; t += 0.0137) ExpectSameSample(back->Sample(t), traj->Sample(t), t);
  }
}

TEST(EmulatedWireTest, EmptyAndMalformedTrajectoryMessages) {
  auto wire = std::make_unique<TrajectoryWire>();
  EXPECT_EQ(FromWire(*wire, PlannerOptions{}), nullptr) << "count 0 is no trajectory";
  wire->count = 3;
  wire->dt = 0.1;
  EXPECT_THROW(FromWire(*wire, PlannerOptions{}), std::invalid_argument) << "a cubic B-spline needs 4 points";
  wire->count = 10;
  wire->dt = 0.0;
  EXPECT_THROW(FromWire(*wire, PlannerOptions{}), std::invalid_argument);
}

TEST(EmulatedWireTest, TooManyControlPointsIsRefusedLoudly) {
  const auto traj = MakeTrajectory(TrajectoryWire::kMaxControlPoints + 1, 0.0, 0.0, PlannerOptions{});
  auto wire = std::make_unique<TrajectoryWire>();
  EXPECT_THROW(ToWire(*traj, wire.get()), std::length_error);
}

TEST(EmulatedWireTest, MirrorFollowsNavStackReferenceRules) {
  const PlannerOptions options;
  const auto older = MakeTrajectory(20, 1.0, 0.3, options, 1);
  const auto newer = MakeTrajectory(20, 5.0, 0.4, options, 2);
  auto w = std::make_unique<ReferenceWire>();
  ReferenceMirror mirror(options);

  // Following the newer plan, with the older one handed over before its start time.
  w->mode = ReferenceWire::kTrajectory;
  ToWire(*newer, &w->current);
  ToWire(*older, &w->previous);
  mirror.Update(*w);
  ExpectSameSample(mirror.Reference(4.0), older->Sample(4.0), 4.0);
  ExpectSameSample(mirror.Reference(6.0), newer->Sample(6.0), 6.0);

  // Without a previous plan the new one is sampled (clamped) before its start.
  w->previous.count = 0;
  mirror.Update(*w);
  ExpectSameSample(mirror.Reference(4.0), newer->Sample(4.0), 4.0);

  // Holding (emergency stop): the hold sample whatever the time.
  TrajectorySample hold;
  hold.p = Eigen::Vector3d(1, 2, 3);
  hold.yaw = 0.7;
  w->mode = ReferenceWire::kHold;
  w->hold = ToWire(hold);
  mirror.Update(*w);
  for (double t : {0.0, 6.0, 100.0}) ExpectSameSample(mirror.Reference(t), hold, t);
}

TEST(EmulatedWireTest, SeqSlotDeliversEachValueOnce) {
  auto slot = std::make_unique<SeqSlot<StatsWire>>();
  StatsWire in;
  in.frames_received = 42;
  in.tasks[1].busy_s = 3.5;
  StatsWire out;
  std::uint32_t seen = 0;
  EXPECT_FALSE(slot->Read(&out, &seen)) << "nothing written yet";
  slot->Write(in);
  ASSERT_TRUE(slot->Read(&out, &seen));
  EXPECT_EQ(out.frames_received, 42);
  EXPECT_EQ(out.tasks[1].busy_s, 3.5);
  EXPECT_FALSE(slot->Read(&out, &seen)) << "the same value is not delivered twice";
  in.frames_received = 43;
  slot->Write(in);
  ASSERT_TRUE(slot->Read(&out, &seen));
  EXPECT_EQ(out.frames_received, 43);
}

}  // namespace
}  // namespace enavi::emulation
