#pragma once
// SIGINT/SIGTERM during an emulated episode (docs/design.md, "Time: two clocks"): while a
// ScopedTerminationSignals lives, the two signals are only recorded, so that the episode can stop
// what it started (a navstack process, a ROS stack, their cgroups) before the process dies as the
// signal asked. Installed only where nobody else handles the signal: a host process with its own
// shutdown keeps it.

namespace enavi::emulation {

/// The signal that arrived while handlers were installed (0: none).
int PendingTerminationSignal();

/// Installs the recording handlers (reference-counted across nested scopes). The destructor
/// restores the old dispositions; the last scope to go re-raises a recorded signal, after
/// `on_signal` printed what was cleaned up, so that the process ends the way it was told to.
class ScopedTerminationSignals {
 public:
  ScopedTerminationSignals();
  ~ScopedTerminationSignals();
  ScopedTerminationSignals(const ScopedTerminationSignals&) = delete;
  ScopedTerminationSignals& operator=(const ScopedTerminationSignals&) = delete;
};

}  // namespace enavi::emulation
