// The executor's time sources (navstack/runtime/time_source.h): the emulated clock's dilated
// steady clock, and the stepped clock a ROS node sets from /clock. Waits are bounded polls (a
// bound against hangs), nothing asserts on durations.
#include "navstack/runtime/time_source.h"

#include <atomic>
#include <chrono>
#include <limits>
#include <stdexcept>
#include <thread>

#include <gtest/gtest.h>

#include "tests/unit/runtime/test_gate.h"

namespace enavi::navstack {
namespace {

using namespace std::chrono_literals;

TEST(DilatedSteadyClockTest, IsZeroUntilItsEpochThenWallTimeOverTheDilation) {
  DilatedSteadyClock clock(2.0);
  EXPECT_EQ(clock.Now(), 0.0);
  const auto epoch = std::chrono::steady_clock::now() - 4s;
  clock.SetEpoch(epoch);
  EXPECT_GE(clock.Now(), 2.0);
  EXPECT_LT(clock.Now(), 3.0);
  EXPECT_EQ(clock.WallOf(1.5), epoch + 3s);
  EXPECT_THROW(DilatedSteadyClock(0.0), std::invalid_argument);
  EXPECT_THROW(DilatedSteadyClock(std::numeric_limits<double>::infinity()), std::invalid_argument);
}

TEST(DilatedSteadyClockTest, WaitUntilReturnsOnceTheTimeHasCome) {
  DilatedSteadyClock clock(1.0);
  clock.SetEpoch(std::chrono::steady_clock::now());
  std::mutex m;
  std::condition_variable cv;
  std::unique_lock l(m);
  while (clock.Now() < 0.01) clock.WaitUntil(cv, l, 0.01);
  EXPECT_GE(clock.Now(), 0.01);
}

// A waiter on the stepped clock, in its own thread, waiting for `t`.
struct SteppedWaiter {
  SteppedWaiter(SteppedClock& clock, double t) : clock(clock) {
    clock.Listen(m, cv);
    thread = std::thread([this, t] {
      std::unique_lock l(m);
      while (this->clock.Now() < t) {
        ++wakeups;
        this->clock.WaitUntil(cv, l, t);
      }
      done = true;
    });
  }
  ~SteppedWaiter() {
    thread.join();
    clock.Unlisten(cv);
  }
  SteppedClock& clock;
  std::mutex m;
  std::condition_variable cv;
  std::atomic<int> wakeups{0};
  std::atomic<bool> done{false};
  std::thread thread;
};

TEST(SteppedClockTest, MovesOnlyForwardAndOnlyWhenSet) {
  SteppedClock clock;
  EXPECT_EQ(clock.Now(), 0.0);
  clock.Set(0.25);
  EXPECT_EQ(clock.Now(), 0.25);
  clock.Set(0.1);  // an older /clock message
  EXPECT_EQ(clock.Now(), 0.25);
}

TEST(SteppedClockTest, AWaiterWakesWhenAStepReachesItsTimeAndNotBefore) {
  SteppedClock clock;
  SteppedWaiter w(clock, 0.010);
  ASSERT_TRUE(Eventually([&] { return w.wakeups.load() == 1; }));
  for (int k = 1; k < 10; ++k) clock.Set(0.001 * k);  // 1 kHz steps short of 10 ms
  std::this_thread::sleep_for(20ms);
  EXPECT_FALSE(w.done.load());
  EXPECT_EQ(w.wakeups.load(), 1) << "steps before its time do not wake it";
  clock.Set(0.010);
  EXPECT_TRUE(Eventually([&] { return w.done.load(); }));
}

TEST(SteppedClockTest, NoWakeUpIsLostWhenStepsRaceTheWaiter) {
  // Many short waits against a clock stepped as fast as it can be: a lost wake-up would hang a
  // waiter (Eventually's bound), since nothing else wakes it.
  SteppedClock clock;
  std::atomic<bool> stop{false};
  std::thread stepper([&] {
    double t = 0;
    while (!stop.load()) clock.Set(t += 1e-4);
  });
  for (int i = 0; i < 200; ++i) {
    SteppedWaiter w(clock, clock.Now() + 5e-4);
    ASSERT_TRUE(Eventually([&] { return w.done.load(); })) << "wait " << i;
  }
  stop = true;
  stepper.join();
}

TEST(SteppedClockTest, WaitingOnAConditionVariableNeverListenedIsAnError) {
  SteppedClock clock;
  std::mutex m;
  std::condition_variable cv;
  std::unique_lock l(m);
  EXPECT_THROW(clock.WaitUntil(cv, l, 1.0), std::logic_error);
  clock.Set(2.0);
  clock.WaitUntil(cv, l, 1.0);  // already there: returns without waiting
}

}  // namespace
}  // namespace enavi::navstack
