#include "server/scheduler/farm_server.h"

#include <algorithm>

#include <spdlog/spdlog.h>

#include "api/provenance.h"
#include "navstack/rl/nav_rollout.h"
#include "server/scheduler/collection.h"
#include "server/store/collect_store.h"
#include "server/store/ingest.h"
#include "server/store/worker_store.h"

namespace enavi::server {

std::int64_t NowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

FarmServer::FarmServer(Store* store, FarmServerOptions options)
    : store_(store),
      options_(std::move(options)),
      bus_(std::make_unique<api::ServerBus>(options_.bus)) {}

FarmServer::~FarmServer() { Stop(); }

void FarmServer::Start() {
  // Leases that ran out while no server was watching go back to pending now; leases still
  // running are kept for their workers' heartbeats to renew.
  HandleReleased(store_->leases().ExpireLeases(NowMs()), NowMs());
  // Workers need the policies of every running collection job.
  for (const auto& [hash, json] : store_->collect().ActivePolicies()) bus_->Publish(api::PolicyBlob{hash, json});
  // An assignment lives in the DDS writer of the server that made it: one its worker had not yet
  // received when that server died was lost, and the worker would neither run nor renew it (the
  // lease ran out, an attempt spent, its slot idle meanwhile). Re-send every lease still held; a
  // worker ignores the replay of one it already runs or has finished.
  for (const Lease& l : store_->leases().HeldLeases()) {
    bus_->Publish(api::Assignment{l.worker, l.episode_id, l.attempt, l.job_id, l.deadline_ms,
                                  options_.lease.count(), l.spec, CollectionHash(l.job_id)});
  }
  stop_ = false;
  thread_ = std::thread([this] { Loop(); });
}

void FarmServer::Stop() {
  stop_ = true;
  if (bus_) bus_->Wake();
  if (thread_.joinable()) thread_.join();
}

std::string FarmServer::Submit(const api::JobSpec& job, const std::string& spec_yaml) {
  JobMeta meta;
  meta.labels = job.labels;
  meta.provenance["enavi_version"] = api::BuildVersion();
  meta.provenance["git_commit"] = api::BuildCommit();
  meta.provenance["clock"] = job.clock;
  meta.provenance["cost"] = job.cost;
  if (!job.policy.empty()) {
    meta.provenance["policy"] = job.policy;
    const bool by_hash = job.policy.rfind(api::kPolicyHashPrefix, 0) == 0;
    meta.provenance["policy_sha256"] =
        by_hash ? job.policy.substr(std::string(api::kPolicyHashPrefix).size()) : api::Sha256File(job.policy);
  }
  std::vector<api::EpisodeSpec> episodes = api::ExpandJob(job);
  const std::optional<CollectionInfo> collect = PrepareCollection(store_, job, &episodes);
  return Submit(job.name, spec_yaml, episodes, meta, collect);
}

std::string FarmServer::Submit(const std::string& name, const std::string& spec_yaml,
                               const std::vector<api::EpisodeSpec>& episodes, const JobMeta& meta,
                               const std::optional<CollectionInfo>& collect) {
  const std::int64_t now = NowMs();
  if (collect) PublishPolicy(collect->policy_hash);
  std::string job_id = store_->jobs().CreateJob(name, spec_yaml, episodes, now, meta, collect);
  spdlog::info("job {} '{}': {} episodes", job_id, name, episodes.size());
  PublishEvents({{job_id, "submitted", "", name}}, now);
  bus_->Wake();
  return job_id;
}

bool FarmServer::Cancel(const std::string& job_id) {
  const std::int64_t now = NowMs();
  auto revoked = store_->jobs().CancelJob(job_id, now);
  if (!revoked) return false;
  for (const auto& r : *revoked) RetireAssignment(r.worker, r.episode_id, r.attempt);
  spdlog::info("job {} cancelled ({} running episodes revoked)", job_id, revoked->size());
  RetirePolicyOf(job_id);
  // Workers stop the job's running episodes when they see this.
  PublishEvents({{job_id, "cancelled", "", "job cancelled"}}, now);
  return true;
}

std::vector<WorkerView> FarmServer::Workers() const {
  const auto leased = store_->leases().LeasedCounts();
  std::lock_guard lock(mutex_);
  std::vector<WorkerView> out;
  const auto now = std::chrono::steady_clock::now();
  for (const auto& [id, w] : workers_) {
    WorkerView v;
    v.status = w.status;
    v.alive = w.alive;
    v.last_seen_s = std::chrono::duration<double>(now - w.last_seen).count();
    auto it = leased.find(id);
    v.leased = it == leased.end() ? 0 : it->second;
    out.push_back(std::move(v));
  }
  return out;
}

FarmServerStats FarmServer::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

void FarmServer::ExplainWaiting(api::JobProgress* p) const {
  if (p->terminal()) return;
  std::lock_guard lock(mutex_);
  for (const auto& [feature, count] : p->pending_needs) {
    const bool served = std::any_of(workers_.begin(), workers_.end(), [&f = feature](const auto& w) {
      const auto& features = w.second.status.features;
      return w.second.alive && std::find(features.begin(), features.end(), f) != features.end();
    });
    if (served) continue;
    p->waiting += (p->waiting.empty() ? "" : "; ") + std::to_string(count) + " episode(s) need a worker with " +
                  feature + ", and no connected worker has it" +
                  (feature == "ros" ? " (a worker offers ros where the ROS bridge was built and Debian's ROS is "
                                      "installed: scripts/install-deps.sh)"
                                    : "");
  }
}

void FarmServer::Loop() {
  while (!stop_) {
    try {
      Step();
    } catch (const std::exception& e) {
      // A failed step (database busy, disk full) is logged and retried: state is transactional.
      spdlog::error("server step failed: {}", e.what());
      std::this_thread::sleep_for(options_.tick);
    }
  }
}

void FarmServer::Step() {
  api::ServerBus::Inbox inbox = bus_->Wait(options_.tick, options_.ingest_batch);
  const std::int64_t now = NowMs();
  for (const auto& bad : inbox.bad_samples) spdlog::warn("dropped malformed sample: {}", bad);
  HandleStatuses(inbox.statuses, now);
  for (const auto& id : inbox.workers_gone) HandleGone(id, "worker gone (DDS liveliness lost)", now);
  for (const auto& id : inbox.workers_left) HandleGone(id, "worker left", now);
  if (!inbox.results.empty()) HandleResults(inbox.results, now);

  // Silent workers and expired leases, at most once per tick however busy the inbox is.
  const auto steady_now = std::chrono::steady_clock::now();
  if (steady_now - last_periodic_ >= options_.tick) {
    last_periodic_ = steady_now;
    std::vector<std::string> silent;
    {
      std::lock_guard lock(mutex_);
      for (const auto& [id, w] : workers_) {
        if (w.alive && steady_now - w.last_seen > options_.worker_timeout) silent.push_back(id);
      }
    }
    for (const auto& id : silent) HandleGone(id, "worker gone (no heartbeat)", now);
    HandleReleased(store_->leases().ExpireLeases(now), now);
  }
  Assign(now);
}

void FarmServer::HandleStatuses(const std::vector<api::WorkerStatus>& statuses,
                                std::int64_t now_ms) {
  // Heartbeats renew exactly the attempts a worker lists as running. Renewals are written at
  // most every quarter lease per worker (or when the list changes), all in one transaction:
  // a farm of many workers must not cost one fsync per heartbeat.
  std::map<std::string, std::vector<api::EpisodeRef>> renew;
  const auto now = std::chrono::steady_clock::now();
  for (const auto& s : statuses) {
    if (s.protocol != api::kFarmProtocolVersion) {
      spdlog::warn("worker {} speaks protocol {}, this server {}: ignored", s.worker_id,
                   s.protocol, api::kFarmProtocolVersion);
      continue;
    }
    bool is_new = false;
    {
      std::lock_guard lock(mutex_);
      auto [it, inserted] = workers_.try_emplace(s.worker_id);
      Worker& w = it->second;
      is_new = inserted || !w.alive;
      w.status = s;
      w.last_seen = now;
      w.alive = true;
      if (is_new || s.running != w.renewed || now - w.last_renewal >= options_.lease / 4) {
        w.last_renewal = now;
        w.renewed = s.running;
        renew[s.worker_id] = s.running;
      }
    }
    if (is_new) {
      store_->workers().RecordWorker(s, now_ms);
      spdlog::info("worker {} on {} (pid {}): {} slots", s.worker_id, s.host, s.pid, s.slots);
    }
  }
  store_->leases().RenewLeases(renew, now_ms + options_.lease.count());
}

void FarmServer::HandleGone(const std::string& worker_id, const std::string& reason,
                            std::int64_t now_ms) {
  {
    std::lock_guard lock(mutex_);
    auto it = workers_.find(worker_id);
    if (it == workers_.end() || !it->second.alive) return;
    it->second.alive = false;
  }
  const auto released = store_->leases().ReleaseWorker(worker_id, reason, now_ms);
  if (released.empty()) {
    spdlog::info("worker {}: {}", worker_id, reason);
  } else {
    spdlog::warn("{}: {} ({} leases re-queued)", worker_id, reason, released.size());
  }
  HandleReleased(released, now_ms);
}

void FarmServer::HandleReleased(const std::vector<ReleasedLease>& released, std::int64_t now_ms) {
  std::vector<PendingEvent> events;
  for (const auto& r : released) {
    RetireAssignment(r.worker, r.episode_id, r.attempt);
    events.push_back({r.job_id, r.failed ? "episode_failed" : "requeued", r.episode_id, r.reason});
  }
  PublishEvents(events, now_ms);
  if (!released.empty()) {
    std::lock_guard lock(mutex_);
    stats_.leases_lost += released.size();
  }
}

void FarmServer::PublishPolicy(const std::string& hash) {
  const auto json = store_->collect().Policy(hash);
  if (!json) throw std::invalid_argument("policy sha256:" + hash + ": not stored on this server");
  bus_->Publish(api::PolicyBlob{hash, *json});
}

// A finished collection job's policy leaves the durable history unless a running job flies it,
// so late-joining workers are not sent every policy a long training ever used.
void FarmServer::RetirePolicyOf(const std::string& job_id) {
  const std::string hash = CollectionHash(job_id);
  if (hash.empty() || store_->collect().ActivePolicies().count(hash)) return;
  try {
    bus_->Retire(api::PolicyBlob{hash, ""});
  } catch (const std::exception&) {
    // Not in this server's history (published before a restart).
  }
}

std::string FarmServer::CollectionHash(const std::string& job_id) {
  {
    std::lock_guard lock(mutex_);
    if (auto it = collect_hash_.find(job_id); it != collect_hash_.end()) return it->second;
  }
  const auto c = store_->collect().Collection(job_id);
  std::lock_guard lock(mutex_);
  return collect_hash_[job_id] = c ? c->policy_hash : std::string();
}

std::size_t ResultPayloadBytes(const api::ResultMessage& m) {
  const api::TimeSeries& s = m.result.series;
  std::size_t doubles = s.t.size() + 3 * s.position.size() + 3 * s.velocity.size() + s.eci.size() +
                        s.f_per.size() + s.f_col.size() + s.f_dif.size() + s.res.size() +
                        s.utilisation.size();
  std::size_t bytes = doubles * sizeof(double) + m.error.size();
  for (const auto& e : m.result.events) bytes += sizeof(double) + e.kind.size() + e.detail.size();
  return bytes;
}

void FarmServer::HandleResults(const std::vector<api::ResultMessage>& input,
                               std::int64_t now_ms) {
  std::vector<api::ResultMessage> results = input;
  for (api::ResultMessage& m : results) {
    // Above a size limit: the attempt's error, nothing of it stored.
    const std::size_t result_bytes = ResultPayloadBytes(m);
    std::string refused;
    if (result_bytes > options_.max_result_bytes) {
      refused = "result of " + std::to_string(result_bytes) + " bytes, above the server's limit of " +
                std::to_string(options_.max_result_bytes) + " (enavi serve --max-result-bytes)";
    } else if (m.rollout.size() > options_.max_rollout_bytes) {
      refused = "rollout of " + std::to_string(m.rollout.size()) +
                " bytes, above the server's limit of " + std::to_string(options_.max_rollout_bytes) +
                " (enavi serve --max-rollout-bytes)";
    }
    if (!refused.empty()) {
      spdlog::warn("refused {} attempt {} from worker {}: {}", m.episode_id, m.attempt, m.worker_id,
                   refused);
      m.status = api::ResultStatus::kError;
      m.error = refused;
      m.result = api::EpisodeResult{};
      m.rollout.clear();
      std::lock_guard lock(mutex_);
      ++stats_.oversized;
      continue;
    }
    // A rollout that does not decode is the episode's error, not data.
    if (m.rollout.empty()) continue;
    try {
      navstack::rl::CheckRolloutBlob(m.rollout, "rollout of " + m.episode_id);
    } catch (const std::exception& e) {
      m.status = api::ResultStatus::kError;
      m.error = e.what();
      m.rollout.clear();
    }
  }
  // One transaction for the whole batch, then the acks: a result is acknowledged only once it
  // is durable.
  const std::vector<IngestOutcome> outcomes = store_->ingest().Ingest(results, now_ms);
  {
    // Counted before the acks go out, so whoever sees an ack also sees it counted.
    std::lock_guard lock(mutex_);
    stats_.results_received += results.size();
    for (const IngestOutcome& o : outcomes) {
      if (o.ack == api::AckStatus::kStored) ++stats_.results_stored;
      if (o.ack == api::AckStatus::kDuplicate) ++stats_.duplicates;
    }
  }
  std::vector<PendingEvent> events;
  for (std::size_t i = 0; i < results.size(); ++i) {
    const api::ResultMessage& m = results[i];
    const IngestOutcome& o = outcomes[i];
    bus_->Publish(api::ResultAck{m.worker_id, m.episode_id, m.attempt, o.ack, o.detail});
    if (o.ack == api::AckStatus::kStored || o.ack == api::AckStatus::kRecorded) {
      RetireAssignment(m.worker_id, m.episode_id, m.attempt);
    }
    if (m.status == api::ResultStatus::kError && o.ack == api::AckStatus::kRecorded) {
      spdlog::warn("{} attempt {} on {}: {}", m.episode_id, m.attempt, m.worker_id, m.error);
    }
    if (m.status == api::ResultStatus::kOk && o.ack == api::AckStatus::kRecorded) {
      spdlog::warn("{} attempt {} on {}: {}", m.episode_id, m.attempt, m.worker_id, o.detail);
    }
    if (!o.event.empty()) {
      events.push_back({o.job_id, o.event, m.episode_id,
                        m.status == api::ResultStatus::kOk ? "" : m.error});
    }
  }
  PublishEvents(events, now_ms);
}

void FarmServer::Assign(std::int64_t now_ms) {
  std::vector<std::pair<std::string, api::WorkerStatus>> candidates;
  {
    std::lock_guard lock(mutex_);
    for (const auto& [id, w] : workers_) {
      if (w.alive && !w.status.draining && w.status.slots > 0) candidates.emplace_back(id, w.status);
    }
  }
  if (candidates.empty()) return;
  const auto leased = store_->leases().LeasedCounts();
  // Least-loaded workers first, so a job spreads over the farm.
  std::sort(candidates.begin(), candidates.end(), [&](const auto& a, const auto& b) {
    auto load = [&](const std::string& id) {
      auto it = leased.find(id);
      return it == leased.end() ? 0 : it->second;
    };
    return load(a.first) < load(b.first);
  });
  const std::int64_t deadline = now_ms + options_.lease.count();
  for (const auto& [id, status] : candidates) {
    // Free = slots minus our leases, but never more than the worker itself reports: after a
    // server restart or a lost lease it may still run episodes this database no longer gives it.
    auto it = leased.find(id);
    const int free =
        std::min(status.slots - (it == leased.end() ? 0 : it->second), status.free_slots);
    if (free <= 0) continue;
    const auto leases =
        store_->leases().LeaseEpisodes(id, free, {status.boards, status.clocks, status.features}, deadline, now_ms);
    for (const Lease& l : leases) {
      bus_->Publish(api::Assignment{id, l.episode_id, l.attempt, l.job_id, l.deadline_ms,
                                    options_.lease.count(), l.spec, CollectionHash(l.job_id)});
    }
    if (!leases.empty()) {
      std::lock_guard lock(mutex_);
      stats_.assignments += leases.size();
    }
  }
}

void FarmServer::PublishEvents(const std::vector<PendingEvent>& events, std::int64_t now_ms) {
  // Progress counts once per job and batch: a count per event would scan the job per result.
  std::map<std::string, api::JobProgress> progress;
  for (const auto& pe : events) {
    if (!progress.count(pe.job_id)) {
      progress[pe.job_id] = store_->jobs().Progress(pe.job_id, now_ms).value_or(api::JobProgress{});
    }
  }
  for (const auto& pe : events) {
    const api::JobProgress& p = progress[pe.job_id];
    bus_->Publish(api::JobEvent{pe.job_id, pe.kind, pe.episode_id, p.done, p.failed, p.total,
                                pe.message, now_ms});
  }
  for (const auto& [job_id, p] : progress) {
    if (p.state != "done") continue;
    {
      std::lock_guard lock(mutex_);
      if (!finished_announced_.insert(job_id).second) continue;
    }
    spdlog::info("job {} finished: {} done, {} failed of {}", job_id, p.done, p.failed, p.total);
    bus_->Publish(api::JobEvent{job_id, "finished", "", p.done, p.failed, p.total, "", now_ms});
    RetirePolicyOf(job_id);
  }
}

void FarmServer::RetireAssignment(const std::string& worker_id, const std::string& episode_id,
                                  int attempt) {
  api::Assignment key;
  key.worker_id = worker_id;
  key.episode_id = episode_id;
  key.attempt = attempt;
  try {
    bus_->Retire(key);
  } catch (const std::exception&) {
    // Not in this server's history (assigned before a restart, or by the worker's own retry).
  }
}

}  // namespace enavi::server
