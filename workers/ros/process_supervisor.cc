#include "workers/ros/process_supervisor.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <utility>

#include "workers/emulation/episode_cgroup.h"

namespace enavi::ros {

// The wire between the simulator and the supervisor: one fixed-size record per datagram
// (SOCK_SEQPACKET keeps the boundaries).
struct ProcessSupervisor::Message {
  enum Op : std::int32_t { kStart = 1, kStop = 2, kStarted = 3, kExited = 4, kStopped = 5, kBye = 6 };
  std::int32_t op = 0;
  std::int32_t id = -1;
  std::int64_t value = 0;  // kStarted: pid or -errno; kExited, kStopped: waitpid status
  double grace_s = 0;
};

namespace {

using Message = ProcessSupervisor::Message;
using Clock = std::chrono::steady_clock;

std::vector<char*> CStrings(const std::vector<std::string>& v) {
  std::vector<char*> out;
  for (const std::string& s : v) out.push_back(const_cast<char*>(s.c_str()));
  out.push_back(nullptr);
  return out;
}

// Written with write(2) only: usable between fork and exec.
void WriteText(int fd, const std::string& text) {
  const char* p = text.data();
  std::size_t left = text.size();
  while (left > 0) {
    const ssize_t n = write(fd, p, left);
    if (n <= 0) return;
    p += n;
    left -= static_cast<std::size_t>(n);
  }
}

// The supervisor process: starts, stops and reaps, and cleans up if the simulator vanishes.
class Supervisor {
 public:
  Supervisor(int fd, const std::vector<ProcessSpec>& specs, emulation::EpisodeCgroup* board, int log_fd)
      : fd_(fd), specs_(specs), board_(board), log_(log_fd), pids_(specs.size(), 0), done_(specs.size(), false) {}

  [[noreturn]] void Run() {
    for (;;) {
      Reap();
      pollfd p{fd_, POLLIN, 0};
      const int r = poll(&p, 1, 20);  // also a 50 Hz tick for reaping (no SIGCHLD handler needed)
      if (r < 0 && errno != EINTR) Teardown("poll failed");
      if (r <= 0) continue;
      Message m;
      const ssize_t n = recv(fd_, &m, sizeof m, 0);
      if (n == 0 || (n < 0 && errno != EINTR && errno != EAGAIN)) Teardown("the simulator went away");
      if (n != static_cast<ssize_t>(sizeof m)) continue;
      if (m.op == Message::kBye) Teardown(nullptr);
      if (m.op == Message::kStart) StartProcess(m.id);
      if (m.op == Message::kStop) StopProcess(m.id, m.grace_s);
    }
  }

 private:
  void Reply(std::int32_t op, int id, std::int64_t value) {
    Message m;
    m.op = op;
    m.id = id;
    m.value = value;
    send(fd_, &m, sizeof m, MSG_NOSIGNAL);
  }

  // Reaps every child that ended: ours are reported, orphans adopted as subreaper just go.
  void Reap() {
    for (;;) {
      int status = 0;
      const pid_t pid = waitpid(-1, &status, WNOHANG);
      if (pid <= 0) return;
      for (std::size_t i = 0; i < pids_.size(); ++i) {
        if (pids_[i] == pid && !done_[i]) {
          done_[i] = true;
          Reply(Message::kExited, static_cast<int>(i), status);
        }
      }
    }
  }

  void StartProcess(int id) {
    if (id < 0 || static_cast<std::size_t>(id) >= specs_.size() || pids_[id] != 0) {
      Reply(Message::kStarted, id, -EINVAL);
      return;
    }
    const ProcessSpec& spec = specs_[static_cast<std::size_t>(id)];
    std::vector<char*> argv = CStrings(spec.argv);
    std::vector<char*> env = CStrings(spec.env);
    const int log = open(spec.log_file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    const pid_t pid = fork();
    if (pid < 0) {
      if (log >= 0) close(log);
      Reply(Message::kStarted, id, -errno);
      return;
    }
    if (pid == 0) {
      // Its own session and process group, so that Stop() reaches every process it starts.
      setsid();
      prctl(PR_SET_PDEATHSIG, spec.death_signal);
      sigset_t none;
      sigemptyset(&none);
      sigprocmask(SIG_SETMASK, &none, nullptr);
      for (int sig = 1; sig < NSIG; ++sig) signal(sig, SIG_DFL);
      const int null = open("/dev/null", O_RDONLY);
      if (null >= 0) dup2(null, 0);
      if (log >= 0) {
        dup2(log, 1);
        dup2(log, 2);
      }
      close_range(3, ~0U, 0);
      if (spec.in_board && board_ != nullptr) {
        if (emulation::CgroupStatus s = board_->AddProcess(getpid()); !s.ok) {
          WriteText(2, "enavi: cannot enter the board's cgroups: " + s.message + "\n");
          _exit(126);
        }
      }
      // execvpe looks argv[0] up in the PATH of the environment it is given.
      execvpe(argv[0], argv.data(), env.data());
      WriteText(2, "enavi: cannot run '" + spec.argv[0] + "': " + std::strerror(errno) + "\n");
      _exit(127);
    }
    if (log >= 0) close(log);
    pids_[static_cast<std::size_t>(id)] = pid;
    Reply(Message::kStarted, id, pid);
  }

  // Waits up to `grace_s` for process `i` to end; true if it did.
  bool WaitFor(std::size_t i, double grace_s) {
    const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(grace_s));
    for (;;) {
      Reap();
      if (done_[i]) return true;
      if (Clock::now() >= until) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

  void Kill(std::size_t i, int sig) {
    if (pids_[i] <= 0) return;
    kill(-pids_[i], sig);  // its process group
    kill(pids_[i], sig);
  }

  // Waits until no process of group `pgid` is left (they may outlive its leader: rosbag's
  // Python front end exits on SIGINT while its recorder still closes the bag); true if none is.
  bool WaitForGroup(pid_t pgid, Clock::time_point until) {
    for (;;) {
      Reap();
      if (kill(-pgid, 0) != 0) return true;
      if (Clock::now() >= until) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

  // Ends process `i`: its stop signal to its group, up to `grace_s` for the whole group to end,
  // then SIGKILL of the group and of everything in the board.
  void End(std::size_t i, double grace_s) {
    if (pids_[i] <= 0) return;
    if (!done_[i]) {
      const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(grace_s));
      Kill(i, specs_[i].stop_signal);
      if (!WaitFor(i, grace_s) || !WaitForGroup(pids_[i], until)) {
        Kill(i, SIGKILL);
        WaitFor(i, 5.0);
      }
    }
    // Whatever it started may have left its process group (setsid, double fork): the board's
    // cgroups hold them all.
    kill(-pids_[i], SIGKILL);
    if (specs_[i].in_board && board_ != nullptr) board_->KillTasks(5.0);
    Reap();
  }

  void StopProcess(int id, double grace_s) {
    if (id < 0 || static_cast<std::size_t>(id) >= specs_.size()) {
      Reply(Message::kStopped, id, -1);
      return;
    }
    End(static_cast<std::size_t>(id), grace_s);
    Reply(Message::kStopped, id, 0);
  }

  // Everything ends: the recorder first (it closes its bag on SIGINT), the stack, the master.
  [[noreturn]] void Teardown(const char* why) {
    if (why != nullptr && log_ >= 0) WriteText(log_, std::string("enavi supervisor: ") + why + ": ending the episode's processes\n");
    for (std::size_t k = specs_.size(); k-- > 0;) End(k, why != nullptr ? 10.0 : 2.0);
    if (why != nullptr && board_ != nullptr) board_->Remove(/*with_parent=*/true);
    _exit(0);
  }

  int fd_;
  std::vector<ProcessSpec> specs_;
  emulation::EpisodeCgroup* board_;
  int log_;
  std::vector<pid_t> pids_;
  std::vector<bool> done_;
};

}  // namespace


ProcessSupervisor::ProcessSupervisor(std::vector<ProcessSpec> specs, emulation::EpisodeCgroup* board,
                                     std::string supervisor_log)
    : specs_(std::move(specs)), pids_(specs_.size(), 0), exits_(specs_.size()) {
  int sv[2];
  if (socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv) != 0)
    throw std::runtime_error(std::string("ros: socketpair: ") + std::strerror(errno));
  const int log = open(supervisor_log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  const pid_t pid = fork();
  if (pid < 0) {
    const int err = errno;
    close(sv[0]);
    close(sv[1]);
    if (log >= 0) close(log);
    throw std::runtime_error(std::string("ros: fork: ") + std::strerror(err));
  }
  if (pid == 0) {
    // Outside the simulator's session (a group kill of the worker must leave it to clean up),
    // the reaper of every orphan below it, and holding no descriptor of the simulator's but its
    // socket and log (a worker waiting for the episode's output pipe to close must not wait on it).
    setsid();
    prctl(PR_SET_CHILD_SUBREAPER, 1);
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) signal(sig, SIG_IGN);
    signal(SIGCHLD, SIG_DFL);
    // The socket to fd 3 and the log to fd 4, through descriptors above both so that neither
    // dup2 can overwrite the other.
    const int sock_high = fcntl(sv[1], F_DUPFD, 10);
    const int log_high = log >= 0 ? fcntl(log, F_DUPFD, 10) : -1;
    const int null = open("/dev/null", O_RDWR);
    for (int fd = 0; fd <= 2; ++fd) dup2(null >= 0 ? null : 0, fd);
    dup2(sock_high, 3);
    const int log_fd = log_high >= 0 ? dup2(log_high, 4) : -1;
    close_range(5, ~0U, 0);
    Supervisor(3, specs_, board, log_fd).Run();
  }
  close(sv[1]);
  if (log >= 0) close(log);
  fd_ = sv[0];
  supervisor_ = pid;
}

ProcessSupervisor::~ProcessSupervisor() {
  if (fd_ < 0) return;
  Message bye;
  bye.op = Message::kBye;
  send(fd_, &bye, sizeof bye, MSG_NOSIGNAL);
  close(fd_);
  fd_ = -1;
  // It ends every process first (a few seconds at most); then it is ours to reap.
  int status = 0;
  for (int i = 0; i < 3000 && waitpid(supervisor_, &status, WNOHANG) == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  if (waitpid(supervisor_, &status, WNOHANG) == 0) {
    kill(supervisor_, SIGKILL);
    waitpid(supervisor_, &status, 0);
  }
}

void ProcessSupervisor::Send(const Message& m) {
  if (send(fd_, &m, sizeof m, MSG_NOSIGNAL) != static_cast<ssize_t>(sizeof m))
    throw std::runtime_error(std::string("ros: the process supervisor is gone: ") + std::strerror(errno));
}

void ProcessSupervisor::Record(const Message& m) {
  if (m.op != Message::kExited || m.id < 0 || static_cast<std::size_t>(m.id) >= exits_.size()) return;
  exits_[static_cast<std::size_t>(m.id)] = static_cast<int>(m.value);
  unreported_.push_back({m.id, static_cast<int>(m.value)});
}

ProcessSupervisor::Message ProcessSupervisor::Receive(int expected_op, int id) {
  for (;;) {
    Message m;
    const ssize_t n = recv(fd_, &m, sizeof m, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n != static_cast<ssize_t>(sizeof m)) throw std::runtime_error("ros: the process supervisor is gone");
    if (m.op == expected_op && m.id == id) return m;
    Record(m);
  }
}

pid_t ProcessSupervisor::Start(int id) {
  Message m;
  m.op = Message::kStart;
  m.id = id;
  Send(m);
  const Message reply = Receive(Message::kStarted, id);
  if (reply.value <= 0)
    throw std::runtime_error("ros: cannot start " + specs_.at(static_cast<std::size_t>(id)).name + ": " +
                             std::strerror(static_cast<int>(-reply.value)));
  pids_[static_cast<std::size_t>(id)] = static_cast<pid_t>(reply.value);
  return pids_[static_cast<std::size_t>(id)];
}

ProcessExit ProcessSupervisor::Stop(int id, double grace_s) {
  Message m;
  m.op = Message::kStop;
  m.id = id;
  m.grace_s = grace_s;
  Send(m);
  Receive(Message::kStopped, id);
  // Its exit was sent before the reply.
  for (Message e; recv(fd_, &e, sizeof e, MSG_DONTWAIT) == static_cast<ssize_t>(sizeof e);) Record(e);
  const auto& exit = exits_.at(static_cast<std::size_t>(id));
  return {id, exit ? *exit : 0};
}

std::vector<ProcessExit> ProcessSupervisor::Poll() {
  for (;;) {
    Message m;
    const ssize_t n = recv(fd_, &m, sizeof m, MSG_DONTWAIT);
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
    if (n < 0 && errno == EINTR) continue;
    if (n != static_cast<ssize_t>(sizeof m)) throw std::runtime_error("ros: the process supervisor is gone");
    Record(m);
  }
  return std::exchange(unreported_, {});
}

}  // namespace enavi::ros
