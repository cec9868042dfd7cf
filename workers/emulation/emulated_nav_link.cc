#include "workers/emulation/emulated_nav_link.h"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <fstream>
#include <map>
#include <mutex>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "api/fixed.h"
#include "navstack/runtime/proc_stat.h"
#include "navstack/runtime/realtime_executor.h"
#include "navstack/runtime/sched_deadline.h"
#include "navstack/stack/nav_stack.h"
#include "workers/board/host_calibration.h"
#include "workers/emulation/board_slot.h"
#include "workers/emulation/emulated_child.h"
#include "workers/emulation/emulated_wire.h"
#include "workers/emulation/shm_channel.h"
#include "workers/emulation/termination_signals.h"
#include "workers/sim/link_registry.h"

namespace enavi::emulation {
namespace {

using Clock = std::chrono::steady_clock;
using navstack::TaskId;
using api::Fixed;

std::int64_t ToNs(Clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

}  // namespace

// ---------------------------------------------------------------------------------------------

struct EmulatedNavLink::Impl {
  // Configuration.
  const navstack::MethodInfo* method = nullptr;
  navstack::MethodOptions options;
  navstack::VehicleState initial;
  int threads = 1;
  navstack::SchedulingPolicy policy = navstack::SchedulingPolicy::kGlobalEdf;
  board::BoardProfile board;
  EmulationOptions emulation;
  double speed = 1.0, dilation = 1.0;
  std::map<std::string, std::string> notes;

  // Resources, released in reverse order by Shutdown().
  std::optional<ScopedTerminationSignals> signals;
  // The simulator's own scheduling while the episode runs (restored by Shutdown()).
  bool sim_fifo = false;
  int sim_old_policy = SCHED_OTHER;
  sched_param sim_old_param{};
  std::unique_ptr<BoardSlot> slot;
  std::optional<emulation::ShmChannel> channel;
  LinkShared* shared = nullptr;
  pid_t child = -1;
  std::string child_exit;  // how the child ended, once reaped

  // Running state. The simulator runs `lead` ahead of the wall clock so that a frame is
  // rendered before its capture time; the publisher thread hands frames and odometry to the
  // navstack exactly at their due time epoch + t x k.
  Clock::time_point epoch{};
  bool epoch_set = false;
  Clock::duration lead{};
  Clock::duration frame_early{};
  std::thread publisher;
  mutable std::mutex pub_mutex;
  std::condition_variable pub_cv;
  bool pub_stop = false;
  bool frame_staged = false;  // the channel's back slot holds a frame waiting for its due time
  Clock::time_point frame_due{};
  std::deque<std::pair<Clock::time_point, emulation::OdometryMsg>> odometry_queue;
  std::int64_t frames_published = 0, frames_late = 0;
  double frame_late_sum_s = 0, frame_late_max_s = 0;
  double last_t = 0;
  ReferenceMirror mirror{navstack::PlannerOptions{}};
  std::unique_ptr<ReferenceWire> reference_wire = std::make_unique<ReferenceWire>();
  std::uint32_t reference_seq = 0;
  navstack::TaskRates current_rates;
  double current_map_resolution = 0;
  std::int64_t plan_failures = 0;
  std::uint64_t event_tail = 0;
  std::int64_t events_lost = 0;
  Clock::time_point next_liveness_check{}, next_sweep{};
  // Pacing of the simulator: how far behind schedule it was when it reached each step.
  std::int64_t steps = 0, steps_late = 0;
  double lag_sum_s = 0, lag_max_s = 0;
  // Accounting, refreshed lazily.
  mutable std::unique_ptr<StatsWire> stats = std::make_unique<StatsWire>();
  mutable std::uint32_t stats_seq = 0;
  mutable Clock::time_point next_proc_sample{};
  mutable std::map<pid_t, std::pair<std::string, double>> thread_cpu;  // tid -> (comm, cpu s)

  ~Impl() { Shutdown(); }

  void Start();
  void TakeBoardSlot();
  void MapSharedMemory();
  void ForkNavstack();
  void WaitUntilWorkersRun();
  void TakeFirstReference();
  void PaceSimulator();
  void Shutdown();
  void SetEpoch();
  Clock::time_point Due(double t) const {
    return epoch + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(t * dilation));
  }
  void PublisherLoop();
  void StopPublisher();
  void CheckSignal(const char* where) const {
    if (const int sig = PendingTerminationSignal()) {
      throw std::runtime_error(std::string("emulated clock: interrupted by ") + strsignal(sig) + " " + where);
    }
  }
  void CheckChild();
  void TakeOutputs();
  void SampleProc() const;
};

// Starting an emulated episode, step by step; a throw at any step leaves ~Impl to undo the
// steps before it (Shutdown).
void EmulatedNavLink::Impl::Start() {
  TakeBoardSlot();
  MapSharedMemory();
  ForkNavstack();
  WaitUntilWorkersRun();
  TakeFirstReference();
  PaceSimulator();
}

// The board on this host: speed, dilation, quotas, the episode's cgroups.
void EmulatedNavLink::Impl::TakeBoardSlot() {
  signals.emplace();
  slot = std::make_unique<BoardSlot>(board, dilation, emulation);
  speed = slot->speed();
  dilation = slot->dilation();
  notes.insert(slot->notes().begin(), slot->notes().end());
}

// The frame channel and the mapping the navstack process writes its outputs to.
void EmulatedNavLink::Impl::MapSharedMemory() {
  channel.emplace(emulation::ShmChannel::Create({options.camera.width, options.camera.height}));
  void* mem = mmap(nullptr, sizeof(LinkShared), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  if (mem == MAP_FAILED) throw std::runtime_error(std::string("emulated clock: mmap: ") + std::strerror(errno));
  shared = new (mem) LinkShared();
}

// The navstack process: forked, it waits on a pipe until it is inside the board's groups, so no
// navstack instruction runs unthrottled.
void EmulatedNavLink::Impl::ForkNavstack() {
  int go[2];
  if (pipe2(go, O_CLOEXEC) != 0) throw std::runtime_error(std::string("emulated clock: pipe: ") + std::strerror(errno));
  ChildArgs args;
  args.method = method;
  args.options = &options;
  args.initial = &initial;
  args.threads = threads;
  args.policy = policy;
  args.dilation = dilation;
  args.speed = speed;
  args.sched_deadline = emulation.sched_deadline;
  args.server_period_ns = emulation.server_period_us * 1000;
  args.board_costs = board::BoardCoefficients(board, board::LoadReferenceCosts(), method->cost_family);
  args.shared = shared;
  args.channel_fd = channel->fd();
  args.go_fd = go[0];
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    close(go[0]);
    close(go[1]);
    throw std::runtime_error(std::string("emulated clock: fork: ") + std::strerror(errno));
  }
  if (pid == 0) {
    int code = 1;
    try {
      PrepareChildProcess(parent, &args.channel_fd, &args.go_fd);
      code = RunNavstackChild(args);
    } catch (const std::exception& e) {
      CopyText(shared->error, sizeof shared->error, e.what());
      shared->child_state.store(kFailed, std::memory_order_release);
      code = 1;
    }
    _exit(code);
  }
  child = pid;
  close(go[0]);
  EpisodeCgroup& group = slot->group();
  if (emulation::CgroupStatus s = group.AddProcess(child); !s.ok) {
    close(go[1]);
    throw std::runtime_error("emulated clock: cannot move the navstack process into " + group.name() + ": " + s.message);
  }
  const char byte = 'g';
  const bool sent = write(go[1], &byte, 1) == 1;
  close(go[1]);
  if (!sent) throw std::runtime_error("emulated clock: cannot start the navstack process");
  notes["emulation.process"] = "navstack in its own process (fork, pid " + std::to_string(child) +
                               "), simulator outside the throttled groups";
  if (emulation.on_navstack_started) emulation.on_navstack_started(child);
}

// Waits until the navstack's workers run (and asked for SCHED_DEADLINE), then gives every
// thread its group.
void EmulatedNavLink::Impl::WaitUntilWorkersRun() {
  const auto give_up = Clock::now() + std::chrono::seconds(30);
  while (shared->child_state.load(std::memory_order_acquire) == kStarting) {
    CheckSignal("while the navstack process started");
    CheckChild();
    if (Clock::now() > give_up) throw std::runtime_error("emulated clock: the navstack process did not start within 30 s");
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  CheckChild();
  emulation::CgroupStatus sweep;
  const int placed = slot->group().SweepThreads(&sweep);
  if (!sweep.ok) throw std::runtime_error("emulated clock: per-thread cgroups: " + sweep.message);
  notes["emulation.threads"] = std::to_string(placed) + " navstack threads in per-thread groups (" +
                               std::to_string(threads) + " worker(s), release, IPC)";
  notes["emulation.sched"] = shared->sched_note;
  notes["emulation.scheduler"] =
      std::string(policy == navstack::SchedulingPolicy::kGlobalEdf ? "EDF" : "FIFO") + " without preemption on " +
      std::to_string(threads) + " worker thread(s), releases in sim time = wall / " + Fixed(dilation, 2) +
      "; jobs under a shared lock, commits exclusive";
  notes["cost"] = "measured (job thread CPU time / board speed)";
}

// The stack's first output: the hover reference it publishes before sim time starts.
void EmulatedNavLink::Impl::TakeFirstReference() {
  mirror = ReferenceMirror(options.planner);
  TakeOutputs();
  if (!mirror.has_message()) throw std::runtime_error("emulated clock: the navstack process published no reference");
  next_liveness_check = next_sweep = Clock::now();
}

// The simulator must keep its schedule whatever else runs on the host: its paced threads run
// SCHED_FIFO (above every CFS task, below the board's SCHED_DEADLINE servers; the navstack
// process was forked before, so it does not inherit this), and the publisher thread hands frames
// and odometry over at their due times.
void EmulatedNavLink::Impl::PaceSimulator() {
  if (emulation.simulator_fifo) {
    pthread_getschedparam(pthread_self(), &sim_old_policy, &sim_old_param);
    sched_param fifo{};
    fifo.sched_priority = 1;
    const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &fifo);
    sim_fifo = err == 0;
    notes["emulation.simulator"] =
        sim_fifo ? "simulator threads SCHED_FIFO 1 while paced (outside the board's groups)"
                 : std::string("simulator threads SCHED_OTHER (SCHED_FIFO refused: ") + std::strerror(err) +
                       "); a busy host can delay frames, see emulation.pacing";
  } else {
    notes["emulation.simulator"] = "simulator threads SCHED_OTHER (option)";
  }
  lead = std::chrono::microseconds(emulation.lead_us);
  frame_early = std::chrono::microseconds(emulation.frame_early_us);
  publisher = std::thread([this] { PublisherLoop(); });
}

void EmulatedNavLink::Impl::SetEpoch() {
  if (epoch_set) return;
  // Sim time 0 a little ahead, so the navstack's first releases are not already late and the
  // simulator has its lead from the start.
  epoch = Clock::now() + lead + std::chrono::milliseconds(5);
  epoch_set = true;
  shared->epoch_ns.store(ToNs(epoch), std::memory_order_release);
}

void EmulatedNavLink::Impl::PublisherLoop() {
  pthread_setname_np(pthread_self(), "sim-publisher");
  if (sim_fifo) {
    sched_param fifo{};
    fifo.sched_priority = 1;
    pthread_setschedparam(pthread_self(), SCHED_FIFO, &fifo);
  }
  std::unique_lock l(pub_mutex);
  while (!pub_stop) {
    Clock::time_point next = Clock::time_point::max();
    if (frame_staged) next = frame_due;
    if (!odometry_queue.empty()) next = std::min(next, odometry_queue.front().first);
    if (next == Clock::time_point::max()) {
      pub_cv.wait(l);
      continue;
    }
    const Clock::time_point now = Clock::now();
    if (now < next) {
      pub_cv.wait_until(l, next);
      continue;
    }
    // Odometry first: a frame's consumer should see the state of its capture instant.
    bool have_odometry = false;
    emulation::OdometryMsg odometry;
    while (!odometry_queue.empty() && odometry_queue.front().first <= now) {
      odometry = odometry_queue.front().second;
      odometry_queue.pop_front();
      have_odometry = true;
    }
    if (have_odometry) channel->PublishOdometry(odometry);
    if (frame_staged && frame_due <= now) {
      channel->PublishFrame();
      frame_staged = false;
      ++frames_published;
      const double late = std::max(0.0, std::chrono::duration<double>(Clock::now() - (frame_due + frame_early)).count());
      frame_late_sum_s += late;
      frame_late_max_s = std::max(frame_late_max_s, late);
      if (late > 1e-3) ++frames_late;
      pub_cv.notify_all();
    }
  }
}

void EmulatedNavLink::Impl::StopPublisher() {
  if (!publisher.joinable()) return;
  {
    std::lock_guard l(pub_mutex);
    pub_stop = true;
  }
  pub_cv.notify_all();
  publisher.join();
}

void EmulatedNavLink::Impl::CheckChild() {
  if (child <= 0) return;
  if (shared->child_state.load(std::memory_order_acquire) == kFailed) {
    throw std::runtime_error(std::string("emulated clock: the navstack process failed: ") + shared->error);
  }
  int status = 0;
  const pid_t r = waitpid(child, &status, WNOHANG);
  if (r == child) {
    child = -1;
    child_exit = navstack::DescribeWaitStatus(status);
    if (shared->child_state.load(std::memory_order_acquire) == kFailed) {
      throw std::runtime_error(std::string("emulated clock: the navstack process failed: ") + shared->error);
    }
    throw std::runtime_error("emulated clock: the navstack process died (" + child_exit + ")");
  }
}

void EmulatedNavLink::Impl::TakeOutputs() {
  if (shared->reference.Read(reference_wire.get(), &reference_seq)) {
    const ReferenceWire& w = *reference_wire;
    mirror.Update(w);
    current_rates.f_per = w.f_per;
    current_rates.f_plan = w.f_plan;
    current_rates.f_col = w.f_col;
    current_rates.f_dif = w.f_dif;
    current_rates.resolution = w.resolution;
    current_rates.collision_on_map_update = w.collision_on_map_update != 0;
    current_map_resolution = w.map_resolution;
    plan_failures = w.plan_failures;
  }
}

void EmulatedNavLink::Impl::SampleProc() const {
  if (child <= 0) return;
  for (pid_t tid : navstack::ListThreads(child)) {
    if (const auto t = navstack::ReadThreadCpu(child, tid)) thread_cpu[tid] = {t->comm, t->CpuSeconds()};
  }
}

void EmulatedNavLink::Impl::Shutdown() {
  StopPublisher();
  if (sim_fifo) {
    pthread_setschedparam(pthread_self(), sim_old_policy, &sim_old_param);
    sim_fifo = false;
  }
  if (child > 0) {
    if (shared != nullptr) shared->stop.store(1);
    // A job in flight may take a while at board speed; the results are already in.
    int status = 0;
    pid_t r = 0;
    for (int i = 0; i < 60 && (r = waitpid(child, &status, WNOHANG)) == 0; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (r == 0) {
      kill(child, SIGKILL);
      r = waitpid(child, &status, 0);
    }
    if (r == child) child_exit = navstack::DescribeWaitStatus(status);
    child = -1;
  }
  const std::string cleanup_error = slot ? slot->Release() : std::string();
  slot.reset();
  channel.reset();
  if (shared != nullptr) {
    shared->~LinkShared();
    munmap(shared, sizeof(LinkShared));
    shared = nullptr;
  }
  if (!cleanup_error.empty()) std::fprintf(stderr, "enavi: emulated clock clean-up: %s\n", cleanup_error.c_str());
  signals.reset();  // re-raises a SIGINT/SIGTERM that arrived during the episode, now that nothing is left
}

// ---------------------------------------------------------------------------------------------

EmulatedNavLink::EmulatedNavLink(const navstack::MethodInfo& method, const navstack::MethodOptions& options,
                                 int threads,
                                 navstack::SchedulingPolicy policy, const board::BoardProfile& board,
                                 double dilation, const navstack::VehicleState& initial,
                                 const EmulationOptions& emulation)
    : impl_(std::make_unique<Impl>()) {
  if (threads < 1) throw std::invalid_argument("emulated clock: threads must be >= 1");
  if (options.record_rollout && method.records_rollouts)
    throw std::invalid_argument("emulated clock: E-Navi rollouts (training) are recorded on the virtual clock only");
  if (options.decisions)
    throw std::invalid_argument("emulated clock: decisions taken outside the stack stop the virtual clock only");
  impl_->method = &method;
  impl_->options = options;
  impl_->initial = initial;
  impl_->threads = threads;
  impl_->policy = policy;
  impl_->board = board;
  impl_->dilation = dilation;
  impl_->emulation = emulation;
  impl_->Start();  // on a throw, ~Impl cleans up what was created
}

EmulatedNavLink::~EmulatedNavLink() = default;

pid_t EmulatedNavLink::navstack_pid() const { return impl_->child; }

void EmulatedNavLink::OnState(const navstack::VehicleState& state) {
  Impl& m = *impl_;
  m.SetEpoch();
  {
    std::lock_guard l(m.pub_mutex);
    m.odometry_queue.emplace_back(m.Due(state.t), emulation::ShmChannel::ToMsg(state));
  }
  m.pub_cv.notify_all();
}

void EmulatedNavLink::OnFrame(navstack::DepthFramePtr frame) {
  Impl& m = *impl_;
  m.SetEpoch();
  {
    // The previous frame is due long before this one is captured; wait if it is not out yet.
    std::unique_lock l(m.pub_mutex);
    m.pub_cv.wait(l, [&] { return !m.frame_staged || m.pub_stop; });
  }
  if (frame->image.width != m.channel->width() || frame->image.height != m.channel->height())
    throw std::invalid_argument("emulated clock: frame is " + std::to_string(frame->image.width) + " x " +
                                std::to_string(frame->image.height) + ", the channel " +
                                std::to_string(m.channel->width()) + " x " + std::to_string(m.channel->height()));
  // Rendered ahead of time: copied into the channel's back slot now, published at its due time.
  const emulation::FrameSlot slot = m.channel->BeginFrame();
  emulation::FrameHeader& h = *slot.header;
  h.t = frame->t;
  const Eigen::Vector3d p = frame->X_WC.translation();
  const Eigen::Quaterniond q(frame->X_WC.rotation());
  for (int i = 0; i < 3; ++i) {
    h.p_WC[i] = p[i];
    h.v_W[i] = frame->v_W[i];
  }
  h.q_WC[0] = q.w();
  h.q_WC[1] = q.x();
  h.q_WC[2] = q.y();
  h.q_WC[3] = q.z();
  std::memcpy(slot.depth, frame->image.data.data(), frame->image.data.size() * sizeof(float));
  {
    std::lock_guard l(m.pub_mutex);
    m.frame_staged = true;
    m.frame_due = m.Due(frame->t) - m.frame_early;
  }
  m.pub_cv.notify_all();
}

void EmulatedNavLink::AdvanceTo(double t) {
  Impl& m = *impl_;
  m.CheckSignal("during the episode");
  m.SetEpoch();
  // The simulator may run `lead` ahead: what it computes for t reaches the navstack at t.
  const Clock::time_point due = m.Due(t) - m.lead;
  const Clock::time_point now = Clock::now();
  ++m.steps;
  if (now > due) {
    const double lag = std::chrono::duration<double>(now - due).count();
    m.lag_sum_s += lag;
    m.lag_max_s = std::max(m.lag_max_s, lag);
    if (lag > 1e-3) ++m.steps_late;
  } else {
    std::this_thread::sleep_until(due);
  }
  m.last_t = t;
  m.TakeOutputs();
  const Clock::time_point after = Clock::now();
  if (after >= m.next_liveness_check) {
    m.next_liveness_check = after + std::chrono::milliseconds(20);
    m.CheckChild();
  }
  if (after >= m.next_sweep) {  // threads the stack may have started since
    m.next_sweep = after + std::chrono::seconds(1);
    m.slot->group().SweepThreads();
  }
}

navstack::TrajectorySample EmulatedNavLink::Reference(double t) { return impl_->mirror.Reference(t); }

std::vector<navstack::NavEvent> EmulatedNavLink::TakeEvents() {
  Impl& m = *impl_;
  std::vector<navstack::NavEvent> out;
  const std::uint64_t head = m.shared->event_head.load(std::memory_order_acquire);
  if (head - m.event_tail > static_cast<std::uint64_t>(kEventRing)) {
    m.events_lost += static_cast<std::int64_t>(head - m.event_tail - kEventRing);
    m.event_tail = head - kEventRing;
  }
  for (; m.event_tail < head; ++m.event_tail) {
    EventWire e;
    std::uint32_t seen = 1;  // odd: never a settled sequence, so any settled copy is taken
    if (!m.shared->events[m.event_tail % kEventRing].Read(&e, &seen)) {
      ++m.events_lost;
      continue;
    }
    e.kind[sizeof e.kind - 1] = '\0';
    e.detail[sizeof e.detail - 1] = '\0';
    out.push_back({e.t, e.kind, e.detail});
  }
  return out;
}

navstack::TaskRates EmulatedNavLink::rates() const { return impl_->current_rates; }

double EmulatedNavLink::map_resolution() const { return impl_->current_map_resolution; }

double EmulatedNavLink::OffBoardSeconds(navstack::TaskId, const navstack::WorkCounts&, double host_cpu_s) const {
  return host_cpu_s / impl_->speed;
}

sim::NavAccounting EmulatedNavLink::Accounting() const {
  const Impl& m = *impl_;
  if (m.shared != nullptr) {
    auto fresh = std::make_unique<StatsWire>();
    std::uint32_t seq = m.stats_seq;
    if (m.shared->stats.Read(fresh.get(), &seq)) {
      m.stats_seq = seq;
      m.stats = std::move(fresh);
    }
  }
  const Clock::time_point now = Clock::now();
  if (now >= m.next_proc_sample) {
    m.next_proc_sample = now + std::chrono::milliseconds(500);
    m.SampleProc();
  }
  sim::NavAccounting acc;
  for (int i = 0; i < navstack::kTaskCount; ++i) acc.tasks[i] = m.stats->tasks[i];
  acc.plan_failures = m.plan_failures;
  acc.notes = m.notes;
  const double T = m.last_t;
  if (T > 0) {
    // The paper's psutil figure: every thread of the navstack process from /proc, in board cores.
    double total = 0;
    std::string per_thread;
    std::map<std::string, double> by_name;
    for (const auto& [tid, v] : m.thread_cpu) by_name[v.first] += v.second;
    for (const auto& [name, cpu] : by_name) {
      total += cpu;
      per_thread += (per_thread.empty() ? "" : ", ") + name + " " + Fixed(100.0 * cpu / m.speed / T, 1) + " %";
    }
    acc.notes["emulation.proc_util"] = "navstack process " + Fixed(100.0 * total / m.speed / T, 1) +
                                       " % of a board core over the flight (/proc per thread: " + per_thread + ")";
    std::int64_t frames = 0, late = 0;
    double late_sum = 0, late_max = 0;
    {
      std::lock_guard l(m.pub_mutex);
      frames = m.frames_published;
      late = m.frames_late;
      late_sum = m.frame_late_sum_s;
      late_max = m.frame_late_max_s;
    }
    acc.notes["emulation.pacing"] =
        "simulator " + Fixed(1e3 * std::chrono::duration<double>(m.lead).count(), 0) +
        " ms wall ahead of the navstack; behind that schedule by > 1 ms at " + std::to_string(m.steps_late) + " of " +
        std::to_string(m.steps) + " steps (mean " +
        Fixed(m.steps > 0 ? 1e3 * m.lag_sum_s / static_cast<double>(m.steps) : 0.0, 3) + " ms, max " +
        Fixed(1e3 * m.lag_max_s, 1) + " ms); frames handed over after their capture time x k (by > 1 ms) " +
        std::to_string(late) + " of " + std::to_string(frames) + " (mean " +
        Fixed(frames > 0 ? 1e3 * late_sum / static_cast<double>(frames) : 0.0, 2) + " ms, max " +
        Fixed(1e3 * late_max, 1) + " ms wall)";
  }
  const StatsWire& s = *m.stats;
  acc.notes["emulation.ipc"] = std::to_string(s.frames_received) + " frames taken, " +
                               std::to_string(s.frames_dropped) + " overwritten unread; " +
                               std::to_string(s.odometry_applied) + " odometry updates applied" +
                               (m.events_lost > 0 ? "; " + std::to_string(m.events_lost) + " events lost" : "");
  {
    // Did each job run at the board's speed, and does the cost model price it as measured?
    std::string speed_check, cost_check;
    for (int i = 0; i < navstack::kTaskCount; ++i) {
      const navstack::TaskStats& t = s.tasks[i];
      if (t.completed == 0 || t.host_cpu_s <= 0) continue;
      const std::string name(navstack::TaskName(static_cast<TaskId>(i)));
      const double expected_wall = t.host_cpu_s * m.dilation / m.speed;
      speed_check += (speed_check.empty() ? "" : ", ") + name + " " + Fixed(s.execution_wall_s[i] / expected_wall, 3);
      cost_check += (cost_check.empty() ? "" : ", ") + name + " " + Fixed(s.model_board_s[i] / t.busy_s, 3);
    }
    acc.notes["emulation.speed_check"] =
        "job execution wall time / (its CPU time x k / speed), 1 = exactly one board core: " + speed_check;
    acc.notes["emulation.cost_check"] =
        "the virtual clock's cost model prices the same jobs at this fraction of their measured board time: " +
        cost_check;
  }
  std::string lags;
  for (int i = 0; i < navstack::kTaskCount; ++i)
    if (s.release_lags[i] > 0)
      lags += (lags.empty() ? "" : ", ") + std::string(navstack::TaskName(static_cast<navstack::TaskId>(i))) + " " +
              std::to_string(s.release_lags[i]);
  acc.notes["emulation.release_lag"] =
      (lags.empty() ? std::string("none") : lags) +
      " (release instants the release thread reached after the next was due, no job active: not counted as released "
      "or missed)";
  acc.notes["emulation.lock"] = std::to_string(s.lock.commits) + " commits waited " +
                                Fixed(1e3 * s.lock.commit_wait_s, 1) + " ms in total (longest " +
                                Fixed(1e3 * s.lock.commit_wait_max_s, 1) + " ms wall) for running jobs";
  return acc;
}

void RegisterEmulatedLink() {
  sim::RegisterLink({sim::kNavstackMethod, "emulated",
                     "the stack in its own process, throttled by cgroups to the board's speed, in dilated wall time",
                     [](const sim::LinkRequest& r) -> std::unique_ptr<sim::NavLink> {
                       return std::make_unique<EmulatedNavLink>(*r.method, *r.nav, r.threads, r.policy, *r.board,
                                                                r.spec->dilation, r.initial, *r.emulation);
                     },
                     ""});
}

}  // namespace enavi::emulation
