#include "workers/ros/stack_cpu.h"

#include <unistd.h>

#include <fstream>
#include <set>
#include <sstream>

#include "navstack/runtime/proc_stat.h"

namespace enavi::ros {
namespace {

std::vector<std::string> ReadCmdline(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/cmdline", std::ios::binary);
  std::vector<std::string> out;
  std::string arg;
  while (std::getline(in, arg, '\0')) out.push_back(arg);
  return out;
}

std::string Basename(const std::string& path) {
  const auto slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

bool IsInterpreter(const std::string& program) {
  return program.rfind("python", 0) == 0 || program == "bash" || program == "sh";
}

}  // namespace

std::string ProcessDisplayName(const std::vector<std::string>& cmdline) {
  for (const std::string& arg : cmdline)
    if (arg.rfind("__name:=", 0) == 0 && arg.size() > 8) return arg.substr(8);
  if (cmdline.empty()) return "?";
  const std::string program = Basename(cmdline[0]);
  // python3 /usr/bin/roslaunch ...: the script; bash -c '...': stays bash.
  if (IsInterpreter(program) && cmdline.size() > 1 && !cmdline[1].empty() && cmdline[1][0] != '-')
    return Basename(cmdline[1]);
  return program;
}

void StackCpuMonitor::Sample() {
  static const double tick = 1.0 / static_cast<double>(sysconf(_SC_CLK_TCK));
  std::set<pid_t> processes;
  for (pid_t tid : tasks_()) {
    const pid_t tgid = navstack::ThreadGroupOf(tid);
    if (tgid <= 0) continue;
    processes.insert(tgid);
    if (const auto t = navstack::ReadThreadCpu(tgid, tid)) {
      Seen& th = threads_[{tgid, tid}];
      th.name = t->comm;
      th.cpu_s = t->CpuSeconds();
    }
  }
  for (pid_t pid : processes) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
    std::string line;
    if (!std::getline(in, line)) continue;  // ended since
    const auto stat = navstack::ParseProcStatLine(line);
    if (!stat) continue;
    const std::string* utime = stat->Field(14);
    const std::string* stime = stat->Field(15);
    const std::string* start = stat->Field(22);
    if (!utime || !stime || !start) continue;
    Seen& s = seen_[{pid, std::stoull(*start)}];
    if (s.name.empty()) s.name = ProcessDisplayName(ReadCmdline(pid));
    s.cpu_s = static_cast<double>(std::stoull(*utime) + std::stoull(*stime)) * tick;
  }
}

std::map<std::string, double> StackCpuMonitor::ByName() const {
  std::map<std::string, double> out;
  for (const auto& [key, s] : seen_) out[s.name] += s.cpu_s;
  return out;
}

std::map<std::string, double> StackCpuMonitor::ByThread() const {
  std::map<pid_t, std::string> process_names;
  for (const auto& [key, s] : seen_) process_names[key.first] = s.name;
  std::map<std::string, double> out;
  for (const auto& [key, t] : threads_) {
    const auto p = process_names.find(key.first);
    out[(p == process_names.end() ? std::string("?") : p->second) + "/" + t.name] += t.cpu_s;
  }
  return out;
}

double StackCpuMonitor::Total() const {
  double total = 0;
  for (const auto& [key, s] : seen_) total += s.cpu_s;
  return total;
}

}  // namespace enavi::ros
