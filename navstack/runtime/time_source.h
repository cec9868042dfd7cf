#pragma once
// Where a RealtimeExecutor's sim time comes from (docs/design.md, "Time: two clocks"). The
// emulated clock's navstack process reads the steady clock slowed down by the dilation
// (DilatedSteadyClock); a ROS node reads ROS time, which moves only when /clock says so
// (SteppedClock, set by the node's /clock subscriber). The executor asks what time it is and
// waits until a time or a wake-up of its own; the schedule is the same on both.
//
// Plain C++17 (no C++20 library features): a ROS 1 node's translation units include it.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <vector>

namespace enavi::navstack {

class TimeSource {
 public:
  virtual ~TimeSource() = default;
  /// Sim time now, seconds.
  virtual double Now() const = 0;
  /// Waits on `cv` (the caller holds `lock`; it is released while waiting) until Now() >= t, a
  /// notify of `cv`, or spuriously: the caller checks again. t = +infinity waits for a notify.
  /// On a source that moves in steps, `cv` must have been Listen()ed with `lock`'s mutex.
  virtual void WaitUntil(std::condition_variable& cv, std::unique_lock<std::mutex>& lock, double t) = 0;
  /// Waiters on `cv` under `mutex` are to be woken when the source steps to their time. A source
  /// that follows the steady clock needs no help (the default: nothing to do).
  virtual void Listen(std::mutex& /*mutex*/, std::condition_variable& /*cv*/) {}
  /// Forgets `cv`; returns once no step is waking it. Call before `cv` or its mutex goes away,
  /// without holding that mutex.
  virtual void Unlisten(std::condition_variable& /*cv*/) {}
};

/// Sim time = (steady clock - epoch) / dilation: the emulated clock (k >= 1 slows the world down).
class DilatedSteadyClock final : public TimeSource {
 public:
  /// @throws std::invalid_argument for a dilation that is not finite and > 0.
  explicit DilatedSteadyClock(double dilation);
  /// Sim time 0 (may lie a little in the future). Now() is 0 until it is set.
  void SetEpoch(std::chrono::steady_clock::time_point epoch);
  double dilation() const { return dilation_; }
  /// The steady-clock instant of sim time t (the epoch must be set).
  std::chrono::steady_clock::time_point WallOf(double t) const;

  double Now() const override;
  void WaitUntil(std::condition_variable& cv, std::unique_lock<std::mutex>& lock, double t) override;

 private:
  const double dilation_;
  std::atomic<std::int64_t> epoch_ns_{0};  ///< steady-clock nanoseconds; 0: not set
};

/// A clock that moves only when told: ROS time under /use_sim_time, set from each /clock message.
/// It never runs backwards (an earlier time is ignored) and wakes each listener whose waiter's
/// time a step reaches, once: a 1 kHz /clock does not wake a thread that waits for 10 ms.
class SteppedClock final : public TimeSource {
 public:
  /// Moves the clock to t, waking the waiters it reaches (from the caller's thread).
  void Set(double t);

  double Now() const override { return now_.load(); }
  /// @throws std::logic_error when `cv` was not Listen()ed.
  void WaitUntil(std::condition_variable& cv, std::unique_lock<std::mutex>& lock, double t) override;
  void Listen(std::mutex& mutex, std::condition_variable& cv) override;
  void Unlisten(std::condition_variable& cv) override;

 private:
  struct Listener {
    std::mutex* mutex;
    std::condition_variable* cv;
    double wake_at;  ///< the earliest time a waiter on cv waits for; +inf: none
  };
  std::mutex m_;  // listeners_, notifying_; never held while a listener's mutex is taken
  std::condition_variable idle_;
  std::vector<Listener> listeners_;
  int notifying_ = 0;  // Set()s waking listeners outside m_
  std::atomic<double> now_{0.0};
};

}  // namespace enavi::navstack
