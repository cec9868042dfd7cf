#include "navstack/runtime/time_source.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace enavi::navstack {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

// ---------------------------------------------------------------------------------------------
// DilatedSteadyClock

DilatedSteadyClock::DilatedSteadyClock(double dilation) : dilation_(dilation) {
  if (!(dilation > 0) || !std::isfinite(dilation))
    throw std::invalid_argument("time source: dilation must be > 0, got " + std::to_string(dilation));
}

void DilatedSteadyClock::SetEpoch(Clock::time_point epoch) {
  // 0 means "not set": an epoch at the steady clock's own zero moves by a nanosecond.
  epoch_ns_.store(std::max<std::int64_t>(1, std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                epoch.time_since_epoch()).count()));
}

Clock::time_point DilatedSteadyClock::WallOf(double t) const {
  return Clock::time_point(std::chrono::nanoseconds(epoch_ns_.load())) +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(t * dilation_));
}

double DilatedSteadyClock::Now() const {
  const std::int64_t epoch = epoch_ns_.load();
  if (epoch == 0) return 0.0;
  const std::int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
  return 1e-9 * static_cast<double>(now - epoch) / dilation_;
}

void DilatedSteadyClock::WaitUntil(std::condition_variable& cv, std::unique_lock<std::mutex>& lock, double t) {
  if (std::isinf(t) || epoch_ns_.load() == 0) {
    cv.wait(lock);
  } else {
    cv.wait_until(lock, WallOf(t));
  }
}

// ---------------------------------------------------------------------------------------------
// SteppedClock

void SteppedClock::Set(double t) {
  // Woken outside m_: a waiter holds its own mutex while it registers under m_, so taking a
  // listener's mutex under m_ could deadlock. Unlisten() waits until such a round is over.
  std::vector<Listener> due;
  {
    std::lock_guard g(m_);
    if (!(t > now_.load())) return;
    now_.store(t);
    for (Listener& l : listeners_) {
      if (l.wake_at <= t) {
        due.push_back(l);
        l.wake_at = kInf;  // its waiters re-register the time they still wait for
      }
    }
    if (due.empty()) return;
    ++notifying_;
  }
  for (const Listener& l : due) {
    // Taking the waiter's mutex orders this notify after its wait began (it registered holding
    // that mutex, and holds it until cv.wait releases it): no wake-up is lost.
    { std::lock_guard w(*l.mutex); }
    l.cv->notify_all();
  }
  {
    std::lock_guard g(m_);
    --notifying_;
  }
  idle_.notify_all();
}

void SteppedClock::WaitUntil(std::condition_variable& cv, std::unique_lock<std::mutex>& lock, double t) {
  {
    std::lock_guard g(m_);
    if (now_.load() >= t) return;
    const auto it = std::find_if(listeners_.begin(), listeners_.end(), [&](const Listener& l) { return l.cv == &cv; });
    if (it == listeners_.end()) throw std::logic_error("SteppedClock: WaitUntil on a condition variable never Listen()ed");
    it->wake_at = std::min(it->wake_at, t);
  }
  cv.wait(lock);
}

void SteppedClock::Listen(std::mutex& mutex, std::condition_variable& cv) {
  std::lock_guard g(m_);
  listeners_.push_back({&mutex, &cv, kInf});
}

void SteppedClock::Unlisten(std::condition_variable& cv) {
  std::unique_lock g(m_);
  idle_.wait(g, [this] { return notifying_ == 0; });
  listeners_.erase(std::remove_if(listeners_.begin(), listeners_.end(), [&](const Listener& l) { return l.cv == &cv; }),
                   listeners_.end());
}

}  // namespace enavi::navstack
