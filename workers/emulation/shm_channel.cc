#include "workers/emulation/shm_channel.h"

#include <fcntl.h>
#include <linux/futex.h>
#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>
#include <new>
#include <stdexcept>
#include <string>
#include <utility>

namespace enavi::emulation {
namespace {

constexpr std::uint64_t kMagic = 0x454e4156'49534d48ULL;  // "ENAVISMH"
constexpr std::uint32_t kVersion = 1;
constexpr std::uint32_t kFresh = 4;  // triple-buffer state: bits 0-1 middle slot, bit 2 fresh
constexpr std::size_t kPage = 4096;

static_assert(std::atomic<std::uint32_t>::is_always_lock_free);
static_assert(std::atomic<std::uint64_t>::is_always_lock_free);
static_assert(std::atomic<std::int64_t>::is_always_lock_free);
static_assert(sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t), "futex word");

// Latest-value slot a reader can sleep on: a seqlock (as emulated_wire.h's SeqSlot) whose
// sequence word is also the futex word waiters sleep on.
// Odd sequence = write in progress. The payload is copied as relaxed atomic words, so a torn
// read is detected by the sequence check instead of being a data race.
template <typename T>
struct WaitableSeqSlot {
  static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;
  alignas(64) std::atomic<std::uint32_t> seq{0};
  std::atomic<std::uint32_t> waiters{0};
  std::atomic<std::uint64_t> words[kWords];
};

// The start of the mapping; frame slots follow at frames_offset.
struct Shared {
  std::uint64_t magic = 0;
  std::uint32_t version = 0;
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::uint64_t total_size = 0;
  std::uint64_t frames_offset = 0;
  std::uint64_t frame_slot_bytes = 0;
  alignas(64) std::atomic<std::int32_t> pid[2] = {0, 0};
  std::atomic<std::int64_t> heartbeat_ns[2] = {0, 0};
  alignas(64) std::atomic<std::uint32_t> frame_state{1};  // middle = slot 1, nothing fresh
  std::atomic<std::uint32_t> frame_seq{0};                 // futex word: publications (mod 2^32)
  std::atomic<std::uint32_t> frame_waiters{0};
  std::atomic<std::int64_t> frames_published{0};
  WaitableSeqSlot<OdometryMsg> odometry;
  WaitableSeqSlot<TrajectoryMsg> trajectory;
  WaitableSeqSlot<RotorCommandMsg> rotor;
};

std::size_t RoundUp(std::size_t v, std::size_t to) { return (v + to - 1) / to * to; }

std::size_t FrameSlotBytes(int width, int height) {
  return RoundUp(RoundUp(sizeof(FrameHeader), 64) +
                     static_cast<std::size_t>(width) * height * sizeof(float), kPage);
}

std::size_t FramesOffset() { return RoundUp(sizeof(Shared), kPage); }

std::int64_t NowNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

std::uint32_t* FutexAddr(const std::atomic<std::uint32_t>& word) {
  return reinterpret_cast<std::uint32_t*>(const_cast<std::atomic<std::uint32_t>*>(&word));
}

// Shared (not FUTEX_PRIVATE) futex: the word lives in a mapping of two processes.
void FutexWake(const std::atomic<std::uint32_t>& word) {
  syscall(SYS_futex, FutexAddr(word), FUTEX_WAKE, INT_MAX, nullptr, nullptr, 0);
}

void FutexWait(const std::atomic<std::uint32_t>& word, std::uint32_t expected,
               std::chrono::nanoseconds timeout) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(timeout.count() / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(timeout.count() % 1'000'000'000);
  syscall(SYS_futex, FutexAddr(word), FUTEX_WAIT, expected, &ts, nullptr, 0);
}

template <typename T>
void SeqWrite(WaitableSeqSlot<T>& slot, const T& value) {
  std::uint64_t buf[WaitableSeqSlot<T>::kWords] = {};
  std::memcpy(buf, &value, sizeof(T));
  const std::uint32_t q = slot.seq.load(std::memory_order_relaxed);
  slot.seq.store(q + 1, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  for (std::size_t i = 0; i < WaitableSeqSlot<T>::kWords; ++i) {
    slot.words[i].store(buf[i], std::memory_order_relaxed);
  }
  slot.seq.store(q + 2, std::memory_order_release);
  // Either we see the waiter's announcement or it sees our new sequence (Dekker, seq_cst).
  std::atomic_thread_fence(std::memory_order_seq_cst);
  if (slot.waiters.load(std::memory_order_relaxed) > 0) FutexWake(slot.seq);
}

template <typename T>
bool SeqRead(const WaitableSeqSlot<T>& slot, T* out, std::uint32_t* seen) {
  std::uint64_t buf[WaitableSeqSlot<T>::kWords];
  // Bounded: a writer that died mid-write leaves an odd sequence forever.
  for (int attempt = 0; attempt < 100'000; ++attempt) {
    const std::uint32_t q1 = slot.seq.load(std::memory_order_acquire);
    if (q1 & 1u) continue;
    if (q1 == *seen) return false;
    for (std::size_t i = 0; i < WaitableSeqSlot<T>::kWords; ++i) {
      buf[i] = slot.words[i].load(std::memory_order_relaxed);
    }
    std::atomic_thread_fence(std::memory_order_acquire);
    if (slot.seq.load(std::memory_order_relaxed) == q1) {
      std::memcpy(static_cast<void*>(out), buf, sizeof(T));
      *seen = q1;
      return true;
    }
  }
  return false;
}

Shared* S(void* base) { return static_cast<Shared*>(base); }

}  // namespace

// ---------------------------------------------------------------------------------------------
// Life cycle

ShmChannel ShmChannel::Create(const ShmChannelOptions& options) {
  if (options.width < 1 || options.width > 4096 || options.height < 1 || options.height > 4096) {
    throw std::invalid_argument("ShmChannel: frame size must be in [1, 4096] x [1, 4096], got " +
                                std::to_string(options.width) + " x " +
                                std::to_string(options.height));
  }
  ShmChannel ch;
  ch.role_ = Role::kSimulator;
  ch.fd_ = memfd_create("enavi-shm-channel", MFD_CLOEXEC);
  if (ch.fd_ < 0) {
    throw std::runtime_error(std::string("ShmChannel: memfd_create failed: ") + std::strerror(errno));
  }
  const std::size_t slot_bytes = FrameSlotBytes(options.width, options.height);
  const std::size_t total = FramesOffset() + 3 * slot_bytes;
  if (ftruncate(ch.fd_, static_cast<off_t>(total)) != 0) {
    throw std::runtime_error(std::string("ShmChannel: ftruncate failed: ") + std::strerror(errno));
  }
  ch.Map(total);
  Shared* s = new (ch.base_) Shared();
  s->version = kVersion;
  s->width = options.width;
  s->height = options.height;
  s->total_size = total;
  s->frames_offset = FramesOffset();
  s->frame_slot_bytes = slot_bytes;
  for (int i = 0; i < 3; ++i) new (ch.Slot(i).header) FrameHeader();
  s->pid[0].store(getpid());
  s->heartbeat_ns[0].store(NowNs());
  // The magic goes last: a mapping with it is fully initialised.
  std::atomic_thread_fence(std::memory_order_release);
  s->magic = kMagic;
  return ch;
}

ShmChannel ShmChannel::Attach(int fd, Role role) {
  struct stat st{};
  if (fstat(fd, &st) != 0) {
    throw std::invalid_argument("ShmChannel::Attach: fd " + std::to_string(fd) +
                                " is not open: " + std::strerror(errno));
  }
  if (static_cast<std::size_t>(st.st_size) < FramesOffset()) {
    throw std::invalid_argument("ShmChannel::Attach: fd " + std::to_string(fd) + " holds " +
                                std::to_string(st.st_size) + " bytes, too small for a channel");
  }
  ShmChannel ch;
  ch.role_ = role;
  ch.fd_ = fd;
  ch.Map(static_cast<std::size_t>(st.st_size));
  const Shared* s = S(ch.base_);
  if (s->magic != kMagic || s->version != kVersion) {
    ch.fd_ = -1;  // not ours: leave the caller's descriptor open
    throw std::invalid_argument("ShmChannel::Attach: fd " + std::to_string(fd) +
                                " is not an enavi shm channel of version " +
                                std::to_string(kVersion));
  }
  if (s->total_size != static_cast<std::uint64_t>(st.st_size) ||
      s->frame_slot_bytes != FrameSlotBytes(s->width, s->height)) {
    ch.fd_ = -1;
    throw std::invalid_argument("ShmChannel::Attach: fd " + std::to_string(fd) +
                                " has an inconsistent channel layout");
  }
  const int r = static_cast<int>(role);
  S(ch.base_)->pid[r].store(getpid());
  S(ch.base_)->heartbeat_ns[r].store(NowNs());
  return ch;
}

void ShmChannel::Map(std::size_t size) {
  void* p = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_POPULATE, fd_, 0);
  if (p == MAP_FAILED) {
    throw std::runtime_error(std::string("ShmChannel: mmap failed: ") + std::strerror(errno));
  }
  base_ = p;
  size_ = size;
}

void ShmChannel::Release() {
  if (base_ != nullptr) munmap(base_, size_);
  if (fd_ >= 0) close(fd_);
  if (peer_pidfd_ >= 0) close(peer_pidfd_);
  base_ = nullptr;
  fd_ = -1;
  peer_pidfd_ = -1;
}

ShmChannel::ShmChannel(ShmChannel&& o) noexcept { *this = std::move(o); }

ShmChannel& ShmChannel::operator=(ShmChannel&& o) noexcept {
  if (this == &o) return *this;
  Release();
  fd_ = std::exchange(o.fd_, -1);
  role_ = o.role_;
  base_ = std::exchange(o.base_, nullptr);
  size_ = o.size_;
  back_ = o.back_;
  front_ = o.front_;
  last_frame_index_ = o.last_frame_index_;
  last_frame_seq_ = o.last_frame_seq_;
  peer_pidfd_ = std::exchange(o.peer_pidfd_, -1);
  return *this;
}

ShmChannel::~ShmChannel() { Release(); }

int ShmChannel::width() const { return S(base_)->width; }
int ShmChannel::height() const { return S(base_)->height; }

// ---------------------------------------------------------------------------------------------
// Liveness

void ShmChannel::Heartbeat() {
  S(base_)->heartbeat_ns[static_cast<int>(role_)].store(NowNs(), std::memory_order_relaxed);
}

PeerState ShmChannel::Peer() {
  const pid_t pid = S(base_)->pid[1 - static_cast<int>(role_)].load();
  if (pid == 0) return PeerState::kNotAttached;
  if (peer_pidfd_ < 0) {
    peer_pidfd_ = static_cast<int>(syscall(SYS_pidfd_open, pid, 0));
    if (peer_pidfd_ < 0) {
      if (errno == ESRCH) return PeerState::kDead;
      // No pidfd (old kernel): signal 0 sees a zombie as alive, good enough as a fallback.
      return kill(pid, 0) == 0 || errno == EPERM ? PeerState::kAlive : PeerState::kDead;
    }
  }
  pollfd p{peer_pidfd_, POLLIN, 0};
  // A pidfd becomes readable when the process exits (also before it is reaped).
  return poll(&p, 1, 0) > 0 ? PeerState::kDead : PeerState::kAlive;
}

std::chrono::nanoseconds ShmChannel::PeerHeartbeatAge() const {
  const std::int64_t beat = S(base_)->heartbeat_ns[1 - static_cast<int>(role_)].load();
  if (beat == 0) return std::chrono::nanoseconds::max();
  return std::chrono::nanoseconds(NowNs() - beat);
}

WaitStatus ShmChannel::WaitWord(const std::atomic<std::uint32_t>& word,
                                std::atomic<std::uint32_t>& waiters, std::uint32_t seen,
                                std::chrono::nanoseconds timeout) {
  // Sleep in slices so a dead peer is noticed within one slice, never a hang.
  constexpr std::chrono::nanoseconds kSlice = std::chrono::milliseconds(20);
  const std::int64_t deadline = NowNs() + timeout.count();
  while (true) {
    if (word.load(std::memory_order_acquire) != seen) return WaitStatus::kNew;
    if (Peer() == PeerState::kDead) return WaitStatus::kPeerDead;
    const std::int64_t left = deadline - NowNs();
    if (left <= 0) return WaitStatus::kTimeout;
    waiters.fetch_add(1, std::memory_order_seq_cst);
    std::atomic_thread_fence(std::memory_order_seq_cst);
    if (word.load(std::memory_order_relaxed) == seen) {
      FutexWait(word, seen, std::min(kSlice, std::chrono::nanoseconds(left)));
    }
    waiters.fetch_sub(1, std::memory_order_relaxed);
  }
}

// ---------------------------------------------------------------------------------------------
// Frames: triple buffer

FrameSlot ShmChannel::Slot(int index) const {
  const Shared* s = S(base_);
  auto* p = static_cast<char*>(base_) + s->frames_offset + static_cast<std::size_t>(index) * s->frame_slot_bytes;
  FrameSlot slot;
  slot.header = reinterpret_cast<FrameHeader*>(p);
  slot.depth = reinterpret_cast<float*>(p + RoundUp(sizeof(FrameHeader), 64));
  return slot;
}

FrameSlot ShmChannel::BeginFrame() {
  FrameSlot slot = Slot(back_);
  slot.header->width = S(base_)->width;
  slot.header->height = S(base_)->height;
  return slot;
}

void ShmChannel::PublishFrame() {
  Shared* s = S(base_);
  // The header index orders publications; the reader derives drops from it.
  Slot(back_).header->index = s->frames_published.fetch_add(1, std::memory_order_relaxed);
  const std::uint32_t previous = s->frame_state.exchange(static_cast<std::uint32_t>(back_) | kFresh,
                                                         std::memory_order_acq_rel);
  back_ = static_cast<int>(previous & 3u);
  s->frame_seq.fetch_add(1, std::memory_order_seq_cst);
  if (s->frame_waiters.load(std::memory_order_seq_cst) > 0) FutexWake(s->frame_seq);
  Heartbeat();
}

void ShmChannel::PublishFrame(const navstack::DepthFrame& frame) {
  if (frame.image.width != width() || frame.image.height != height() ||
      frame.image.data.size() != static_cast<std::size_t>(width()) * height()) {
    throw std::invalid_argument("ShmChannel::PublishFrame: frame is " +
                                std::to_string(frame.image.width) + " x " +
                                std::to_string(frame.image.height) + ", channel is " +
                                std::to_string(width()) + " x " + std::to_string(height()));
  }
  FrameSlot slot = BeginFrame();
  FrameHeader& h = *slot.header;
  h.t = frame.t;
  const Eigen::Vector3d p = frame.X_WC.translation();
  const Eigen::Quaterniond q(frame.X_WC.rotation());
  for (int i = 0; i < 3; ++i) h.p_WC[i] = p[i];
  h.q_WC[0] = q.w();
  h.q_WC[1] = q.x();
  h.q_WC[2] = q.y();
  h.q_WC[3] = q.z();
  for (int i = 0; i < 3; ++i) h.v_W[i] = frame.v_W[i];
  std::memcpy(slot.depth, frame.image.data.data(), frame.image.data.size() * sizeof(float));
  PublishFrame();
}

FrameSlot ShmChannel::AcquireFrame(std::int64_t* dropped) {
  Shared* s = S(base_);
  if (dropped != nullptr) *dropped = 0;
  if ((s->frame_state.load(std::memory_order_acquire) & kFresh) == 0) return {};
  const std::uint32_t previous =
      s->frame_state.exchange(static_cast<std::uint32_t>(front_), std::memory_order_acq_rel);
  front_ = static_cast<int>(previous & 3u);
  FrameSlot slot = Slot(front_);
  if (dropped != nullptr) *dropped = slot.header->index - last_frame_index_ - 1;
  last_frame_index_ = slot.header->index;
  Heartbeat();
  return slot;
}

navstack::DepthFrame ShmChannel::ToDepthFrame(const FrameSlot& slot) {
  navstack::DepthFrame f;
  const FrameHeader& h = *slot.header;
  f.index = h.index;
  f.t = h.t;
  f.image = navstack::DepthImage(h.width, h.height);
  std::memcpy(f.image.data.data(), slot.depth, f.image.data.size() * sizeof(float));
  f.X_WC = Eigen::Isometry3d::Identity();
  f.X_WC.linear() = Eigen::Quaterniond(h.q_WC[0], h.q_WC[1], h.q_WC[2], h.q_WC[3]).toRotationMatrix();
  f.X_WC.translation() = Eigen::Vector3d(h.p_WC[0], h.p_WC[1], h.p_WC[2]);
  f.v_W = Eigen::Vector3d(h.v_W[0], h.v_W[1], h.v_W[2]);
  return f;
}

WaitStatus ShmChannel::WaitFrame(std::chrono::nanoseconds timeout) {
  Shared* s = S(base_);
  // The writer sets the fresh bit before bumping frame_seq: sample the word, then test the bit.
  const std::int64_t deadline = NowNs() + timeout.count();
  while (true) {
    const std::uint32_t seq = s->frame_seq.load(std::memory_order_seq_cst);
    if (s->frame_state.load(std::memory_order_acquire) & kFresh) return WaitStatus::kNew;
    const std::int64_t left = deadline - NowNs();
    if (left <= 0) return WaitStatus::kTimeout;
    const WaitStatus w = WaitWord(s->frame_seq, s->frame_waiters, seq, std::chrono::nanoseconds(left));
    if (w != WaitStatus::kNew) {
      // A frame published just before the peer died is still worth delivering.
      if (s->frame_state.load(std::memory_order_acquire) & kFresh) return WaitStatus::kNew;
      return w;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Latest-value slots

void ShmChannel::PublishOdometry(const OdometryMsg& msg) {
  SeqWrite(S(base_)->odometry, msg);
  Heartbeat();
}
bool ShmChannel::ReadOdometry(OdometryMsg* msg, std::uint32_t* seq) {
  return SeqRead(S(base_)->odometry, msg, seq);
}
WaitStatus ShmChannel::WaitOdometry(std::uint32_t seq, std::chrono::nanoseconds timeout) {
  return WaitWord(S(base_)->odometry.seq, S(base_)->odometry.waiters, seq, timeout);
}

void ShmChannel::PublishTrajectory(const TrajectoryMsg& msg) {
  SeqWrite(S(base_)->trajectory, msg);
  Heartbeat();
}
bool ShmChannel::ReadTrajectory(TrajectoryMsg* msg, std::uint32_t* seq) {
  return SeqRead(S(base_)->trajectory, msg, seq);
}
WaitStatus ShmChannel::WaitTrajectory(std::uint32_t seq, std::chrono::nanoseconds timeout) {
  return WaitWord(S(base_)->trajectory.seq, S(base_)->trajectory.waiters, seq, timeout);
}

void ShmChannel::PublishRotor(const RotorCommandMsg& msg) {
  SeqWrite(S(base_)->rotor, msg);
  Heartbeat();
}
bool ShmChannel::ReadRotor(RotorCommandMsg* msg, std::uint32_t* seq) {
  return SeqRead(S(base_)->rotor, msg, seq);
}
WaitStatus ShmChannel::WaitRotor(std::uint32_t seq, std::chrono::nanoseconds timeout) {
  return WaitWord(S(base_)->rotor.seq, S(base_)->rotor.waiters, seq, timeout);
}

OdometryMsg ShmChannel::ToMsg(const navstack::VehicleState& s) {
  OdometryMsg m;
  m.t = s.t;
  for (int i = 0; i < 3; ++i) {
    m.p_WB[i] = s.p_WB[i];
    m.v_WB[i] = s.v_WB[i];
    m.a_WB[i] = s.a_WB[i];
    m.w_WB_B[i] = s.w_WB_B[i];
  }
  m.q_WB[0] = s.q_WB.w();
  m.q_WB[1] = s.q_WB.x();
  m.q_WB[2] = s.q_WB.y();
  m.q_WB[3] = s.q_WB.z();
  return m;
}

navstack::VehicleState ShmChannel::FromMsg(const OdometryMsg& m) {
  navstack::VehicleState s;
  s.t = m.t;
  s.p_WB = Eigen::Vector3d(m.p_WB[0], m.p_WB[1], m.p_WB[2]);
  s.v_WB = Eigen::Vector3d(m.v_WB[0], m.v_WB[1], m.v_WB[2]);
  s.a_WB = Eigen::Vector3d(m.a_WB[0], m.a_WB[1], m.a_WB[2]);
  s.q_WB = Eigen::Quaterniond(m.q_WB[0], m.q_WB[1], m.q_WB[2], m.q_WB[3]);
  s.w_WB_B = Eigen::Vector3d(m.w_WB_B[0], m.w_WB_B[1], m.w_WB_B[2]);
  return s;
}

}  // namespace enavi::emulation
