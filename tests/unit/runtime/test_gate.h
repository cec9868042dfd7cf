#pragma once
// Helpers of the executor tests that run real threads: a latch the test opens, and a bounded
// poll (a bound against hangs, not a timing assertion).

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

namespace enavi::navstack {

class Gate {
 public:
  void Open() {
    std::lock_guard l(m_);
    open_ = true;
    cv_.notify_all();
  }
  void Wait() {
    std::unique_lock l(m_);
    cv_.wait(l, [this] { return open_; });
  }

 private:
  std::mutex m_;
  std::condition_variable cv_;
  bool open_ = false;
};

/// Polls `done` every millisecond for up to 10 s.
template <typename F>
bool Eventually(F done) {
  for (int i = 0; i < 10'000; ++i) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return done();
}

}  // namespace enavi::navstack
