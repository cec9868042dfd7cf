// Latency of the simulator <-> navstack shared-memory channel across two processes:
// odometry -> rotor command round trip (futex wake each way), and a 640x480 depth frame
// published (copy in) and acquired (no copy) with a command back.
#include <benchmark/benchmark.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>

#include "workers/emulation/shm_channel.h"

namespace enavi::emulation {
namespace {

using std::chrono::seconds;

// The navstack stand-in: answers every odometry message or frame with a rotor command.
[[noreturn]] void Echo(int fd, bool frames) {
  ShmChannel nav = ShmChannel::Attach(fd, ShmChannel::Role::kNavstack);
  std::uint32_t seq = 0;
  while (true) {
    RotorCommandMsg cmd;
    if (frames) {
      if (nav.WaitFrame(seconds(5)) != WaitStatus::kNew) _exit(0);
      const FrameSlot f = nav.AcquireFrame();
      if (f.header == nullptr) continue;
      cmd.t = f.header->t;
    } else {
      if (nav.WaitOdometry(seq, seconds(5)) != WaitStatus::kNew) _exit(0);
      OdometryMsg odom;
      if (!nav.ReadOdometry(&odom, &seq)) continue;
      cmd.t = odom.t;
    }
    nav.PublishRotor(cmd);
  }
}

void RoundTrip(benchmark::State& state, bool frames) {
  ShmChannel sim = ShmChannel::Create();
  const int fd = sim.fd();
  const pid_t child = fork();
  if (child == 0) Echo(dup(fd), frames);
  navstack::DepthFrame frame;
  frame.image = navstack::DepthImage(sim.width(), sim.height());
  for (float& d : frame.image.data) d = 3.0f;
  std::uint32_t seq = 0;
  double t = 0;
  for (auto _ : state) {
    t += 1.0;
    if (frames) {
      frame.t = t;
      sim.PublishFrame(frame);
    } else {
      OdometryMsg odom;
      odom.t = t;
      sim.PublishOdometry(odom);
    }
    RotorCommandMsg cmd;
    do {
      if (sim.WaitRotor(seq, seconds(5)) != WaitStatus::kNew) {
        state.SkipWithError("navstack stand-in stopped answering");
        break;
      }
      sim.ReadRotor(&cmd, &seq);
    } while (cmd.t != t);
  }
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
}

void BM_OdometryToCommandRoundTrip(benchmark::State& state) { RoundTrip(state, false); }
void BM_DepthFrameToCommandRoundTrip(benchmark::State& state) { RoundTrip(state, true); }

BENCHMARK(BM_OdometryToCommandRoundTrip)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DepthFrameToCommandRoundTrip)->UseRealTime()->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace enavi::emulation

BENCHMARK_MAIN();
