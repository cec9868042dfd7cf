#pragma once
// Per-thread CPU utilisation read from /proc, the paper's psutil figure (docs/design.md, "Time: two clocks"
// and 8): percent of ONE core over an interval, 100 % = one core busy the whole interval,
// so a process can exceed 100 % on a multi-core machine (psutil Process.cpu_percent).

#include <sys/types.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace enavi::navstack {

/// Cumulative CPU time of one thread at one instant.
struct ThreadCpuTimes {
  pid_t tid = 0;
  std::string comm;           ///< thread name (/proc/.../comm, as set by pthread_setname_np)
  std::uint64_t utime_ticks = 0;
  std::uint64_t stime_ticks = 0;
  /// Nanoseconds on CPU from /proc/.../schedstat (sum_exec_runtime); -1 when the kernel has no
  /// schedstat file, then the tick counts (1 / sysconf(_SC_CLK_TCK) s) are all there is.
  std::int64_t sum_exec_ns = -1;
  /// Nanoseconds spent runnable but waiting for a CPU (schedstat run_delay); -1 if unknown.
  /// A starved thread (busy host) shows here, not in its CPU time.
  std::int64_t run_delay_ns = -1;
  std::int64_t sampled_ns = 0;  ///< CLOCK_MONOTONIC time of the sample

  /// CPU time in seconds at the best resolution available.
  double CpuSeconds() const;
};

/// One line of /proc/<pid>/stat or /proc/<pid>/task/<tid>/stat (proc(5)): the name (field 2)
/// and the fields after it as text.
struct ProcStatLine {
  std::string comm;
  std::vector<std::string> fields;  ///< fields[0] is field 3 (state), fields[i] is field i + 3

  /// Field `index` (proc(5) numbering, >= 3); nullptr when the line is shorter.
  const std::string* Field(int index) const;
};

/// Splits a stat line. The name is in parentheses and may itself contain spaces and ')', so it
/// ends at the last ')'. nullopt when the line has no parenthesised name.
std::optional<ProcStatLine> ParseProcStatLine(const std::string& line);

/// Start time of a live process (/proc/<pid>/stat field 22, clock ticks since boot): with the
/// pid it names one process across pid reuse. nullopt when the process is gone or a zombie
/// (it will never run again).
std::optional<std::uint64_t> ProcessStartTime(pid_t pid);

/// The process a thread belongs to (Tgid in /proc/<tid>/status); 0 when the thread is gone.
pid_t ThreadGroupOf(pid_t tid);

/// Reads /proc/<pid>/task/<tid>/{stat,schedstat}. nullopt if the thread does not exist (it
/// exited). Throws std::runtime_error if the stat line cannot be parsed (a kernel contract).
std::optional<ThreadCpuTimes> ReadThreadCpu(pid_t pid, pid_t tid);

/// How a process ended, from its waitpid status: "exit code 3", "killed by signal 11
/// (Segmentation fault)".
std::string DescribeWaitStatus(int wstatus);

/// Thread ids of a process (/proc/<pid>/task), ascending; empty if the process is gone.
std::vector<pid_t> ListThreads(pid_t pid);

/// Utilisation between two samples of the same thread, percent of one core:
/// 100 x (cpu(b) - cpu(a)) / (sampled(b) - sampled(a)). Uses schedstat nanoseconds when both
/// samples have them, else clock ticks. 0 when no time elapsed.
double CpuPercent(const ThreadCpuTimes& a, const ThreadCpuTimes& b);

/// Percent of the interval the thread was runnable but not running (schedstat run_delay);
/// -1 when a sample lacks schedstat. CPU percent + wait percent ~ 100 for a thread that never
/// sleeps, whatever the host load.
double WaitPercent(const ThreadCpuTimes& a, const ThreadCpuTimes& b);

/// Utilisation of one thread over an interval.
struct ThreadUtilisation {
  pid_t tid = 0;
  std::string comm;
  double percent = 0.0;       ///< of one core
  double wait_percent = -1.0; ///< runnable but waiting for a CPU, -1 if unknown
};

/// Samples all threads of a process and reports each thread's utilisation since the previous
/// Sample() (the first call only sets the baseline, like psutil's first cpu_percent()).
/// A thread that appeared since the previous sample gets its baseline then and is reported from
/// the next Sample() on; threads that exited drop out.
class ThreadCpuMonitor {
 public:
  explicit ThreadCpuMonitor(pid_t pid);
  std::vector<ThreadUtilisation> Sample();
  /// Sum of the per-thread figures of the last Sample(): the process's percent of one core.
  double TotalPercent() const { return total_percent_; }

 private:
  pid_t pid_;
  std::vector<ThreadCpuTimes> previous_;
  double total_percent_ = 0.0;
};

}  // namespace enavi::navstack
