#pragma once
// Shared-memory channel between the simulator process and the navstack process of an emulated
// episode (docs/design.md, "Time: two clocks": the navstack runs throttled in its own process, the simulator
// outside). One memfd mapping holds:
//   - depth frames, simulator -> navstack: a triple buffer (3 slots). The writer always has a
//     free slot and never waits; the reader always gets the newest complete frame without a
//     copy; frames the reader did not take in time are dropped and counted. A sensor's old
//     frame is worthless to a planner, so newest-wins is the policy.
//   - odometry (simulator -> navstack), trajectory and rotor commands (navstack -> simulator):
//     seqlock latest-value slots, a writer that never waits, a reader that retries a torn read.
//   - wake-ups: futexes on the slots' sequence words in the mapping. The publisher makes a
//     FUTEX_WAKE system call only when a waiter has announced itself, and a waiter blocks in
//     the kernel with a timeout, so the wake-up costs one scheduler wake (bench_shm_latency)
//     and nothing else needs to be passed to the child. (An eventfd would need more descriptors
//     and a system call on every publish.)
//   - liveness: each side records its pid and a heartbeat; waits poll the peer's pidfd between
//     bounded futex sleeps, so a dead peer turns into kPeerDead, never into a hang. Nothing in
//     the protocol waits on the peer, so a peer dying mid-write cannot block the survivor.
// Memory ordering: all shared words are lock-free std::atomic (address-free, valid across
// processes); seqlock payloads are copied as relaxed atomic 64-bit words, frames are owned by
// exactly one side at a time through the triple buffer's atomic exchange.

#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <cstdint>

#include "navstack/common/camera.h"
#include "navstack/common/state.h"

namespace enavi::emulation {

/// Vehicle state as it crosses the process boundary (navstack::VehicleState without Eigen).
struct OdometryMsg {
  double t = 0.0;
  double p_WB[3] = {0, 0, 0};
  double v_WB[3] = {0, 0, 0};
  double a_WB[3] = {0, 0, 0};
  double q_WB[4] = {1, 0, 0, 0};  ///< w, x, y, z
  double w_WB_B[3] = {0, 0, 0};
};

/// A trajectory as time samples for the simulator-side tracking controller (navstack ->
/// simulator): sample i is the reference at t0 + i * dt.
struct TrajectoryMsg {
  static constexpr int kMaxSamples = 128;
  double t_issue = 0.0;  ///< sim time the navstack published it
  double t0 = 0.0;
  double dt = 0.0;
  std::int32_t count = 0;
  std::int32_t flags = 0;  ///< bit 0: hover / fail-safe requested
  struct Sample {
    double p[3], v[3], a[3], j[3];
    double yaw, yaw_rate;
  } samples[kMaxSamples];
};

/// Rotor commands (navstack -> simulator) when the controller runs on the board.
struct RotorCommandMsg {
  double t = 0.0;
  double thrust_N[4] = {0, 0, 0, 0};
};

/// Metadata of one depth frame in the shared ring.
struct FrameHeader {
  std::int64_t index = -1;  ///< frame counter, -1 = never written
  double t = 0.0;           ///< sim time of capture
  double p_WC[3] = {0, 0, 0};
  double q_WC[4] = {1, 0, 0, 0};  ///< w, x, y, z
  double v_W[3] = {0, 0, 0};
  std::int32_t width = 0;
  std::int32_t height = 0;
};

/// A frame slot: header plus width x height row-major z-depth floats.
struct FrameSlot {
  FrameHeader* header = nullptr;
  float* depth = nullptr;
};

struct ShmChannelOptions {
  int width = 640;
  int height = 480;
};

enum class PeerState { kNotAttached, kAlive, kDead };
enum class WaitStatus { kNew, kTimeout, kPeerDead };

/// One end of the channel. Move-only; unmaps (and closes its descriptors) when destroyed.
class ShmChannel {
 public:
  enum class Role : int { kSimulator = 0, kNavstack = 1 };

  /// Simulator side: creates the memfd (close-on-exec; clear FD_CLOEXEC or dup2 it for an exec'd
  /// child) and maps it. Throws std::runtime_error if the kernel refuses, std::invalid_argument
  /// for a frame size outside [1, 4096] x [1, 4096].
  static ShmChannel Create(const ShmChannelOptions& options = {});
  /// Maps an inherited descriptor and takes ownership of it. Throws std::invalid_argument if it is not a channel of this
  /// version (bad magic, version or size), std::runtime_error if the mapping fails.
  static ShmChannel Attach(int fd, Role role);

  ShmChannel(ShmChannel&& other) noexcept;
  ShmChannel& operator=(ShmChannel&& other) noexcept;
  ~ShmChannel();

  int fd() const { return fd_; }
  Role role() const { return role_; }
  int width() const;
  int height() const;

  // --- liveness
  /// Records this side's heartbeat (publishing does it too).
  void Heartbeat();
  PeerState Peer();
  /// Time since the peer's last heartbeat; max() if it never beat.
  std::chrono::nanoseconds PeerHeartbeatAge() const;

  // --- frames (simulator writes, navstack reads)
  /// The slot the writer fills next, in place (e.g. the depth camera renders straight into it).
  FrameSlot BeginFrame();
  /// Publishes the slot returned by BeginFrame(); the previous unread frame, if any, is dropped.
  void PublishFrame();
  /// Copies a navstack frame in and publishes it. Throws std::invalid_argument on a size mismatch.
  void PublishFrame(const navstack::DepthFrame& frame);
  /// Newest frame not yet taken, owned by the reader until its next AcquireFrame(); a slot with
  /// header == nullptr if nothing new. `dropped` (optional) gets the frames skipped since the
  /// previous acquisition.
  FrameSlot AcquireFrame(std::int64_t* dropped = nullptr);
  /// Converts an acquired slot into a navstack frame (copies the pixels).
  static navstack::DepthFrame ToDepthFrame(const FrameSlot& slot);
  /// Blocks until a frame newer than the last acquired one is published, the peer dies, or
  /// the timeout passes.
  WaitStatus WaitFrame(std::chrono::nanoseconds timeout);

  // --- latest-value slots, one writer thread each. Read*() returns false if nothing is new since
  // `*seq` (which it updates on success), or if no consistent copy could be taken because the
  // writer kept rewriting the slot or died in the middle of a write (check Peer()).
  void PublishOdometry(const OdometryMsg& msg);
  bool ReadOdometry(OdometryMsg* msg, std::uint32_t* seq);
  WaitStatus WaitOdometry(std::uint32_t seq, std::chrono::nanoseconds timeout);

  void PublishTrajectory(const TrajectoryMsg& msg);
  bool ReadTrajectory(TrajectoryMsg* msg, std::uint32_t* seq);
  WaitStatus WaitTrajectory(std::uint32_t seq, std::chrono::nanoseconds timeout);

  void PublishRotor(const RotorCommandMsg& msg);
  bool ReadRotor(RotorCommandMsg* msg, std::uint32_t* seq);
  WaitStatus WaitRotor(std::uint32_t seq, std::chrono::nanoseconds timeout);

  /// Conversions between the navstack types and the wire PODs.
  static OdometryMsg ToMsg(const navstack::VehicleState& s);
  static navstack::VehicleState FromMsg(const OdometryMsg& m);

 private:
  ShmChannel() = default;
  void Map(std::size_t size);
  void Release();
  WaitStatus WaitWord(const std::atomic<std::uint32_t>& word, std::atomic<std::uint32_t>& waiters,
                      std::uint32_t seen, std::chrono::nanoseconds timeout);
  FrameSlot Slot(int index) const;

  int fd_ = -1;
  Role role_ = Role::kSimulator;
  void* base_ = nullptr;
  std::size_t size_ = 0;
  int back_ = 0;   // writer-owned frame slot
  int front_ = 2;  // reader-owned frame slot
  std::int64_t last_frame_index_ = -1;
  std::uint32_t last_frame_seq_ = 0;
  int peer_pidfd_ = -1;
};

}  // namespace enavi::emulation
