#include "workers/worker/process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <map>
#include <stdexcept>
#include <thread>
#include <utility>

extern char** environ;

namespace enavi::worker {
namespace {

namespace fs = std::filesystem;

std::string ResolveProgram(const std::string& name) {
  if (name.find('/') != std::string::npos) {
    if (access(name.c_str(), X_OK) != 0) {
      throw std::runtime_error("cannot execute '" + name + "': " + std::strerror(errno));
    }
    return name;
  }
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::string candidate = dirs.substr(start, end - start) + "/" + name;
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
    start = end + 1;
  }
  throw std::runtime_error("cannot execute '" + name + "': not found in PATH");
}

int OpenOutput(const fs::path& path) {
  const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw std::runtime_error("cannot open '" + path.string() + "': " + std::strerror(errno));
  }
  return fd;
}

// After fork, only async-signal-safe calls until exec: everything is prepared beforehand.
[[noreturn]] void ChildFail(const char* what) {
  const int err = errno;
  const char* msg = std::strerror(err);  // glibc's table lookup: no allocation for known errnos
  (void)!write(STDERR_FILENO, "enavi: child setup failed: ", 27);
  (void)!write(STDERR_FILENO, what, std::strlen(what));
  (void)!write(STDERR_FILENO, ": ", 2);
  (void)!write(STDERR_FILENO, msg, std::strlen(msg));
  (void)!write(STDERR_FILENO, "\n", 1);
  _exit(127);
}

}  // namespace

std::string ExitStatus::Describe() const {
  if (exited) return "exit code " + std::to_string(code);
  const char* name = strsignal(signal);
  return "killed by signal " + std::to_string(signal) + " (" + (name ? name : "?") + ")";
}

ChildProcess ChildProcess::Spawn(const SpawnOptions& options) {
  if (options.argv.empty()) throw std::invalid_argument("spawn: empty command");
  const std::string program = ResolveProgram(options.argv.front());

  // Environment: environ with the overrides applied.
  std::map<std::string, std::string> env;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string kv(*e);
    env[kv.substr(0, kv.find('='))] = kv;
  }
  for (const auto& kv : options.env) env[kv.substr(0, kv.find('='))] = kv;
  std::vector<std::string> env_strings;
  for (auto& [k, v] : env) env_strings.push_back(v);
  std::vector<char*> envp;
  for (auto& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::vector<std::string> args = options.argv;
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  const int out_fd = options.stdout_file.empty() ? -1 : OpenOutput(options.stdout_file);
  // stdout and stderr into one file share one open file description (one offset).
  const int err_fd = options.stderr_file.empty()           ? -1
                     : options.stderr_file == options.stdout_file ? fcntl(out_fd, F_DUPFD_CLOEXEC, 0)
                                                                  : OpenOutput(options.stderr_file);
  const int null_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
  const std::string cwd = options.cwd.string();
  const pid_t parent = getpid();

  const pid_t pid = fork();
  if (pid < 0) {
    const int err = errno;
    for (int fd : {out_fd, err_fd, null_fd}) if (fd >= 0) close(fd);
    throw std::runtime_error(std::string("fork: ") + std::strerror(err));
  }
  if (pid == 0) {
    // Own process group: a timeout kills the episode and anything it started.
    setpgid(0, 0);
    if (options.die_with_parent) {
      if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0) ChildFail("prctl");
      if (getppid() != parent) _exit(127);  // the parent died before prctl took effect
    }
    // The worker blocks SIGTERM/SIGINT for its signal thread; the episode must not inherit that.
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    signal(SIGPIPE, SIG_DFL);
    if (kAddressSpaceLimitApplies && options.memory_limit_bytes > 0) {
      const rlimit lim{static_cast<rlim_t>(options.memory_limit_bytes),
                       static_cast<rlim_t>(options.memory_limit_bytes)};
      if (setrlimit(RLIMIT_AS, &lim) != 0) ChildFail("setrlimit(RLIMIT_AS)");
    }
    if (options.cpu_limit_s > 0) {
      // Soft limit: SIGXCPU; hard limit a little later: SIGKILL.
      const rlimit lim{static_cast<rlim_t>(options.cpu_limit_s),
                       static_cast<rlim_t>(options.cpu_limit_s + 5)};
      if (setrlimit(RLIMIT_CPU, &lim) != 0) ChildFail("setrlimit(RLIMIT_CPU)");
    }
    if (null_fd >= 0 && dup2(null_fd, STDIN_FILENO) < 0) ChildFail("dup2(stdin)");
    if (out_fd >= 0 && dup2(out_fd, STDOUT_FILENO) < 0) ChildFail("dup2(stdout)");
    if (err_fd >= 0 && dup2(err_fd, STDERR_FILENO) < 0) ChildFail("dup2(stderr)");
    if (!cwd.empty() && chdir(cwd.c_str()) != 0) ChildFail("chdir");
    // Nothing else of the parent's (DDS sockets, the database) leaks into the episode.
    close_range(3, ~0U, 0);
    execve(program.c_str(), argv.data(), envp.data());
    ChildFail("execve");
  }
  // Both sides set the group (the classic race): a signal sent right after Spawn returns must
  // already reach the child's group.
  setpgid(pid, pid);
  for (int fd : {out_fd, err_fd, null_fd}) if (fd >= 0) close(fd);
  ChildProcess child;
  child.pid_ = pid;
  return child;
}

ChildProcess::~ChildProcess() {
  if (running()) {
    Signal(SIGKILL);
    Wait(std::chrono::milliseconds::max());
  }
}

ChildProcess::ChildProcess(ChildProcess&& other) noexcept
    : pid_(std::exchange(other.pid_, -1)), status_(std::exchange(other.status_, std::nullopt)) {}

ChildProcess& ChildProcess::operator=(ChildProcess&& other) noexcept {
  if (this != &other) {
    if (running()) {
      Signal(SIGKILL);
      Wait(std::chrono::milliseconds::max());
    }
    pid_ = std::exchange(other.pid_, -1);
    status_ = std::exchange(other.status_, std::nullopt);
  }
  return *this;
}

std::optional<ExitStatus> ChildProcess::Poll() {
  if (status_ || pid_ <= 0) return status_;
  // Look without reaping first: while the child is a zombie its pid (and so its process group
  // id) cannot be reused, so killing what it left in its group cannot hit a stranger.
  siginfo_t info{};
  if (waitid(P_PID, static_cast<id_t>(pid_), &info, WEXITED | WNOHANG | WNOWAIT) != 0) {
    if (errno == ECHILD) status_ = ExitStatus{false, 0, 0};  // reaped elsewhere
    return status_;
  }
  if (info.si_pid != pid_) return std::nullopt;  // still running
  kill(-pid_, SIGKILL);
  int wstatus = 0;
  waitpid(pid_, &wstatus, 0);
  ExitStatus s;
  if (WIFEXITED(wstatus)) {
    s.exited = true;
    s.code = WEXITSTATUS(wstatus);
  } else if (WIFSIGNALED(wstatus)) {
    s.signal = WTERMSIG(wstatus);
  }
  status_ = s;
  return status_;
}

std::optional<ExitStatus> ChildProcess::Wait(std::chrono::milliseconds timeout) {
  const auto deadline = timeout == std::chrono::milliseconds::max()
                            ? std::chrono::steady_clock::time_point::max()
                            : std::chrono::steady_clock::now() + timeout;
  auto pause = std::chrono::milliseconds(1);
  while (true) {
    if (auto s = Poll()) return s;
    if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(pause);
    pause = std::min(pause * 2, std::chrono::milliseconds(20));
  }
}

void ChildProcess::Signal(int signal) {
  if (!running()) return;
  // The group, or the child alone if it has already exec'd into something that left the group.
  if (kill(-pid_, signal) != 0) kill(pid_, signal);
}

ExitStatus ChildProcess::Terminate(std::chrono::milliseconds grace) {
  Signal(SIGTERM);
  if (auto s = Wait(grace)) return *s;
  Signal(SIGKILL);
  return *Wait(std::chrono::milliseconds::max());
}

std::filesystem::path SelfExecutable() { return fs::read_symlink("/proc/self/exe"); }

std::vector<std::string> SplitCommand(const std::string& command) {
  std::vector<std::string> out;
  std::string current;
  bool in_word = false;
  char quote = 0;
  for (char c : command) {
    if (quote != 0) {
      if (c == quote) {
        quote = 0;
      } else {
        current += c;
      }
    } else if (c == '\'' || c == '"') {
      quote = c;
      in_word = true;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      if (in_word) out.push_back(std::move(current));
      current.clear();
      in_word = false;
    } else {
      current += c;
      in_word = true;
    }
  }
  if (quote != 0) throw std::invalid_argument("command '" + command + "': unterminated quote");
  if (in_word) out.push_back(std::move(current));
  if (out.empty()) throw std::invalid_argument("command: empty");
  return out;
}

}  // namespace enavi::worker
