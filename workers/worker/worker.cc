#include "workers/worker/worker.h"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>

#include <spdlog/spdlog.h>

#include "api/atomic_file.h"
#include "api/content_hash.h"
#include "api/job_spec.h"
#include "workers/worker/process.h"

namespace enavi::worker {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string HostName() {
  char name[256] = {0};
  if (gethostname(name, sizeof(name) - 1) != 0) return "localhost";
  return name;
}

template <typename List>
bool Has(const List& list, const std::string& v) {
  return std::find(list.begin(), list.end(), v) != list.end();
}

}  // namespace

fs::path DefaultStateDir(const api::BusOptions& bus) {
  fs::path base;
  if (const char* xdg = std::getenv("XDG_STATE_HOME"); xdg && *xdg) {
    base = fs::path(xdg) / "enavi";
  } else if (const char* home = std::getenv("HOME"); home && *home) {
    base = fs::path(home) / ".local/state/enavi";
  } else {
    base = fs::temp_directory_path() / ("enavi-" + std::to_string(getuid()));
  }
  return base / ("d" + std::to_string(bus.domain_id) + "-" + bus.partition);
}

Worker::Worker(WorkerOptions options)
    : options_(std::move(options)),
      spool_(options_.spool_dir.empty() ? throw std::invalid_argument("--spool: required")
                                        : options_.spool_dir),
      host_(HostName()) {
  if (options_.slots < 1 || options_.slots > 256) {
    throw std::invalid_argument("--slots: " + std::to_string(options_.slots) + " outside [1, 256]");
  }
  if (options_.work_dir.empty()) throw std::invalid_argument("--work-dir: required");
  // Episodes run inside their own directory: every path handed to them must be absolute.
  options_.work_dir = fs::absolute(options_.work_dir);
  if (options_.worker_id.empty()) options_.worker_id = host_ + "-" + std::to_string(getpid());
  // What the episode command flies is the registries' (the composition root passes them).
  if (options_.boards.empty()) throw std::invalid_argument("--boards: the worker serves no board");
  if (options_.clocks.empty()) throw std::invalid_argument("--clocks: the worker serves no clock");
  if (options_.episode_command.empty()) {
    options_.episode_command = DefaultEpisodeCommand();
  }
  fs::create_directories(options_.work_dir);
  fs::create_directories(options_.work_dir / "policies");
  bus_ = std::make_unique<api::WorkerBus>(options_.bus, options_.worker_id);
}

Worker::~Worker() {
  abandon_ = true;
  for (auto& [key, slot] : running_) {
    slot->abort = true;
    if (slot->thread.joinable()) slot->thread.join();
  }
}

void Worker::RequestStop(bool abandon) {
  if (abandon || stop_requests_.fetch_add(1) >= 1) abandon_ = true;
  if (abandon) stop_requests_.fetch_add(1);
  if (bus_) bus_->Wake();
}

WorkerStats Worker::stats() const {
  std::lock_guard lock(stats_mutex_);
  return stats_;
}

void Worker::Run() {
  spdlog::info("worker {}: {} slots, episode command: {} ...", options_.worker_id, options_.slots,
               options_.episode_command.front());
  if (!kAddressSpaceLimitApplies && options_.limits.memory_bytes > 0) {
    spdlog::warn("worker {}: {}", options_.worker_id, kAddressSpaceLimitOff);
  }
  // Results finished before a restart go out again first.
  std::vector<std::string> problems;
  for (auto& m : spool_.LoadAll(&problems)) {
    spdlog::info("re-sending spooled result {} attempt {}", m.episode_id, m.attempt);
    Send(std::move(m), /*spool=*/false);
  }
  for (const auto& p : problems) spdlog::warn("spool: {}", p);

  auto next_heartbeat = Clock::now();
  Clock::time_point drain_deadline = Clock::time_point::max();
  Clock::time_point ack_deadline = Clock::time_point::max();
  while (true) {
    const auto now = Clock::now();
    if (now >= next_heartbeat) {
      PublishStatus();
      next_heartbeat = now + options_.heartbeat;
    }
    const auto wait = std::clamp(
        std::chrono::duration_cast<std::chrono::milliseconds>(next_heartbeat - Clock::now()),
        std::chrono::milliseconds(1), std::chrono::milliseconds(200));
    api::WorkerBus::Inbox inbox = bus_->Wait(wait);
    for (const auto& bad : inbox.bad_samples) spdlog::warn("dropped malformed sample: {}", bad);
    for (const auto& p : inbox.policies) HandlePolicy(p);
    for (const auto& a : inbox.assignments) HandleAssignment(a);
    StartWaiting();
    for (const auto& ack : inbox.acks) HandleAck(ack);
    for (const auto& e : inbox.events) HandleEvent(e);
    CollectFinished();
    ResendDue();

    // Shutdown: drain, then abandon what is left, then wait briefly for the last acks.
    if (stop_requests_.load() > 0) {
      if (drain_deadline == Clock::time_point::max()) {
        drain_deadline = Clock::now() + options_.drain_timeout;
        spdlog::info("worker {}: stopping; {} episodes running", options_.worker_id,
                     running_.size());
        PublishStatus();  // announce draining at once
      }
      if (abandon_.load() || Clock::now() >= drain_deadline) {
        for (auto& [key, w] : waiting_) {
          api::ResultMessage m;
          m.episode_id = key.first;
          m.attempt = key.second;
          m.worker_id = options_.worker_id;
          m.job_id = w.first.job_id;
          m.status = api::ResultStatus::kRejected;
          m.error = "worker stopped before the episode's policy arrived";
          Send(std::move(m), /*spool=*/false);
        }
        waiting_.clear();
        for (auto& [key, slot] : running_) {
          slot->shutdown = true;
          slot->abort = true;
        }
      }
      if (running_.empty() && waiting_.empty()) {
        if (ack_deadline == Clock::time_point::max()) ack_deadline = Clock::now() + options_.ack_grace;
        if (unacked_.empty() || Clock::now() >= ack_deadline) break;
      }
    }
  }
  if (!unacked_.empty()) {
    spdlog::warn("worker {}: {} results not yet acknowledged stay in {}", options_.worker_id,
                 unacked_.size(), spool_.dir().string());
  }
  // Graceful leave: the server re-queues nothing and stops assigning at once.
  try {
    bus_->DisposeStatus();
  } catch (const std::exception& e) {
    spdlog::warn("status dispose failed: {}", e.what());
  }
  spdlog::info("worker {}: stopped", options_.worker_id);
}

void Worker::HandleAssignment(const api::Assignment& a) {
  const Key key{a.episode_id, a.attempt};
  if (running_.count(key) || waiting_.count(key) || unacked_.count(key)) return;  // replay of one we have
  auto reject = [&](const std::string& why) {
    api::ResultMessage m;
    m.episode_id = a.episode_id;
    m.attempt = a.attempt;
    m.worker_id = options_.worker_id;
    m.job_id = a.job_id;
    m.status = api::ResultStatus::kRejected;
    m.error = why;
    spdlog::info("rejected {} attempt {}: {}", a.episode_id, a.attempt, why);
    {
      std::lock_guard lock(stats_mutex_);
      ++stats_.rejected;
    }
    Send(std::move(m), /*spool=*/false);
  };
  if (stop_requests_.load() > 0) return reject("worker is stopping");
  if (static_cast<int>(running_.size() + waiting_.size()) >= options_.slots) return reject("no free slot");
  if (!Has(options_.boards, a.spec.board)) return reject("board " + a.spec.board + " not served");
  if (!Has(options_.clocks, a.spec.clock)) return reject("clock " + a.spec.clock + " not served");
  if (a.spec.ros && !Has(options_.features, "ros")) return reject("ROS methods not served (no ROS on this worker)");
  if (!a.policy_hash.empty() && !fs::exists(PolicyPath(a.policy_hash))) {
    spdlog::info("{} attempt {} waits for policy {}", a.episode_id, a.attempt, a.policy_hash.substr(0, 12));
    waiting_.emplace(key, std::make_pair(a, Clock::now()));
    PublishStatus();
    return;
  }
  StartSlot(a);
}

fs::path Worker::PolicyPath(const std::string& hash) const {
  return options_.work_dir / "policies" / (hash + ".json");
}

// Policies are cached by content hash: verified, written once, shared by every episode.
void Worker::HandlePolicy(const api::PolicyBlob& policy) {
  const fs::path path = PolicyPath(policy.hash);
  if (fs::exists(path)) return;
  if (api::Sha256Hex(policy.json) != policy.hash) {
    spdlog::warn("policy {} does not match its hash: ignored", policy.hash);
    return;
  }
  try {
    api::WriteFileAtomic(path, policy.json);
  } catch (const std::runtime_error& e) {
    spdlog::error("cannot cache policy {}: {}", policy.hash, e.what());
    return;
  }
  spdlog::info("cached policy {} ({} bytes)", policy.hash.substr(0, 12), policy.json.size());
}

void Worker::StartWaiting() {
  for (auto it = waiting_.begin(); it != waiting_.end();) {
    const api::Assignment& a = it->second.first;
    if (fs::exists(PolicyPath(a.policy_hash))) {
      StartSlot(a);
    } else if (Clock::now() - it->second.second >= options_.policy_wait) {
      api::ResultMessage m;
      m.episode_id = a.episode_id;
      m.attempt = a.attempt;
      m.worker_id = options_.worker_id;
      m.job_id = a.job_id;
      m.status = api::ResultStatus::kError;
      m.error = "policy " + a.policy_hash + " not received within " +
                std::to_string(options_.policy_wait.count()) + " s";
      spdlog::warn("{} attempt {}: {}", a.episode_id, a.attempt, m.error);
      Send(std::move(m), /*spool=*/true);
    } else {
      ++it;
      continue;
    }
    it = waiting_.erase(it);
  }
}

void Worker::StartSlot(const api::Assignment& a) {
  const Key key{a.episode_id, a.attempt};
  auto slot = std::make_unique<Slot>();
  slot->assignment = a;
  Slot* raw = slot.get();
  running_.emplace(key, std::move(slot));
  raw->thread = std::thread([this, raw] { SlotMain(raw); });
  spdlog::info("running {} attempt {} ({} {} {} seed {})", a.episode_id, a.attempt, a.spec.board,
               a.spec.world, a.spec.method, a.spec.seed);
  PublishStatus();  // the lease is renewed from the first heartbeat that lists it
}

void Worker::SlotMain(Slot* slot) {
  const api::Assignment& a = slot->assignment;
  // A collection episode flies the cached policy file; its result records the hash.
  api::EpisodeSpec spec = a.spec;
  if (!a.policy_hash.empty()) spec.policy = PolicyPath(a.policy_hash).string();
  EpisodeRun run;
  run.collect_rollout = !a.policy_hash.empty();
  run.command = options_.episode_command;
  run.dir = options_.work_dir / (a.episode_id + "." + std::to_string(a.attempt));
  run.limits = options_.limits;
  run.env = {"ENAVI_EPISODE_ID=" + a.episode_id, "ENAVI_ATTEMPT=" + std::to_string(a.attempt),
             "ENAVI_JOB_ID=" + a.job_id, "ENAVI_WORKER_ID=" + options_.worker_id};
  EpisodeOutcome outcome;
  try {
    outcome = RunEpisode(spec, run, slot->abort);
    if (!a.policy_hash.empty()) outcome.result.spec.policy = api::kPolicyHashPrefix + a.policy_hash;
  } catch (const std::exception& e) {
    outcome.kind = EpisodeOutcome::Kind::kError;
    outcome.error = std::string("worker could not run the episode: ") + e.what();
  }
  if (!options_.keep_episode_dirs && outcome.kind != EpisodeOutcome::Kind::kError) {
    std::error_code ec;
    fs::remove_all(run.dir, ec);
  }
  {
    std::lock_guard lock(finished_mutex_);
    finished_.emplace_back(Key{a.episode_id, a.attempt}, std::move(outcome));
  }
  bus_->Wake();
}

void Worker::CollectFinished() {
  std::vector<std::pair<Key, EpisodeOutcome>> done;
  {
    std::lock_guard lock(finished_mutex_);
    done.swap(finished_);
  }
  for (auto& [key, outcome] : done) {
    auto it = running_.find(key);
    if (it == running_.end()) continue;
    it->second->thread.join();
    const api::Assignment a = it->second->assignment;
    const bool shutdown = it->second->shutdown.load();
    running_.erase(it);

    api::ResultMessage m;
    m.episode_id = a.episode_id;
    m.attempt = a.attempt;
    m.worker_id = options_.worker_id;
    m.job_id = a.job_id;
    m.wall_time_s = outcome.wall_time_s;
    switch (outcome.kind) {
      case EpisodeOutcome::Kind::kResult:
        m.status = api::ResultStatus::kOk;
        m.result = std::move(outcome.result);
        m.policy_hash = a.policy_hash;
        m.rollout = std::move(outcome.rollout);
        if (m.rollout.size() > api::kMaxRolloutBytes) {
          m.status = api::ResultStatus::kError;
          m.error = "rollout of " + std::to_string(m.rollout.size()) + " bytes exceeds the " +
                    std::to_string(api::kMaxRolloutBytes) +
                    "-byte limit of one bus sample (a learned policy's: smaller images or a shorter timeout_s)";
          m.rollout.clear();
        }
        break;
      case EpisodeOutcome::Kind::kError:
        m.status = api::ResultStatus::kError;
        m.error = outcome.error;
        spdlog::warn("{} attempt {} failed: {}", a.episode_id, a.attempt, outcome.error);
        break;
      case EpisodeOutcome::Kind::kAborted:
        {
          std::lock_guard lock(stats_mutex_);
          ++stats_.aborted;
        }
        // Cancelled or closed elsewhere: nobody wants a result. Stopping: hand it back.
        if (!shutdown) continue;
        m.status = api::ResultStatus::kRejected;
        m.error = "worker stopped before the episode finished";
        break;
    }
    {
      std::lock_guard lock(stats_mutex_);
      if (m.status != api::ResultStatus::kRejected) ++stats_.episodes_run;
    }
    const bool spool = m.status != api::ResultStatus::kRejected;
    Send(std::move(m), spool);
  }
  if (!done.empty()) PublishStatus();
}

void Worker::Send(api::ResultMessage message, bool spool) {
  const Key key{message.episode_id, message.attempt};
  if (spool) {
    try {
      spool_.Save(message);
    } catch (const std::exception& e) {
      spdlog::error("cannot spool {}: {} (kept in memory only)", message.episode_id, e.what());
    }
  }
  Outgoing& out = unacked_[key];
  out.message = std::move(message);
  out.backoff = options_.resend;
  out.next_send = Clock::now();  // ResendDue sends it now
  ResendDue();
}

void Worker::ResendDue() {
  const auto now = Clock::now();
  for (auto& [key, out] : unacked_) {
    if (out.next_send > now) continue;
    try {
      bus_->Publish(out.message);
    } catch (const std::exception& e) {
      spdlog::warn("publishing result {} failed: {} (will retry)", key.first, e.what());
    }
    out.next_send = now + out.backoff;
    out.backoff = std::min(out.backoff * 2, std::chrono::milliseconds(60000));
  }
}

void Worker::HandleAck(const api::ResultAck& ack) {
  const Key key{ack.episode_id, ack.attempt};
  auto it = unacked_.find(key);
  if (it == unacked_.end()) return;
  if (ack.status == api::AckStatus::kUnknown) {
    spdlog::warn("server does not know episode {}: dropping its result", ack.episode_id);
  }
  try {
    bus_->Retire(it->second.message);
  } catch (const std::exception&) {
    // Already gone from the writer's history (e.g. loaded from the spool, never written).
  }
  spool_.Remove(ack.episode_id, ack.attempt);
  unacked_.erase(it);
  std::lock_guard lock(stats_mutex_);
  ++stats_.results_acked;
}

void Worker::HandleEvent(const api::JobEvent& e) {
  std::erase_if(waiting_, [&](const auto& w) {
    return (e.kind == "cancelled" && w.second.first.job_id == e.job_id) ||
           (e.kind == "episode_done" && w.first.first == e.episode_id);
  });
  for (auto& [key, slot] : running_) {
    const bool job_cancelled = e.kind == "cancelled" && slot->assignment.job_id == e.job_id;
    // Another attempt of an episode we run has finished it: ours is wasted work. (Not on
    // episode_failed: a late success of ours would still be stored.)
    const bool closed = e.kind == "episode_done" && key.first == e.episode_id;
    if ((job_cancelled || closed) && !slot->abort.exchange(true)) {
      spdlog::info("stopping {} attempt {}: {}", key.first, key.second,
                   job_cancelled ? "job cancelled" : "finished elsewhere");
    }
  }
}

void Worker::PublishStatus() {
  api::WorkerStatus s;
  s.worker_id = options_.worker_id;
  s.host = host_;
  s.pid = getpid();
  s.slots = options_.slots;
  s.draining = stop_requests_.load() > 0;
  s.free_slots = s.draining ? 0 : options_.slots - static_cast<int>(running_.size() + waiting_.size());
  s.boards = options_.boards;
  s.clocks = options_.clocks;
  s.features = options_.features;
  s.calibration_id = options_.calibration_id;
  s.seq = ++seq_;
  for (const auto& [key, slot] : running_) s.running.push_back({key.first, key.second});
  for (const auto& [key, w] : waiting_) s.running.push_back({key.first, key.second});
  s.unacked_results = static_cast<int>(unacked_.size());
  s.version = ENAVI_VERSION;
  try {
    bus_->Publish(s);
  } catch (const std::exception& e) {
    spdlog::warn("heartbeat failed: {}", e.what());
  }
}

}  // namespace enavi::worker
