#include "workers/ros/ros_nav_link.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <pthread.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "api/fixed.h"
#include "navstack/runtime/proc_stat.h"
#include "workers/emulation/board_slot.h"
#include "workers/emulation/termination_signals.h"
#include "workers/ros/launch_plan.h"
#include "workers/ros/process_supervisor.h"
#include "workers/ros/stack_cpu.h"
#include "workers/sim/link_registry.h"

extern char** environ;

namespace enavi::ros {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using api::Fixed;

// The episode's processes, by their index in the supervisor's list: the order the supervisor
// ends them in on its own is the reverse (the stack first, the master last).
enum ProcessId : int { kMaster = 0, kRecorder = 1, kStack = 2 };

// A free TCP port on the loopback interface (the kernel's choice; the master binds it right after).
int FreeLoopbackPort() {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error(std::string("ros: socket: ") + std::strerror(errno));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  socklen_t len = sizeof addr;
  const bool ok = bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0 &&
                  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) == 0;
  close(fd);
  if (!ok) throw std::runtime_error(std::string("ros: no free loopback port: ") + std::strerror(errno));
  return ntohs(addr.sin_port);
}

bool PortAccepts(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  const bool ok = connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
  close(fd);
  return ok;
}

std::vector<std::string> CurrentEnvironment() {
  std::vector<std::string> env;
  for (char** e = environ; e != nullptr && *e != nullptr; ++e) env.emplace_back(*e);
  return env;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

Clock::duration Seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

struct RosNavLink::Impl {
  RosLinkOptions o;
  std::map<std::string, std::string> notes;

  // Resources, released in reverse order by Shutdown().
  std::optional<emulation::ScopedTerminationSignals> signals;
  std::unique_ptr<emulation::BoardSlot> slot;
  bool own_dir = false;
  EpisodeFiles files;
  std::string master_uri;
  std::unique_ptr<ProcessSupervisor> supervisor;
  std::unique_ptr<BridgeNode> node;
  bool stack_running = false, recorder_running = false;
  std::unique_ptr<StackCpuMonitor> cpu;

  // Pacing and publishing (the emulated clock's rules: emulated_nav_link.h).
  double speed = 1.0, dilation = 1.0;
  Clock::time_point epoch{};
  bool epoch_set = false;
  Clock::duration lead = std::chrono::microseconds(20'000);
  Clock::duration frame_early = std::chrono::microseconds(2'000);
  std::thread publisher;
  std::mutex pub_mutex;
  std::condition_variable pub_cv;
  bool pub_stop = false;
  double sim_horizon = -1;        // the clock never runs ahead of the simulation
  std::int64_t clock_ticks = 0;   // published /clock ticks (tick k is k / clock_hz)
  std::deque<std::pair<Clock::time_point, navstack::VehicleState>> odometry_queue;
  std::deque<std::pair<Clock::time_point, navstack::DepthFramePtr>> frame_queue;
  std::int64_t frames_published = 0, frames_late = 0, odometry_published = 0;
  double frame_late_max_s = 0;
  double next_odometry_t = 0;
  std::string publish_error;

  // What the stack did.
  std::optional<sim::LinkFailure> failure;
  std::optional<Command> command;
  double first_command_t = -1;
  std::int64_t commands = 0;
  std::map<std::string, std::int64_t> command_types;
  std::vector<navstack::NavEvent> events;
  double last_t = 0;
  double ready_wall_s = 0;
  Clock::time_point next_check{}, next_sweep{}, next_cpu{}, next_master_check{};
  std::int64_t steps = 0, steps_late = 0;
  double lag_max_s = 0;
  std::map<std::string, double> final_cpu;  // host CPU seconds by process name, at the end
  std::map<std::string, double> final_threads;  // and by thread
  // The same at t = 0: what the stack spent starting up is not flight CPU (reported apart).
  std::map<std::string, double> start_cpu, start_threads;
  bool finished = false;

  ~Impl() { Shutdown(); }

  Clock::time_point Due(double t) const { return epoch + Seconds(t * dilation); }
  void Start();
  void StartMaster();
  void WaitUntilReady();
  void PublisherLoop();
  void Check();
  void Fail(const std::string& reason, const std::string& detail);
  void StackExited(int status);
  void StopStack();
  void Shutdown();
};

void RosNavLink::Impl::Fail(const std::string& reason, const std::string& detail) {
  if (failure) return;
  failure = sim::LinkFailure{reason, detail};
  events.push_back({last_t, reason, detail.substr(0, 200)});
}

void RosNavLink::Impl::StackExited(int status) {
  stack_running = false;
  const bool clean = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  notes["ros.stack_exit"] = navstack::DescribeWaitStatus(status) + " at t = " + Fixed(last_t, 3) + " s";
  notes["ros.stack_log_tail"] = LogTail(files.stack_log);
  Fail(clean ? "stack_exited" : "stack_crashed",
       "the stack ended (" + navstack::DescribeWaitStatus(status) + ") before the episode did; log: " + files.stack_log);
}

void RosNavLink::Impl::StartMaster() {
  // The port is free when chosen; another process may take it first, so try a few.
  for (int attempt = 0; attempt < 3; ++attempt) {
    const int port = FreeLoopbackPort();
    master_uri = "http://127.0.0.1:" + std::to_string(port) + "/";
    std::vector<ProcessSpec> specs(3);
    const std::vector<std::string> env = EpisodeEnvironment(CurrentEnvironment(), o.stack, master_uri, files);
    specs[kMaster] = {"master", MasterCommand(port), env, files.master_log, false, SIGINT, SIGKILL};
    specs[kRecorder] = {"rosbag", files.bag.empty() ? std::vector<std::string>{"true"} : BagCommand(o.stack, files.bag),
                        env, files.bag_log, false, SIGINT, SIGINT};
    const std::string launch_xml = o.stack.launch.empty() ? std::string() : ReadFile(o.stack.launch);
    specs[kStack] = {"stack", StackCommand(o.stack, launch_xml, EpisodeLaunchArgs(o.geometry), master_uri), env,
                     files.stack_log, true, SIGINT, SIGKILL};
    notes["ros.command"] = [&] {
      std::string c;
      for (const std::string& a : specs[kStack].argv) c += (c.empty() ? "" : " ") + a;
      return c;
    }();
    supervisor.reset();
    supervisor = std::make_unique<ProcessSupervisor>(std::move(specs), &slot->group(), files.supervisor_log);
    supervisor->Start(kMaster);
    const auto give_up = Clock::now() + std::chrono::seconds(20);
    bool exited = false;
    while (Clock::now() < give_up) {
      for (const ProcessExit& e : supervisor->Poll()) exited = exited || e.id == kMaster;
      if (exited || PortAccepts(port)) break;
      if (const int sig = emulation::PendingTerminationSignal())
        throw std::runtime_error(std::string("ros: interrupted by ") + strsignal(sig) + " while the master started");
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (!exited && PortAccepts(port)) {
      notes["ros.master"] = master_uri + " (rosmaster, pid " + std::to_string(supervisor->pid(kMaster)) + ")";
      return;
    }
  }
  throw std::runtime_error("ros: the master did not start (3 attempts); its log: " + files.master_log + ":\n" +
                           LogTail(files.master_log, 10));
}

void RosNavLink::Impl::Start() {
  // 1. The board on this host, and somewhere for the episode's files.
  signals.emplace();
  slot = std::make_unique<emulation::BoardSlot>(o.board, o.dilation, o.emulation);
  speed = slot->speed();
  dilation = slot->dilation();
  notes.insert(slot->notes().begin(), slot->notes().end());
  std::string dir = o.output_dir;
  if (dir.empty()) {
    std::string templ = (fs::temp_directory_path() / "enavi-ros-XXXXXX").string();
    if (mkdtemp(templ.data()) == nullptr)
      throw std::runtime_error(std::string("ros: cannot create a temporary directory: ") + std::strerror(errno));
    dir = templ;
    own_dir = true;
  }
  files = FilesIn(dir, "");
  files.bag = o.bag_file;
  for (const std::string& d : {files.dir, files.ros_log, files.ros_home}) fs::create_directories(d);
  if (!files.bag.empty()) fs::create_directories(fs::path(files.bag).parent_path());
  notes["ros.files"] = files.dir + (own_dir ? " (removed after the episode)" : "");

  // 2. The master (under the supervisor, forked before roscpp starts any thread), our node.
  StartMaster();
  node = std::make_unique<BridgeNode>(o.stack, master_uri, o.geometry, [&] {
    CommandLimits l;
    l.bounds = o.geometry.bounds;
    return l;
  }());

  // 3. The recorder, then the stack inside the board's groups.
  if (!files.bag.empty()) {
    supervisor->Start(kRecorder);
    recorder_running = true;
    notes["ros.bag"] = files.bag;
  }
  supervisor->Start(kStack);
  stack_running = true;
  cpu = std::make_unique<StackCpuMonitor>([this] { return slot->group().Tasks(); });
  WaitUntilReady();
  publisher = std::thread([this] { PublisherLoop(); });
}

void RosNavLink::Impl::WaitUntilReady() {
  // Sim time stands at 0 until the stack is wired up: its start-up (roslaunch, node init, at the
  // board's speed) is not flight time.
  const auto t0 = Clock::now();
  const auto give_up = t0 + Seconds(o.stack.startup_timeout_s);
  auto next_clock = t0;
  while (!failure) {
    const auto now = Clock::now();
    if (now >= next_sweep) {
      next_sweep = now + std::chrono::milliseconds(50);
      slot->group().SweepThreads();
    }
    if (now >= next_clock) {  // nodes waiting for their first /clock see one
      next_clock = now + std::chrono::milliseconds(100);
      node->PublishClock(0);
    }
    for (const ProcessExit& e : supervisor->Poll()) {
      if (e.id == kStack) StackExited(e.status);
      if (e.id == kMaster) Fail("master_died", "the ROS master ended during start-up: " + navstack::DescribeWaitStatus(e.status));
    }
    if (failure) break;
    if (node->CommandAdvertised()) {
      ready_wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
      notes["ros.startup"] = Fixed(ready_wall_s, 2) + " s wall from start to " + o.stack.Topic("command") + " advertised";
      events.push_back({0, "stack_ready", Fixed(ready_wall_s, 2) + " s wall"});
      return;
    }
    if (now >= give_up) {
      notes["ros.stack_log_tail"] = LogTail(files.stack_log);
      Fail("stack_not_ready", "nothing advertised " + o.stack.Topic("command") + " within " +
                                  Fixed(o.stack.startup_timeout_s, 0) + " s (wall) of the stack's start; log: " +
                                  files.stack_log);
      break;
    }
    if (const int sig = emulation::PendingTerminationSignal())
      throw std::runtime_error(std::string("ros: interrupted by ") + strsignal(sig) + " while the stack started");
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

void RosNavLink::Impl::PublisherLoop() {
  pthread_setname_np(pthread_self(), "ros-publisher");
  const double clock_dt = 1.0 / o.stack.clock_hz;
  std::unique_lock l(pub_mutex);
  while (!pub_stop) {
    if (!epoch_set) {
      pub_cv.wait(l);
      continue;
    }
    // The next thing due: a clock tick the simulation has reached, an odometry message, a frame.
    const double tick_t = static_cast<double>(clock_ticks) * clock_dt;
    Clock::time_point next = Clock::time_point::max();
    if (tick_t <= sim_horizon + 1e-9) next = Due(tick_t);
    if (!odometry_queue.empty()) next = std::min(next, odometry_queue.front().first);
    if (!frame_queue.empty()) next = std::min(next, frame_queue.front().first);
    if (next == Clock::time_point::max()) {
      pub_cv.wait(l);
      continue;
    }
    if (Clock::now() < next) {
      pub_cv.wait_until(l, next);
      continue;
    }
    const Clock::time_point now = Clock::now();
    // In the order a stack expects them at one instant: the time, the state, then the frame.
    std::optional<double> clock;
    while (static_cast<double>(clock_ticks) * clock_dt <= sim_horizon + 1e-9 &&
           Due(static_cast<double>(clock_ticks) * clock_dt) <= now) {
      clock = static_cast<double>(clock_ticks++) * clock_dt;
    }
    std::vector<navstack::VehicleState> states;
    while (!odometry_queue.empty() && odometry_queue.front().first <= now) {
      states.push_back(odometry_queue.front().second);
      odometry_queue.pop_front();
    }
    std::vector<std::pair<Clock::time_point, navstack::DepthFramePtr>> frames;
    while (!frame_queue.empty() && frame_queue.front().first <= now) {
      frames.push_back(frame_queue.front());
      frame_queue.pop_front();
    }
    l.unlock();
    try {
      if (clock) node->PublishClock(*clock);
      for (const navstack::VehicleState& s : states) node->PublishOdometry(s);
      for (const auto& [due, frame] : frames) {
        node->PublishFrame(*frame);
        const double late = std::chrono::duration<double>(Clock::now() - (due + frame_early)).count();
        frame_late_max_s = std::max(frame_late_max_s, late);
        if (late > 1e-3) ++frames_late;
      }
    } catch (const std::exception& e) {
      l.lock();
      publish_error = e.what();
      return;
    }
    l.lock();
    odometry_published += static_cast<std::int64_t>(states.size());
    frames_published += static_cast<std::int64_t>(frames.size());
    pub_cv.notify_all();
  }
}

void RosNavLink::Impl::Check() {
  const Clock::time_point now = Clock::now();
  if (now >= next_check) {
    next_check = now + std::chrono::milliseconds(20);
    for (const ProcessExit& e : supervisor->Poll()) {
      if (e.id == kStack && stack_running) StackExited(e.status);
      if (e.id == kMaster) Fail("master_died", "the ROS master ended: " + navstack::DescribeWaitStatus(e.status));
      if (e.id == kRecorder) {
        recorder_running = false;
        notes["ros.bag_exit"] = navstack::DescribeWaitStatus(e.status) + " at t = " + Fixed(last_t, 3) + " s";
      }
    }
  }
  if (now >= next_sweep) {  // threads the stack started since get their one board core
    next_sweep = now + std::chrono::milliseconds(50);
    slot->group().SweepThreads();
  }
  if (now >= next_cpu) {
    next_cpu = now + std::chrono::milliseconds(250);
    cpu->Sample();
  }
  if (now >= next_master_check) {
    next_master_check = now + std::chrono::seconds(2);
    if (!node->MasterAlive()) Fail("master_died", "the ROS master stopped answering");
  }
  {
    std::lock_guard l(pub_mutex);
    if (!publish_error.empty()) throw std::runtime_error("ros: publishing failed: " + publish_error);
  }
  // What the stack commanded.
  const CommandInbox in = node->TakeCommands();
  if (in.newest) {
    if (!command) {
      first_command_t = last_t;
      events.push_back({last_t, "first_command", in.newest->type});
    }
    ++command_types[in.newest->type];
    command = in.newest;
  }
  commands = in.received;
  if (in.error) Fail(in.error_kind, *in.error);
  if (!command && last_t >= o.stack.command_timeout_s)
    Fail("no_command", "no command on " + o.stack.Topic("command") + " within " + Fixed(o.stack.command_timeout_s, 1) +
                           " s of sim time");
}

void RosNavLink::Impl::StopStack() {
  if (cpu && slot) {
    cpu->Sample();
    final_cpu = cpu->ByName();
    final_threads = cpu->ByThread();
  }
  if (stack_running) {
    // roslaunch shuts its nodes down on SIGINT; what is left after 2 s is killed.
    const ProcessExit e = supervisor->Stop(kStack, 2.0);
    stack_running = false;
    notes["ros.stack_stop"] = "stopped at the end of the episode (" + navstack::DescribeWaitStatus(e.status) + ")";
  }
  if (recorder_running) {
    const ProcessExit e = supervisor->Stop(kRecorder, 10.0);  // closes the bag
    recorder_running = false;
    notes["ros.bag_exit"] = navstack::DescribeWaitStatus(e.status);
  }
}

void RosNavLink::Impl::Shutdown() {
  if (publisher.joinable()) {
    {
      std::lock_guard l(pub_mutex);
      pub_stop = true;
    }
    pub_cv.notify_all();
    publisher.join();
  }
  try {
    if (supervisor) StopStack();
  } catch (const std::exception& e) {
    notes["ros.cleanup"] = e.what();
  }
  node.reset();        // leaves the graph before the master goes
  supervisor.reset();  // ends the master (and anything left), then exits
  std::string cleanup_error = slot ? slot->Release() : std::string();
  slot.reset();
  if (!cleanup_error.empty()) std::fprintf(stderr, "enavi: ROS episode clean-up: %s\n", cleanup_error.c_str());
  if (own_dir && !files.dir.empty()) {
    std::error_code ec;
    fs::remove_all(files.dir, ec);
    own_dir = false;
  }
  signals.reset();  // re-raises a SIGINT/SIGTERM that arrived during the episode, now that nothing is left
}

// ---------------------------------------------------------------------------------------------

RosNavLink::RosNavLink(RosLinkOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->o = std::move(options);
  impl_->Start();  // on a throw, ~Impl cleans up what was created
}

RosNavLink::~RosNavLink() = default;

void RosNavLink::OnState(const navstack::VehicleState& state) {
  Impl& m = *impl_;
  {
    std::lock_guard l(m.pub_mutex);
    if (!m.epoch_set) {
      m.cpu->Sample();
      m.start_cpu = m.cpu->ByName();
      m.start_threads = m.cpu->ByThread();
      // Sim time 0 a little ahead, so the simulator has its lead from the start.
      m.epoch = Clock::now() + m.lead + std::chrono::milliseconds(5);
      m.epoch_set = true;
      m.node->PublishGoal(0);
    }
    if (state.t + 1e-9 >= m.next_odometry_t) {
      m.next_odometry_t += 1.0 / m.o.stack.odometry_hz;
      m.odometry_queue.emplace_back(m.Due(state.t), state);
    }
  }
  m.pub_cv.notify_all();
}

void RosNavLink::OnFrame(navstack::DepthFramePtr frame) {
  Impl& m = *impl_;
  {
    std::lock_guard l(m.pub_mutex);
    m.frame_queue.emplace_back(m.Due(frame->t) - m.frame_early, std::move(frame));
  }
  m.pub_cv.notify_all();
}

void RosNavLink::AdvanceTo(double t) {
  Impl& m = *impl_;
  if (const int sig = emulation::PendingTerminationSignal())
    throw std::runtime_error(std::string("ros: interrupted by ") + strsignal(sig) + " during the episode");
  // The simulator may run `lead` ahead: what it computes for t reaches the stack at t.
  const Clock::time_point due = m.Due(t) - m.lead;
  const Clock::time_point now = Clock::now();
  ++m.steps;
  if (now > due) {
    const double lag = std::chrono::duration<double>(now - due).count();
    m.lag_max_s = std::max(m.lag_max_s, lag);
    if (lag > 1e-3) ++m.steps_late;
  } else {
    std::this_thread::sleep_until(due);
  }
  {
    std::lock_guard l(m.pub_mutex);
    m.sim_horizon = t;
  }
  m.pub_cv.notify_all();
  m.last_t = t;
  m.Check();
}

navstack::TrajectorySample RosNavLink::Reference(double t) {
  const Impl& m = *impl_;
  if (m.command) return SampleCommand(*m.command, t);
  // Until its first command the vehicle hovers where it started.
  navstack::TrajectorySample hold;
  hold.p = m.o.initial.p_WB;
  hold.yaw = YawOf(m.o.initial.q_WB);
  return hold;
}

std::vector<navstack::NavEvent> RosNavLink::TakeEvents() { return std::exchange(impl_->events, {}); }

navstack::TaskRates RosNavLink::rates() const {
  navstack::TaskRates r;
  r.f_per = r.f_plan = r.f_col = r.f_dif = r.resolution = 0;
  r.collision_on_map_update = false;
  return r;
}

void RosNavLink::FinishEpisode(bool, bool) {
  Impl& m = *impl_;
  if (m.finished) return;
  m.finished = true;
  m.StopStack();
}

double RosNavLink::OffBoardSeconds(navstack::TaskId, const navstack::WorkCounts&, double host_cpu_s) const {
  return host_cpu_s / impl_->speed;
}

std::optional<sim::LinkFailure> RosNavLink::failure() const { return impl_->failure; }

sim::NavAccounting RosNavLink::Accounting() const {
  const Impl& m = *impl_;
  sim::NavAccounting acc;
  acc.notes = m.notes;
  // Host CPU of each process over the flight (since t = 0) -> board seconds (x 1 / speed: a
  // board core does `speed` of a host core's work per second).
  const auto since_start = [](const std::map<std::string, double>& now, const std::map<std::string, double>& start) {
    std::map<std::string, double> out;
    for (const auto& [name, cpu_s] : now) {
      const auto s = start.find(name);
      out[name] = std::max(0.0, cpu_s - (s == start.end() ? 0.0 : s->second));
    }
    return out;
  };
  const std::map<std::string, double> host = m.finished ? m.final_cpu : m.cpu ? m.cpu->ByName() : std::map<std::string, double>{};
  const double T = m.last_t;
  const auto pct = [&](double host_s) { return Fixed(T > 0 ? 100.0 * host_s / m.speed / T : 0.0, 1) + " %"; };
  std::string per_node, startup;
  double total = 0, startup_total = 0;
  for (const auto& [name, cpu_s] : since_start(host, m.start_cpu)) {
    acc.process_cpu_board_s[name] = cpu_s / m.speed;
    total += cpu_s;
    per_node += (per_node.empty() ? "" : ", ") + name + " " + pct(cpu_s);
  }
  for (const auto& [name, cpu_s] : m.start_cpu) {
    startup_total += cpu_s;
    startup += (startup.empty() ? "" : ", ") + name + " " + Fixed(cpu_s / m.speed, 2) + " s";
  }
  // The busiest threads (up to 12), so that a user sees where inside a node the CPU goes.
  const std::map<std::string, double> threads =
      m.finished ? m.final_threads : m.cpu ? m.cpu->ByThread() : std::map<std::string, double>{};
  std::vector<std::pair<double, std::string>> busiest;
  for (const auto& [name, cpu_s] : since_start(threads, m.start_threads)) busiest.emplace_back(cpu_s, name);
  std::sort(busiest.rbegin(), busiest.rend());
  std::string per_thread;
  for (std::size_t i = 0; i < busiest.size() && i < 12; ++i)
    per_thread += (per_thread.empty() ? "" : ", ") + busiest[i].second + " " + pct(busiest[i].first);
  acc.notes["ros.threads"] = "busiest threads over the flight, % of a board core: " + per_thread;
  acc.notes["ros.cpu"] = "the stack's processes " + pct(total) + " of a board core over the flight (/proc per process: " +
                         per_node + ")";
  acc.notes["ros.startup_cpu"] = Fixed(startup_total / m.speed, 2) + " board core-seconds before t = 0 (" + startup + ")";
  std::string types;
  for (const auto& [type, n] : m.command_types) types += (types.empty() ? "" : ", ") + type + " " + std::to_string(n);
  acc.notes["ros.commands"] = std::to_string(m.commands) + " received" +
                              (m.first_command_t >= 0 ? ", the first at t = " + Fixed(m.first_command_t, 3) + " s" : "") +
                              (types.empty() ? "" : " (newest taken per step: " + types + ")");
  acc.notes["ros.pacing"] = "simulator behind its schedule by > 1 ms at " + std::to_string(m.steps_late) + " of " +
                            std::to_string(m.steps) + " steps (max " + Fixed(1e3 * m.lag_max_s, 1) + " ms); frames published " +
                            std::to_string(m.frames_published) + " (" + std::to_string(m.frames_late) +
                            " late by > 1 ms, max " + Fixed(1e3 * std::max(0.0, m.frame_late_max_s), 1) +
                            " ms), odometry " + std::to_string(m.odometry_published) + ", clock ticks " +
                            std::to_string(m.clock_ticks) + " at " + Fixed(m.o.stack.clock_hz, 0) + " Hz";
  return acc;
}

void RegisterRosLink() {
  sim::LinkInfo link{sim::kRosMethod, "emulated", "a user's ROS 1 stack in the board's cgroups, in dilated wall time",
                     [](const sim::LinkRequest& r) -> std::unique_ptr<sim::NavLink> {
                       RosLinkOptions o;
                       o.stack = *r.spec->ros;
                       o.board = *r.board;
                       o.dilation = r.spec->dilation;
                       o.geometry.start = r.start;
                       o.geometry.goal = r.goal;
                       o.geometry.start_yaw = r.start_yaw;
                       o.geometry.bounds = r.bounds;
                       o.geometry.camera = r.camera;
                       o.geometry.X_BC = r.X_BC;
                       o.geometry.board = r.board->id;
                       o.geometry.cores = r.board->cores;
                       o.geometry.seed = r.spec->seed;
                       o.initial = r.initial;
                       o.output_dir = r.output_dir;
                       o.bag_file = r.bag_file;
                       o.emulation = *r.emulation;  // the spec's speed_probe applied
                       return std::make_unique<RosNavLink>(std::move(o));
                     },
                     ""};
  // The bridge was built; the host must also have the ROS programs it starts.
  for (const char* program : {"rosmaster", "roslaunch", "rosbag"}) {
    bool found = false;
    for (const char* dir : {"/usr/bin", "/usr/local/bin"}) found = found || access((std::string(dir) + "/" + program).c_str(), X_OK) == 0;
    if (!found) {
      link.unavailable = std::string("this host has no ") + program +
                         " (Debian's python3-rosmaster, python3-roslaunch, python3-rosbag: scripts/install-deps.sh)";
      break;
    }
  }
  sim::RegisterLink(std::move(link));
}

}  // namespace enavi::ros
