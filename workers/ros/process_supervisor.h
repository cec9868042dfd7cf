#pragma once
// The processes of one ROS episode (docs/ros.md, "Nothing left behind"): the private master, the
// user's stack and the bag recorder, started and ended by a supervisor process.
//
// Why a separate process: the simulator may be killed (a worker's episode child dies with its
// worker), and nothing it started may outlive it. The supervisor is forked from the simulator
// before any ROS thread exists; it sits outside the board's cgroups in a session of its own, is
// the subreaper of everything it starts (a node that double-forks is still its descendant), and
// watches the socket to the simulator: when the simulator goes away without a goodbye, the
// supervisor closes the bag (SIGINT), kills the stack (its process groups, then every task left
// in the board's cgroups), stops the master, removes the episode's cgroups and exits. The master
// and the recorder die with the supervisor (PR_SET_PDEATHSIG) should it be killed itself.

#include <signal.h>
#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

namespace enavi::emulation {
class EpisodeCgroup;
}

namespace enavi::ros {

/// A process the supervisor may start, by its index in the list it was given.
struct ProcessSpec {
  std::string name;               ///< for messages: master, stack, rosbag
  std::vector<std::string> argv;  ///< argv[0] is looked up in the environment's PATH
  std::vector<std::string> env;   ///< the complete environment, "NAME=value"
  std::string log_file;           ///< stdout and stderr (appended)
  bool in_board = false;          ///< runs inside the board's cgroups (the stack: every process it starts too)
  int stop_signal = SIGINT;       ///< what Stop() sends first (roslaunch and rosbag shut down cleanly on SIGINT)
  int death_signal = SIGKILL;     ///< sent to it when the supervisor dies (the recorder: SIGINT, to close its bag)
};

/// How a process ended (a waitpid status), and when it was seen.
struct ProcessExit {
  int id = -1;
  int status = 0;
};

class ProcessSupervisor {
 public:
  /// Forks the supervisor. `board` (may be null when no spec is in_board) is the episode's group
  /// the in_board processes start inside; the supervisor's copy of it removes the groups if the
  /// simulator dies. Throws std::runtime_error when the fork fails.
  ProcessSupervisor(std::vector<ProcessSpec> specs, emulation::EpisodeCgroup* board, std::string supervisor_log);
  /// Stops every process still running (in reverse order) and lets the supervisor exit.
  ~ProcessSupervisor();
  ProcessSupervisor(const ProcessSupervisor&) = delete;
  ProcessSupervisor& operator=(const ProcessSupervisor&) = delete;

  /// Starts process `id`; returns its pid. Throws std::runtime_error when it cannot be started
  /// (its log file then says why: a missing program exits with code 127).
  pid_t Start(int id);
  /// Sends the stop signal to the process's group, waits up to `grace_s` wall seconds, then
  /// SIGKILLs the group (and, for in_board, every task left in the board's cgroups). Returns
  /// how it ended; an exit already seen is returned as it was.
  ProcessExit Stop(int id, double grace_s);
  /// Exits seen since the last call, without blocking. Throws std::runtime_error when the
  /// supervisor itself is gone.
  std::vector<ProcessExit> Poll();
  /// The pid of process `id` (0 before Start).
  pid_t pid(int id) const { return pids_.at(static_cast<std::size_t>(id)); }
  /// The supervisor's own pid.
  pid_t supervisor_pid() const { return supervisor_; }

  struct Message;  ///< the wire between the two processes (process_supervisor.cc)

 private:
  void Send(const Message& m);
  Message Receive(int expected_op, int id);
  void Record(const Message& m);

  std::vector<ProcessSpec> specs_;
  std::vector<pid_t> pids_;
  std::vector<std::optional<int>> exits_;
  std::vector<ProcessExit> unreported_;
  int fd_ = -1;
  pid_t supervisor_ = -1;
};

}  // namespace enavi::ros
