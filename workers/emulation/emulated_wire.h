#pragma once
// What crosses the process boundary of an emulated episode besides frames and odometry (those
// use emulation::ShmChannel): the navigation stack's outputs as plain data in shared memory.
//
// The reference is sent as the stack's trajectories themselves (B-spline control points, knot
// span, start time and initial yaw), not as samples, so the simulator rebuilds the very
// Trajectory the stack made and its controller samples it at 200 Hz exactly as on the virtual
// clock; plus the hold reference (no plan yet, emergency stop, fail-safe) and the previous
// trajectory for the hand-over before a new plan's start time (NavStack::Reference's rule).

#include <atomic>
#include <cstdint>
#include <cstring>
#include <memory>

#include "navstack/common/state.h"
#include "navstack/methods/reference_tracker.h"
#include "navstack/planning/planner_options.h"
#include "navstack/planning/trajectory.h"
#include "navstack/runtime/executor.h"
#include "navstack/runtime/realtime_executor.h"

namespace enavi::emulation {

struct SampleWire {
  double p[3] = {0, 0, 0}, v[3] = {0, 0, 0}, a[3] = {0, 0, 0}, j[3] = {0, 0, 0};
  double yaw = 0, yaw_rate = 0;
};
SampleWire ToWire(const navstack::TrajectorySample& s);
navstack::TrajectorySample FromWire(const SampleWire& w);

/// A Trajectory: uniform cubic B-spline control points, knot span, start time, initial yaw and
/// yaw rate.
struct TrajectoryWire {
  static constexpr int kMaxControlPoints = 1024;
  std::int32_t count = 0;  ///< control points; 0 = no trajectory
  double t0 = 0, dt = 0, yaw0 = 0, yaw_rate0 = 0;
  double q[kMaxControlPoints][3];
};

/// Serialises `traj` into `out`. The spline is exact; the initial yaw is recovered as
/// Sample(t0).yaw, which equals the planner's yaw0 up to one rounding of the angle wrap, so the
/// rebuilt yaw profile agrees to ~1e-15 rad. Throws std::length_error if the spline has more
/// than kMaxControlPoints control points.
void ToWire(const navstack::Trajectory& traj, TrajectoryWire* out);
/// Rebuilds the trajectory with the planner options the stack uses (yaw rule); null if count
/// is 0. Throws std::invalid_argument for a malformed message (count out of range, dt <= 0).
std::shared_ptr<const navstack::Trajectory> FromWire(const TrajectoryWire& w,
                                                     const navstack::PlannerOptions& options);

/// The stack's outputs as of its last commit.
struct ReferenceWire {
  enum Mode : std::int32_t { kHold = 0, kTrajectory = 1 };
  std::int32_t mode = kHold;
  SampleWire hold;              ///< the reference while holding
  TrajectoryWire current;       ///< the stack's trajectory (followed when mode is kTrajectory)
  TrajectoryWire previous;      ///< followed before current's start time; count 0 = none
  double f_per = 0, f_plan = 0, f_col = 0, f_dif = 0, resolution = 0;
  std::int32_t collision_on_map_update = 0;
  double map_resolution = 0;
  std::int64_t plan_failures = 0;
  std::int64_t publications = 0;
};

/// The simulator's copy of the stack's reference (navstack/methods/reference_tracker.h) on the
/// rebuilt trajectories.
class ReferenceMirror {
 public:
  explicit ReferenceMirror(navstack::PlannerOptions options) : options_(options) {}
  /// Takes a new message (rebuilds the trajectories that changed).
  void Update(const ReferenceWire& w);
  navstack::TrajectorySample Reference(double t) const;
  bool has_message() const { return has_message_; }

 private:
  navstack::PlannerOptions options_;
  bool has_message_ = false;
  navstack::PublishedReference ref_;
};

/// Per-task accounting and a few counters of the navstack process.
struct StatsWire {
  navstack::TaskStats tasks[navstack::kTaskCount];
  navstack::JobLockStats lock;
  /// Wall seconds the jobs executed (RealtimeExecutor::ExecutionWallSeconds).
  double execution_wall_s[navstack::kTaskCount] = {};
  /// What the virtual clock's cost model charges for the same jobs on this board (their work
  /// counts priced per unit), board seconds: the in-situ check of the cost model.
  double model_board_s[navstack::kTaskCount] = {};
  /// Release instants reached late with no job active (RealtimeExecutor::ReleaseLags).
  std::int64_t release_lags[navstack::kTaskCount] = {};
  double child_now = 0;            ///< the stack's sim time at this snapshot
  std::int64_t frames_received = 0;
  std::int64_t frames_dropped = 0;  ///< published but overwritten before the stack took them
  std::int64_t odometry_applied = 0;
  std::int64_t publications = 0;
};

struct EventWire {
  double t = 0;
  char kind[32] = {};
  char detail[96] = {};
};

/// Latest-value slot in shared memory for one writer (a seqlock): the writer never waits, a
/// reader retries a torn copy. The payload is copied as relaxed atomic words so a concurrent
/// read is a detected retry, not a data race. T must be trivially copyable.
template <typename T>
struct SeqSlot {
  static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;
  alignas(64) std::atomic<std::uint32_t> seq{0};
  std::atomic<std::uint64_t> words[kWords];

  void Write(const T& value) {
    const auto* src = reinterpret_cast<const unsigned char*>(&value);
    const std::uint32_t q = seq.load(std::memory_order_relaxed);
    seq.store(q + 1, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_release);
    for (std::size_t i = 0; i < kWords; ++i) {
      std::uint64_t w = 0;
      std::memcpy(&w, src + 8 * i, std::min<std::size_t>(8, sizeof(T) - 8 * i));
      words[i].store(w, std::memory_order_relaxed);
    }
    seq.store(q + 2, std::memory_order_release);
  }
  /// Copies the value if it changed since `*seen` (updated on success). False if nothing new,
  /// or if no consistent copy could be taken (the writer died mid-write).
  bool Read(T* out, std::uint32_t* seen) const {
    auto* dst = reinterpret_cast<unsigned char*>(out);
    for (int attempt = 0; attempt < 10'000; ++attempt) {
      const std::uint32_t q1 = seq.load(std::memory_order_acquire);
      if (q1 & 1u) continue;
      if (q1 == *seen) return false;
      for (std::size_t i = 0; i < kWords; ++i) {
        const std::uint64_t w = words[i].load(std::memory_order_relaxed);
        std::memcpy(dst + 8 * i, &w, std::min<std::size_t>(8, sizeof(T) - 8 * i));
      }
      std::atomic_thread_fence(std::memory_order_acquire);
      if (seq.load(std::memory_order_relaxed) == q1) {
        *seen = q1;
        return true;
      }
    }
    return false;
  }
};

}  // namespace enavi::emulation
