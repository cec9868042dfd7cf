#pragma once
// Where a ROS stack's CPU goes (docs/ros.md, "What a ROS episode records"): every process inside
// the board's cgroups, its CPU time from /proc (utime + stime of the whole process, threads that
// already ended included), grouped by ROS node name (the __name:= roslaunch gives each node) or,
// for a process that is no node, by its program (roslaunch, a shell). The paper's figure is the
// psutil CPU percent of the planner's process: this is the same counter, per process.

#include <sys/types.h>

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace enavi::ros {

/// A process's name as the results show it: the value of a `__name:=` argument, else its
/// program's file name (for an interpreter, the script's: python3 /usr/bin/roslaunch is
/// roslaunch). `cmdline` is /proc/<pid>/cmdline split at its NULs.
std::string ProcessDisplayName(const std::vector<std::string>& cmdline);

class StackCpuMonitor {
 public:
  /// `tasks` lists the thread ids inside the board's groups (EpisodeCgroup::Tasks).
  explicit StackCpuMonitor(std::function<std::vector<pid_t>()> tasks) : tasks_(std::move(tasks)) {}

  /// Reads every process with a thread inside; a process keeps its last reading after it ends.
  void Sample();
  /// Host CPU seconds by display name (processes of the same name summed), since they started.
  std::map<std::string, double> ByName() const;
  /// Host CPU seconds by thread, "process/thread" (the thread's name, pthread_setname_np),
  /// threads of the same name summed: where inside a node the CPU goes.
  std::map<std::string, double> ByThread() const;
  /// Host CPU seconds of every process seen.
  double Total() const;
  std::size_t processes() const { return seen_.size(); }

 private:
  struct Seen {
    std::string name;
    double cpu_s = 0;
  };
  std::function<std::vector<pid_t>()> tasks_;
  std::map<std::pair<pid_t, unsigned long long>, Seen> seen_;  // (pid, start time) -> last reading
  std::map<std::pair<pid_t, pid_t>, Seen> threads_;             // (pid, tid) -> last reading
};

}  // namespace enavi::ros
