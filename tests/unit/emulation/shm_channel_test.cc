#include "workers/emulation/shm_channel.h"

#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>

namespace enavi::emulation {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

ShmChannelOptions Small() {
  ShmChannelOptions o;
  o.width = 8;
  o.height = 6;
  return o;
}

void Fill(ShmChannel& ch, float value, double t) {
  FrameSlot slot = ch.BeginFrame();
  slot.header->t = t;
  for (int i = 0; i < ch.width() * ch.height(); ++i) slot.depth[i] = value;
  ch.PublishFrame();
}

TEST(ShmChannelTest, FrameRingKeepsTheNewestAndCountsDrops) {
  ShmChannel sim = ShmChannel::Create(Small());
  ShmChannel nav = ShmChannel::Attach(dup(sim.fd()), ShmChannel::Role::kNavstack);
  std::int64_t dropped = -1;
  EXPECT_EQ(nav.AcquireFrame(&dropped).header, nullptr) << "nothing published yet";
  for (int k = 0; k < 5; ++k) Fill(sim, static_cast<float>(k), 0.1 * k);
  FrameSlot got = nav.AcquireFrame(&dropped);
  ASSERT_NE(got.header, nullptr);
  EXPECT_EQ(got.header->index, 4) << "newest wins";
  EXPECT_EQ(got.depth[0], 4.0f);
  EXPECT_EQ(dropped, 4) << "frames 0..3 were overwritten unread";
  EXPECT_EQ(nav.AcquireFrame(&dropped).header, nullptr) << "no frame twice";
  Fill(sim, 5.0f, 0.5);
  got = nav.AcquireFrame(&dropped);
  ASSERT_NE(got.header, nullptr);
  EXPECT_EQ(got.header->index, 5);
  EXPECT_EQ(dropped, 0);
}

TEST(ShmChannelTest, AcquiredFrameIsNeverOverwrittenWhileHeld) {
  ShmChannel sim = ShmChannel::Create(Small());
  ShmChannel nav = ShmChannel::Attach(dup(sim.fd()), ShmChannel::Role::kNavstack);
  Fill(sim, 1.0f, 0.0);
  const FrameSlot held = nav.AcquireFrame();
  ASSERT_NE(held.header, nullptr);
  for (int k = 2; k < 12; ++k) Fill(sim, static_cast<float>(k), k);  // the writer never waits
  for (int i = 0; i < sim.width() * sim.height(); ++i) ASSERT_EQ(held.depth[i], 1.0f) << i;
  EXPECT_EQ(held.header->index, 0);
  EXPECT_EQ(nav.AcquireFrame().depth[0], 11.0f);
}

TEST(ShmChannelTest, DepthFrameAndOdometryRoundTripThroughTheWireTypes) {
  ShmChannel sim = ShmChannel::Create(Small());
  ShmChannel nav = ShmChannel::Attach(dup(sim.fd()), ShmChannel::Role::kNavstack);
  navstack::DepthFrame f;
  f.t = 1.25;
  f.image = navstack::DepthImage(8, 6);
  for (std::size_t i = 0; i < f.image.data.size(); ++i) f.image.data[i] = 0.5f * static_cast<float>(i);
  f.X_WC.translation() = Eigen::Vector3d(1, 2, 3);
  f.X_WC.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  f.v_W = Eigen::Vector3d(0.1, 0.2, 0.3);
  sim.PublishFrame(f);
  const navstack::DepthFrame g = ShmChannel::ToDepthFrame(nav.AcquireFrame());
  EXPECT_EQ(g.t, f.t);
  EXPECT_EQ(g.image.data, f.image.data);
  EXPECT_TRUE(g.X_WC.isApprox(f.X_WC, 1e-12));
  EXPECT_EQ(g.v_W, f.v_W);

  navstack::VehicleState s;
  s.t = 3.0;
  s.p_WB = Eigen::Vector3d(1, -2, 3);
  s.v_WB = Eigen::Vector3d(0.5, 0, -0.5);
  s.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitY()));
  sim.PublishOdometry(ShmChannel::ToMsg(s));
  OdometryMsg m;
  std::uint32_t seq = 0;
  ASSERT_TRUE(nav.ReadOdometry(&m, &seq));
  const navstack::VehicleState r = ShmChannel::FromMsg(m);
  EXPECT_EQ(r.p_WB, s.p_WB);
  EXPECT_EQ(r.v_WB, s.v_WB);
  EXPECT_TRUE(r.q_WB.isApprox(s.q_WB));
}

TEST(ShmChannelTest, WrongFrameSizeIsRefused) {
  ShmChannel sim = ShmChannel::Create(Small());
  navstack::DepthFrame f;
  f.image = navstack::DepthImage(640, 480);
  EXPECT_THROW(sim.PublishFrame(f), std::invalid_argument);
  ShmChannelOptions bad;
  bad.width = 0;
  EXPECT_THROW(ShmChannel::Create(bad), std::invalid_argument);
}

TEST(ShmChannelTest, LatestValueSlotReturnsOnlyNewValues) {
  ShmChannel sim = ShmChannel::Create(Small());
  ShmChannel nav = ShmChannel::Attach(dup(sim.fd()), ShmChannel::Role::kNavstack);
  OdometryMsg m;
  std::uint32_t seq = 0;
  EXPECT_FALSE(nav.ReadOdometry(&m, &seq)) << "nothing published";
  m.t = 1.0;
  sim.PublishOdometry(m);
  m.t = 2.0;
  sim.PublishOdometry(m);
  OdometryMsg got;
  ASSERT_TRUE(nav.ReadOdometry(&got, &seq));
  EXPECT_EQ(got.t, 2.0) << "latest value, not a queue";
  EXPECT_FALSE(nav.ReadOdometry(&got, &seq));
}

TEST(ShmChannelTest, ConcurrentReaderNeverSeesATornMessage) {
  ShmChannel sim = ShmChannel::Create(Small());
  ShmChannel nav = ShmChannel::Attach(dup(sim.fd()), ShmChannel::Role::kNavstack);
  constexpr int kMessages = 20'000;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    TrajectoryMsg msg{};
    for (int k = 1; k <= kMessages; ++k) {
      msg.t_issue = k;
      msg.count = k;
      msg.samples[0].p[0] = k;
      msg.samples[TrajectoryMsg::kMaxSamples - 1].yaw = k;
      nav.PublishTrajectory(msg);
    }
    done = true;
  });
  std::uint32_t seq = 0;
  int reads = 0, torn = 0;
  double last = 0;
  bool backwards = false;
  auto* msg = new TrajectoryMsg();
  while (true) {
    const bool finished = done.load();  // read before the slot: nothing can follow it
    if (!sim.ReadTrajectory(msg, &seq)) {
      if (finished) break;
      continue;
    }
    ++reads;
    const double k = msg->t_issue;
    if (msg->count != static_cast<int>(k) || msg->samples[0].p[0] != k ||
        msg->samples[TrajectoryMsg::kMaxSamples - 1].yaw != k) {
      ++torn;
    }
    backwards |= k < last;
    last = k;
  }
  writer.join();
  delete msg;
  EXPECT_GT(reads, 0);
  EXPECT_EQ(torn, 0);
  EXPECT_FALSE(backwards);
  EXPECT_EQ(last, kMessages) << "the final value is always delivered";
}

TEST(ShmChannelTest, RoundTripWithANavstackProcess) {
  ShmChannel sim = ShmChannel::Create(Small());
  const int fd = sim.fd();
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ShmChannel nav = ShmChannel::Attach(dup(fd), ShmChannel::Role::kNavstack);
    std::uint32_t seq = 0;
    if (nav.WaitOdometry(seq, seconds(10)) != WaitStatus::kNew) _exit(2);
    OdometryMsg odom;
    if (!nav.ReadOdometry(&odom, &seq)) _exit(3);
    if (nav.WaitFrame(seconds(10)) != WaitStatus::kNew) _exit(4);
    const FrameSlot frame = nav.AcquireFrame();
    if (frame.header == nullptr) _exit(5);
    float sum = 0;
    for (int i = 0; i < nav.width() * nav.height(); ++i) sum += frame.depth[i];
    RotorCommandMsg cmd;
    cmd.t = odom.t;  // echo the stamp: the simulator matches command to state
    cmd.thrust_N[0] = sum;
    nav.PublishRotor(cmd);
    _exit(0);
  }
  OdometryMsg odom;
  odom.t = 7.5;
  sim.PublishOdometry(odom);
  Fill(sim, 2.0f, 7.5);
  std::uint32_t seq = 0;
  ASSERT_EQ(sim.WaitRotor(seq, seconds(10)), WaitStatus::kNew);
  RotorCommandMsg cmd;
  ASSERT_TRUE(sim.ReadRotor(&cmd, &seq));
  EXPECT_EQ(cmd.t, 7.5);
  EXPECT_EQ(cmd.thrust_N[0], 2.0f * 8 * 6);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "child exit " << WEXITSTATUS(status);
}

TEST(ShmChannelTest, DeadNavstackIsReportedInsteadOfWaitingForever) {
  ShmChannel sim = ShmChannel::Create(Small());
  EXPECT_EQ(sim.Peer(), PeerState::kNotAttached);
  int attached[2];
  ASSERT_EQ(pipe(attached), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ShmChannel nav = ShmChannel::Attach(dup(sim.fd()), ShmChannel::Role::kNavstack);
    const char byte = 1;
    if (write(attached[1], &byte, 1) != 1) _exit(2);
    pause();  // "hangs" until killed
    _exit(0);
  }
  char byte;
  ASSERT_EQ(read(attached[0], &byte, 1), 1);
  EXPECT_EQ(sim.Peer(), PeerState::kAlive);
  EXPECT_LT(sim.PeerHeartbeatAge(), seconds(10));
  kill(child, SIGKILL);
  // Not reaped yet: a zombie must count as dead.
  EXPECT_EQ(sim.WaitRotor(0, seconds(30)), WaitStatus::kPeerDead);
  EXPECT_EQ(sim.WaitFrame(seconds(30)), WaitStatus::kPeerDead);
  EXPECT_EQ(sim.Peer(), PeerState::kDead);
  int status = 0;
  waitpid(child, &status, 0);
  close(attached[0]);
  close(attached[1]);
}

TEST(ShmChannelTest, WaitTimesOutWhenThePeerIsSilent) {
  ShmChannel sim = ShmChannel::Create(Small());
  ShmChannel nav = ShmChannel::Attach(dup(sim.fd()), ShmChannel::Role::kNavstack);
  EXPECT_EQ(nav.WaitFrame(milliseconds(30)), WaitStatus::kTimeout);
  EXPECT_EQ(nav.WaitOdometry(0, milliseconds(30)), WaitStatus::kTimeout);
}

TEST(ShmChannelTest, ForeignDescriptorIsRefused) {
  const int fd = memfd_create("not-a-channel", MFD_CLOEXEC);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(ftruncate(fd, 1 << 20), 0);
  EXPECT_THROW(ShmChannel::Attach(fd, ShmChannel::Role::kNavstack), std::invalid_argument);
  EXPECT_EQ(fcntl(fd, F_GETFD), FD_CLOEXEC) << "a refused descriptor stays the caller's";
  close(fd);
  EXPECT_THROW(ShmChannel::Attach(-1, ShmChannel::Role::kNavstack), std::invalid_argument);
}

}  // namespace
}  // namespace enavi::emulation
