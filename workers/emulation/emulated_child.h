#pragma once
// The navstack process of an emulated episode (EmulatedNavLink forks it, workers/sim/
// emulated_nav_link.h): the mapping it shares with the simulator besides the ShmChannel, and its
// main. Internal to enavi::episode.

#include <sys/types.h>

#include <atomic>
#include <cstdint>
#include <string>

#include "navstack/methods/method.h"
#include "navstack/runtime/cost_model.h"
#include "navstack/runtime/virtual_executor.h"
#include "workers/emulation/emulated_wire.h"

namespace enavi::emulation {

inline constexpr int kEventRing = 1024;

enum ChildState : std::int32_t { kStarting = 0, kReady = 1, kRunning = 2, kFailed = 3, kDone = 4 };

// The shared anonymous mapping between the simulator and the navstack process (besides the
// ShmChannel): control words, the stack's outputs, its accounting and its events.
struct LinkShared {
  std::atomic<std::int64_t> epoch_ns{0};  // CLOCK_MONOTONIC of sim time 0; 0 = not yet
  std::atomic<std::int32_t> child_state{kStarting};
  std::atomic<std::int32_t> stop{0};
  std::atomic<std::int32_t> deadline_workers{0};
  char error[1024] = {};       // written before child_state = kFailed
  char sched_note[1024] = {};  // written before child_state = kReady
  SeqSlot<ReferenceWire> reference;
  SeqSlot<StatsWire> stats;
  std::atomic<std::uint64_t> event_head{0};
  SeqSlot<EventWire> events[kEventRing];
};

/// What the navstack process gets from the simulator: pointers into the simulator's memory,
/// valid in the child because fork copied it.
struct ChildArgs {
  const navstack::MethodInfo* method = nullptr;  ///< builds the navigator in the child
  const navstack::MethodOptions* options = nullptr;
  const navstack::VehicleState* initial = nullptr;
  int threads = 1;
  navstack::SchedulingPolicy policy = navstack::SchedulingPolicy::kGlobalEdf;
  double dilation = 1.0;
  double speed = 1.0;  // board core speed / host core speed
  bool sched_deadline = true;
  std::int64_t server_period_ns = 2'000'000;
  navstack::WorkCountCostModel::Coefficients board_costs;  // the virtual clock's prices
  LinkShared* shared = nullptr;
  int channel_fd = -1;
  int go_fd = -1;
};

/// Copies `text` into a fixed buffer of `size` bytes, truncated and NUL-terminated.
void CopyText(char* dst, std::size_t size, const std::string& text);

/// After fork, in the child: dies with the simulator (PR_SET_PDEATHSIG), default signal
/// dispositions and an empty mask, stdout to /dev/null, only the channel (fd 3) and the start
/// pipe (fd 4) kept open; updates the two descriptors. _exit()s if the simulator is gone.
void PrepareChildProcess(pid_t parent, int* channel_fd, int* go_fd);

/// The navstack process's main: waits for the start byte, runs NavStack on a RealtimeExecutor
/// until the simulator says stop or dies; returns the exit code. Throws on failure (the caller
/// records the message in LinkShared::error).
int RunNavstackChild(const ChildArgs& args);

}  // namespace enavi::emulation
