#include "server/store/leases.h"

#include <algorithm>

#include <nlohmann/json.hpp>

#include "server/store/connection.h"
#include "server/store/jobs.h"

namespace enavi::server {
namespace {

bool Accepts(const std::vector<std::string>& list, const std::string& value) {
  return list.empty() || std::find(list.begin(), list.end(), value) != list.end();
}

}  // namespace

std::vector<Lease> LeaseStore::LeaseEpisodes(const std::string& worker_id, int count,
                                             const WorkerCapabilities& caps, std::int64_t deadline_ms,
                                             std::int64_t now_ms) {
  std::vector<Lease> leases;
  if (count <= 0) return leases;
  std::lock_guard lock(c_.mutex);
  Database& db = c_.db;
  Transaction tx(db);
  // Oldest job first, then episode order. Capability filters are applied here rather than in
  // SQL so the statement stays cacheable; scanning stops once `count` are found.
  Statement& pending = db.Prepare(
      "SELECT e.id, e.job_id, e.attempts, e.spec_json, e.board, e.clock, e.needs FROM episodes e "
      "JOIN jobs j ON j.id = e.job_id WHERE e.state = 'pending' AND j.state = 'running' "
      "ORDER BY j.created_ms, j.rowid, e.idx");
  while (static_cast<int>(leases.size()) < count && pending.Step()) {
    if (!Accepts(caps.boards, pending.Text(4)) || !Accepts(caps.clocks, pending.Text(5))) continue;
    // A need is a feature the worker must list (an empty feature list is not "any" here).
    if (const std::string needs = pending.Text(6);
        !needs.empty() && std::find(caps.features.begin(), caps.features.end(), needs) == caps.features.end())
      continue;
    Lease l;
    l.episode_id = pending.Text(0);
    l.job_id = pending.Text(1);
    l.attempt = static_cast<int>(pending.Int(2)) + 1;
    l.worker = worker_id;
    l.deadline_ms = deadline_ms;
    l.spec = nlohmann::json::parse(pending.Text(3)).get<api::EpisodeSpec>();
    leases.push_back(std::move(l));
  }
  pending.Reset();
  Statement& update = db.Prepare(
      "UPDATE episodes SET state = 'leased', attempts = ?, lease_owner = ?, "
      "lease_deadline_ms = ?, updated_ms = ? WHERE id = ? AND state = 'pending'");
  Statement& started = db.Prepare(
      "UPDATE jobs SET started_ms = ? WHERE id = ? AND started_ms IS NULL");
  for (const Lease& l : leases) {
    update.Reset().Bind(1, l.attempt).Bind(2, worker_id).Bind(3, deadline_ms).Bind(4, now_ms)
        .Bind(5, l.episode_id).Run();
    started.Reset().Bind(1, now_ms).Bind(2, l.job_id).Run();
  }
  tx.Commit();
  return leases;
}

int LeaseStore::RenewLeases(const std::string& worker_id, const std::vector<api::EpisodeRef>& running,
                            std::int64_t deadline_ms) {
  return RenewLeases(std::map<std::string, std::vector<api::EpisodeRef>>{{worker_id, running}},
                     deadline_ms);
}

int LeaseStore::RenewLeases(const std::map<std::string, std::vector<api::EpisodeRef>>& running_by_worker,
                            std::int64_t deadline_ms) {
  const bool any = std::any_of(running_by_worker.begin(), running_by_worker.end(),
                               [](const auto& kv) { return !kv.second.empty(); });
  if (!any) return 0;
  std::lock_guard lock(c_.mutex);
  Database& db = c_.db;
  Transaction tx(db);
  Statement& renew = db.Prepare(
      "UPDATE episodes SET lease_deadline_ms = ? WHERE id = ? AND state = 'leased' "
      "AND lease_owner = ? AND attempts = ?");
  int renewed = 0;
  for (const auto& [worker_id, running] : running_by_worker) {
    for (const auto& ref : running) {
      renew.Reset().Bind(1, deadline_ms).Bind(2, ref.episode_id).Bind(3, worker_id)
          .Bind(4, ref.attempt).Run();
      renewed += static_cast<int>(db.Changes());
    }
  }
  tx.Commit();
  return renewed;
}

std::vector<ReleasedLease> LeaseStore::ReleaseWhere(const std::string& where, const std::string& arg,
                                                    std::int64_t value, const std::string& reason,
                                                    std::int64_t now_ms) {
  Database& db = c_.db;
  Transaction tx(db);
  std::vector<ReleasedLease> released;
  Statement& select = db.Prepare(
      "SELECT id, job_id, lease_owner, attempts FROM episodes WHERE state = 'leased' AND " + where);
  if (arg.empty()) {
    select.Bind(1, value);
  } else {
    select.Bind(1, arg);
  }
  while (select.Step()) {
    ReleasedLease r;
    r.episode_id = select.Text(0);
    r.job_id = select.Text(1);
    r.worker = select.Text(2);
    r.attempt = static_cast<int>(select.Int(3));
    r.failed = r.attempt >= c_.options.max_attempts;
    r.reason = reason + " (worker " + r.worker + ", attempt " + std::to_string(r.attempt) + ")";
    if (r.failed) {
      r.reason += "; gave up after " + std::to_string(r.attempt) + " attempts";
    }
    released.push_back(std::move(r));
  }
  select.Reset();
  Statement& update = db.Prepare(
      "UPDATE episodes SET state = ?, lease_owner = NULL, lease_deadline_ms = NULL, "
      "last_error = ?, updated_ms = ? WHERE id = ? AND state = 'leased'");
  std::vector<std::string> jobs;
  for (const auto& r : released) {
    update.Reset().Bind(1, r.failed ? "failed" : "pending").Bind(2, r.reason).Bind(3, now_ms)
        .Bind(4, r.episode_id).Run();
    if (r.failed) jobs.push_back(r.job_id);
  }
  FinishJobsIfComplete(db, jobs, now_ms);
  tx.Commit();
  return released;
}

std::vector<ReleasedLease> LeaseStore::ExpireLeases(std::int64_t now_ms) {
  std::lock_guard lock(c_.mutex);
  return ReleaseWhere("lease_deadline_ms < ?", "", now_ms, "lease expired", now_ms);
}

std::vector<Lease> LeaseStore::HeldLeases() {
  std::lock_guard lock(c_.mutex);
  std::vector<Lease> leases;
  Statement& q = c_.db.Prepare(
      "SELECT id, job_id, lease_owner, attempts, lease_deadline_ms, spec_json FROM episodes "
      "WHERE state = 'leased'");
  while (q.Step()) {
    Lease l;
    l.episode_id = q.Text(0);
    l.job_id = q.Text(1);
    l.worker = q.Text(2);
    l.attempt = static_cast<int>(q.Int(3));
    l.deadline_ms = q.Int(4);
    l.spec = nlohmann::json::parse(q.Text(5)).get<api::EpisodeSpec>();
    leases.push_back(std::move(l));
  }
  return leases;
}

std::vector<ReleasedLease> LeaseStore::ReleaseWorker(const std::string& worker_id,
                                                     const std::string& reason, std::int64_t now_ms) {
  std::lock_guard lock(c_.mutex);
  return ReleaseWhere("lease_owner = ?", worker_id, 0, reason, now_ms);
}

std::map<std::string, int> LeaseStore::LeasedCounts() {
  std::lock_guard lock(c_.mutex);
  std::map<std::string, int> counts;
  Statement& q = c_.db.Prepare(
      "SELECT lease_owner, COUNT(*) FROM episodes WHERE state = 'leased' GROUP BY lease_owner");
  while (q.Step()) counts[q.Text(0)] = static_cast<int>(q.Int(1));
  return counts;
}

bool LeaseStore::HoldsLease(const std::string& episode_id, int attempt, const std::string& worker_id) {
  std::lock_guard lock(c_.mutex);
  Statement& q = c_.db.Prepare(
      "SELECT 1 FROM episodes WHERE id = ? AND state = 'leased' AND attempts = ? "
      "AND lease_owner = ?");
  q.Bind(1, episode_id).Bind(2, attempt).Bind(3, worker_id);
  const bool held = q.Step();
  q.Reset();
  return held;
}

}  // namespace enavi::server
