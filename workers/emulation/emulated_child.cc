#include "workers/emulation/emulated_child.h"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include "api/fixed.h"
#include "navstack/methods/reference_tracker.h"
#include "navstack/runtime/realtime_executor.h"
#include "navstack/runtime/sched_deadline.h"
#include "workers/emulation/shm_channel.h"

namespace enavi::emulation {
namespace {

using Clock = std::chrono::steady_clock;
using navstack::TaskId;

using api::Fixed;

void NameThread(const char* name) { pthread_setname_np(pthread_self(), name); }

// Publishes the stack's outputs. Every call happens under the exclusive JobLock (after a commit
// or after the IPC thread fed a frame), so NavStack is read consistently and there is one
// writer at a time.
class OutputPublisher {
 public:
  OutputPublisher(LinkShared* shared) : shared_(shared), wire_(std::make_unique<ReferenceWire>()) {}

  void Publish(navstack::Navigator& nav, double now) {
    ReferenceWire& w = *wire_;
    const navstack::PublishedReference& ref = tracker_.reference();
    if (tracker_.Update(nav, now)) {
      if (ref.current) {
        ToWire(*ref.current, &w.current);
      } else {
        w.current.count = 0;
      }
      if (ref.previous) {
        ToWire(*ref.previous, &w.previous);
      } else {
        w.previous.count = 0;
      }
    }
    w.mode = ref.following ? ReferenceWire::kTrajectory : ReferenceWire::kHold;
    w.hold = ToWire(ref.hold);
    const navstack::TaskRates& r = nav.rates();
    w.f_per = r.f_per;
    w.f_plan = r.f_plan;
    w.f_col = r.f_col;
    w.f_dif = r.f_dif;
    w.resolution = r.resolution;
    w.collision_on_map_update = r.collision_on_map_update ? 1 : 0;
    w.map_resolution = nav.map_resolution();
    w.plan_failures = nav.plan_failures();
    ++w.publications;
    shared_->reference.Write(w);

    for (const navstack::NavEvent& e : nav.TakeEvents()) {
      EventWire ew;
      ew.t = e.t;
      CopyText(ew.kind, sizeof ew.kind, e.kind);
      CopyText(ew.detail, sizeof ew.detail, e.detail);
      const std::uint64_t head = shared_->event_head.load(std::memory_order_relaxed);
      shared_->events[head % kEventRing].Write(ew);
      shared_->event_head.store(head + 1, std::memory_order_release);
    }
  }

 private:
  LinkShared* shared_;
  std::unique_ptr<ReferenceWire> wire_;
  navstack::ReferenceTracker tracker_;
};

std::string DescribeSched(const std::vector<navstack::DeadlineResult>& results, bool requested,
                          const navstack::DeadlineParams& params, double rate) {
  const int n = static_cast<int>(results.size());
  int granted = 0;
  std::string reason;
  for (const auto& r : results) {
    if (r.deadline) {
      ++granted;
    } else if (reason.empty()) {
      reason = r.reason;
    }
  }
  const std::string server = "runtime " + std::to_string(params.runtime_ns / 1000) + " us / period " +
                             std::to_string(params.period_ns / 1000) + " us (" + Fixed(rate, 3) +
                             " of a host core = one board core)";
  if (!requested)
    return "SCHED_DEADLINE not requested; " + std::to_string(n) +
           " worker thread(s) SCHED_OTHER, held to one board core each by their per-thread cgroup quota";
  if (granted == n) return "SCHED_DEADLINE speed server on each of " + std::to_string(n) + " worker thread(s): " + server;
  return "fallback on " + std::to_string(n - granted) + " of " + std::to_string(n) +
         " worker thread(s): SCHED_OTHER held to one board core by the per-thread cgroup quota (" + reason + ")" +
         (granted > 0 ? "; " + std::to_string(granted) + " with a SCHED_DEADLINE speed server: " + server : "");
}

}  // namespace

int RunNavstackChild(const ChildArgs& a) {
  LinkShared* shared = a.shared;
  NameThread("enavi-navstack");
  char go = 0;
  while (true) {
    const ssize_t n = read(a.go_fd, &go, 1);
    if (n == 1) break;
    if (n == 0 || errno != EINTR) return 3;  // the simulator gave up before placing us
  }
  close(a.go_fd);
  emulation::ShmChannel channel = emulation::ShmChannel::Attach(a.channel_fd, emulation::ShmChannel::Role::kNavstack);

  const double rate = a.speed / a.dilation;
  const navstack::DeadlineParams server = navstack::SpeedServerParams(std::min(1.0, rate), a.server_period_ns);
  std::vector<navstack::DeadlineResult> sched(static_cast<std::size_t>(a.threads));
  navstack::Navigator* nav = nullptr;
  OutputPublisher publisher(shared);

  navstack::RealtimeExecutorOptions eo;
  eo.threads = a.threads;
  eo.policy = a.policy;
  const auto clock = std::make_shared<navstack::DilatedSteadyClock>(a.dilation);
  eo.clock = clock;
  eo.host_to_board = 1.0 / a.speed;
  eo.on_worker_start = [&](int w) {
    const std::string name = "nav-worker-" + std::to_string(w);
    NameThread(name.c_str());
    if (a.sched_deadline) sched[static_cast<std::size_t>(w)] = navstack::EnterDeadline(server);
  };
  // Every job priced as the virtual clock would: the in-situ check of the cost model.
  const navstack::WorkCountCostModel model(a.board_costs);
  std::mutex model_mutex;
  std::array<double, navstack::kTaskCount> model_s{};
  eo.observer = [&](TaskId task, const navstack::WorkCounts& work, double cpu) {
    const double priced = model.JobSeconds(task, work, cpu);
    std::lock_guard l(model_mutex);
    model_s[static_cast<int>(task)] += priced;
  };
  navstack::RealtimeExecutor* exec_ptr = nullptr;
  eo.after_commit = [&](TaskId) { publisher.Publish(*nav, exec_ptr->now()); };
  navstack::RealtimeExecutor exec(eo);
  exec_ptr = &exec;
  const std::unique_ptr<navstack::Navigator> navigator = a.method->make(*a.options, &exec, *a.initial);
  navstack::Navigator& stack = *navigator;
  nav = &stack;
  // Jobs use the stack: the workers must be gone before it is, also when this function throws.
  struct StopFirst {
    navstack::RealtimeExecutor& e;
    ~StopFirst() { e.Stop(); }
  } stop_first{exec};
  exec.Launch();
  {
    std::ofstream comm("/proc/self/task/" + std::to_string(exec.ReleaseThreadTid()) + "/comm");
    comm << "nav-release";
  }
  int granted = 0;
  for (const auto& r : sched) granted += r.deadline ? 1 : 0;
  shared->deadline_workers.store(granted);
  CopyText(shared->sched_note, sizeof shared->sched_note, DescribeSched(sched, a.sched_deadline, server, rate));
  publisher.Publish(stack, 0.0);
  shared->child_state.store(kReady, std::memory_order_release);

  // Sim time 0 is set by the simulator when it starts flying.
  std::int64_t epoch_ns = 0;
  while ((epoch_ns = shared->epoch_ns.load(std::memory_order_acquire)) == 0) {
    if (shared->stop.load() || channel.Peer() == emulation::PeerState::kDead) return 0;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  clock->SetEpoch(Clock::time_point(std::chrono::nanoseconds(epoch_ns)));
  exec.Start();
  shared->child_state.store(kRunning, std::memory_order_release);

  auto stats = std::make_unique<StatsWire>();
  auto publish_stats = [&] {
    const auto all = exec.AllStats();
    const auto wall = exec.ExecutionWallSeconds();
    const auto lags = exec.ReleaseLags();
    for (int i = 0; i < navstack::kTaskCount; ++i) {
      stats->tasks[i] = all[i];
      stats->execution_wall_s[i] = wall[i];
      stats->release_lags[i] = lags[i];
    }
    {
      std::lock_guard l(model_mutex);
      for (int i = 0; i < navstack::kTaskCount; ++i) stats->model_board_s[i] = model_s[i];
    }
    stats->lock = exec.lock_stats();
    stats->child_now = exec.now();
    ++stats->publications;
    shared->stats.Write(*stats);
  };
  emulation::OdometryMsg odom;
  std::uint32_t odom_seq = 0;
  bool odom_pending = false;
  while (!shared->stop.load(std::memory_order_relaxed)) {
    if (const std::string err = exec.error(); !err.empty()) throw std::runtime_error(err);
    const emulation::WaitStatus w = channel.WaitFrame(std::chrono::milliseconds(5));
    if (w == emulation::WaitStatus::kPeerDead) return 0;
    if (channel.ReadOdometry(&odom, &odom_seq)) odom_pending = true;
    if (w == emulation::WaitStatus::kNew) {
      std::int64_t dropped = 0;
      const emulation::FrameSlot slot = channel.AcquireFrame(&dropped);
      if (slot.header != nullptr) {
        auto frame = std::make_shared<navstack::DepthFrame>(emulation::ShmChannel::ToDepthFrame(slot));
        std::unique_lock lock(exec.job_lock());
        if (odom_pending) {
          stack.OnState(emulation::ShmChannel::FromMsg(odom));
          odom_pending = false;
          ++stats->odometry_applied;
        }
        stack.OnFrame(std::move(frame));
        publisher.Publish(stack, exec.now());
        ++stats->frames_received;
        stats->frames_dropped += std::max<std::int64_t>(0, dropped);
      }
    } else if (odom_pending && exec.job_lock().try_lock()) {
      // Odometry does not wait for running jobs (they read the state at their start).
      stack.OnState(emulation::ShmChannel::FromMsg(odom));
      exec.job_lock().unlock();
      odom_pending = false;
      ++stats->odometry_applied;
    }
    publish_stats();
    channel.Heartbeat();
  }
  exec.Stop();
  publish_stats();
  shared->child_state.store(kDone, std::memory_order_release);
  return 0;
}

void PrepareChildProcess(pid_t parent, int* channel_fd, int* go_fd) {
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() != parent) _exit(1);  // the simulator died before the line above
  struct sigaction dfl{};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGPIPE, SIGHUP}) sigaction(sig, &dfl, nullptr);
  sigset_t none;
  sigemptyset(&none);
  pthread_sigmask(SIG_SETMASK, &none, nullptr);
  // Nothing of the simulator's descriptors (stdout carries --json) except the two we need.
  const int devnull = open("/dev/null", O_WRONLY | O_CLOEXEC);
  if (devnull >= 0) dup2(devnull, STDOUT_FILENO);
  const int ch = fcntl(*channel_fd, F_DUPFD, 100);
  const int go = fcntl(*go_fd, F_DUPFD, 100);
  if (ch < 0 || go < 0 || dup2(ch, 3) != 3 || dup2(go, 4) != 4) _exit(1);
  close_range(5, ~0U, 0);
  *channel_fd = 3;
  *go_fd = 4;
}

void CopyText(char* dst, std::size_t size, const std::string& text) {
  const std::size_t n = std::min(size - 1, text.size());
  std::memcpy(dst, text.data(), n);
  dst[n] = '\0';
}

}  // namespace enavi::emulation
