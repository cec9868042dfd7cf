#include "navstack/runtime/proc_stat.h"

#include <dirent.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace enavi::navstack {
namespace {

std::int64_t MonotonicNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

double TickSeconds() {
  static const double tick = 1.0 / static_cast<double>(sysconf(_SC_CLK_TCK));
  return tick;
}

std::string TaskDir(pid_t pid, pid_t tid) {
  return "/proc/" + std::to_string(pid) + "/task/" + std::to_string(tid);
}

}  // namespace

const std::string* ProcStatLine::Field(int index) const {
  const int i = index - 3;
  if (i < 0 || i >= static_cast<int>(fields.size())) return nullptr;
  return &fields[static_cast<std::size_t>(i)];
}

std::optional<ProcStatLine> ParseProcStatLine(const std::string& line) {
  const auto open = line.find('(');
  const auto close = line.rfind(')');
  if (open == std::string::npos || close == std::string::npos || close < open) return std::nullopt;
  ProcStatLine out;
  out.comm = line.substr(open + 1, close - open - 1);
  std::istringstream rest(line.substr(close + 1));
  std::string field;
  while (rest >> field) out.fields.push_back(field);
  return out;
}

std::optional<std::uint64_t> ProcessStartTime(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!in || !std::getline(in, line)) return std::nullopt;
  const auto parsed = ParseProcStatLine(line);
  if (!parsed) return std::nullopt;
  const std::string* state = parsed->Field(3);
  const std::string* start = parsed->Field(22);
  if (state == nullptr || start == nullptr || *state == "Z" || *state == "X") return std::nullopt;
  return std::stoull(*start);
}

pid_t ThreadGroupOf(pid_t tid) {
  std::ifstream in("/proc/" + std::to_string(tid) + "/status");
  std::string key;
  while (in >> key) {
    if (key == "Tgid:") {
      long v = 0;
      in >> v;
      return static_cast<pid_t>(v);
    }
    std::string rest;
    std::getline(in, rest);
  }
  return 0;
}

double ThreadCpuTimes::CpuSeconds() const {
  if (sum_exec_ns >= 0) return static_cast<double>(sum_exec_ns) * 1e-9;
  return static_cast<double>(utime_ticks + stime_ticks) * TickSeconds();
}

std::optional<ThreadCpuTimes> ReadThreadCpu(pid_t pid, pid_t tid) {
  const std::string dir = TaskDir(pid, tid);
  std::ifstream stat_file(dir + "/stat");
  if (!stat_file) return std::nullopt;
  std::string line;
  if (!std::getline(stat_file, line)) return std::nullopt;  // thread exited while reading

  ThreadCpuTimes t;
  t.tid = tid;
  t.sampled_ns = MonotonicNs();
  const auto parsed = ParseProcStatLine(line);
  if (!parsed) {
    throw std::runtime_error("ReadThreadCpu: cannot parse " + dir + "/stat: '" + line + "'");
  }
  t.comm = parsed->comm;
  // Field 14 utime, field 15 stime.
  const std::string* utime = parsed->Field(14);
  const std::string* stime = parsed->Field(15);
  if (utime == nullptr || stime == nullptr) {
    throw std::runtime_error("ReadThreadCpu: " + dir + "/stat has fewer than 15 fields");
  }
  t.utime_ticks = std::stoull(*utime);
  t.stime_ticks = std::stoull(*stime);
  // schedstat: "sum_exec_runtime_ns run_delay_ns timeslices" (CONFIG_SCHED_INFO).
  std::ifstream schedstat(dir + "/schedstat");
  long long exec_ns = -1, delay_ns = -1;
  if (schedstat >> exec_ns >> delay_ns) {
    t.sum_exec_ns = exec_ns;
    t.run_delay_ns = delay_ns;
  }
  return t;
}

std::vector<pid_t> ListThreads(pid_t pid) {
  std::vector<pid_t> tids;
  const std::string dir = "/proc/" + std::to_string(pid) + "/task";
  DIR* d = opendir(dir.c_str());
  if (d == nullptr) return tids;
  while (dirent* e = readdir(d)) {
    if (e->d_name[0] < '0' || e->d_name[0] > '9') continue;
    tids.push_back(static_cast<pid_t>(std::stol(e->d_name)));
  }
  closedir(d);
  std::sort(tids.begin(), tids.end());
  return tids;
}

double CpuPercent(const ThreadCpuTimes& a, const ThreadCpuTimes& b) {
  const double wall = static_cast<double>(b.sampled_ns - a.sampled_ns) * 1e-9;
  if (wall <= 0.0) return 0.0;
  double cpu = 0.0;
  if (a.sum_exec_ns >= 0 && b.sum_exec_ns >= 0) {
    cpu = static_cast<double>(b.sum_exec_ns - a.sum_exec_ns) * 1e-9;
  } else {
    cpu = static_cast<double>((b.utime_ticks + b.stime_ticks) -
                              (a.utime_ticks + a.stime_ticks)) * TickSeconds();
  }
  return 100.0 * cpu / wall;
}

double WaitPercent(const ThreadCpuTimes& a, const ThreadCpuTimes& b) {
  const double wall = static_cast<double>(b.sampled_ns - a.sampled_ns) * 1e-9;
  if (a.run_delay_ns < 0 || b.run_delay_ns < 0) return -1.0;
  if (wall <= 0.0) return 0.0;
  return 100.0 * static_cast<double>(b.run_delay_ns - a.run_delay_ns) * 1e-9 / wall;
}

ThreadCpuMonitor::ThreadCpuMonitor(pid_t pid) : pid_(pid) {}

std::vector<ThreadUtilisation> ThreadCpuMonitor::Sample() {
  std::vector<ThreadCpuTimes> current;
  for (pid_t tid : ListThreads(pid_)) {
    if (auto t = ReadThreadCpu(pid_, tid)) current.push_back(std::move(*t));
  }
  std::vector<ThreadUtilisation> out;
  total_percent_ = 0.0;
  // Both lists are sorted by tid: merge.
  auto prev = previous_.begin();
  for (const ThreadCpuTimes& cur : current) {
    while (prev != previous_.end() && prev->tid < cur.tid) ++prev;
    if (prev == previous_.end() || prev->tid != cur.tid) continue;
    // A tid reused by a new thread shows less CPU time than before: baseline it afresh.
    if (cur.CpuSeconds() < prev->CpuSeconds()) continue;
    const double pct = CpuPercent(*prev, cur);
    out.push_back(ThreadUtilisation{cur.tid, cur.comm, pct, WaitPercent(*prev, cur)});
    total_percent_ += pct;
  }
  previous_ = std::move(current);
  return out;
}

std::string DescribeWaitStatus(int wstatus) {
  if (WIFEXITED(wstatus)) return "exit code " + std::to_string(WEXITSTATUS(wstatus));
  if (WIFSIGNALED(wstatus)) {
    const char* name = strsignal(WTERMSIG(wstatus));
    return "killed by signal " + std::to_string(WTERMSIG(wstatus)) + " (" + (name ? name : "?") + ")";
  }
  return "status " + std::to_string(wstatus);
}

}  // namespace enavi::navstack
