#include "server/store/jobs.h"

#include <iomanip>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "server/store/connection.h"
#include "server/store/schema.h"

namespace enavi::server {
namespace {

std::string NewJobId() {
  std::random_device rd;  // ids only: never affects a result
  std::ostringstream os;
  os << "j" << std::hex << std::setfill('0') << std::setw(8) << rd() << std::setw(4)
     << (rd() & 0xffff);
  return os.str();
}

std::string EpisodeId(const std::string& job_id, std::size_t index) {
  std::ostringstream os;
  os << job_id << "-" << std::setfill('0') << std::setw(5) << index;
  return os.str();
}

}  // namespace

std::string JobStore::CreateJob(const std::string& name, const std::string& spec_yaml,
                                const std::vector<api::EpisodeSpec>& episodes, std::int64_t now_ms,
                                const JobMeta& meta, const std::optional<CollectionInfo>& collect) {
  if (episodes.empty()) throw std::invalid_argument("job '" + name + "': no episodes");
  std::lock_guard lock(c_.mutex);
  Database& db = c_.db;
  Transaction tx(db);
  std::string job_id = NewJobId();
  db.Prepare("INSERT INTO jobs (id, name, spec_yaml, state, total, created_ms) "
             "VALUES (?, ?, ?, 'running', ?, ?)")
      .Bind(1, job_id).Bind(2, name).Bind(3, spec_yaml)
      .Bind(4, static_cast<std::int64_t>(episodes.size())).Bind(5, now_ms).Run();
  db.Prepare("UPDATE jobs SET provenance_json = ? WHERE id = ?")
      .Bind(1, nlohmann::json(meta.provenance).dump()).Bind(2, job_id).Run();
  Statement& label = db.Prepare("INSERT INTO job_labels (job_id, key, value) VALUES (?, ?, ?)");
  for (const auto& [key, value] : meta.labels) label.Reset().Bind(1, job_id).Bind(2, key).Bind(3, value).Run();
  Statement& insert = db.Prepare(
      "INSERT INTO episodes (id, job_id, idx, spec_json, board, world, method, seed, clock, "
      "state, updated_ms, needs) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, 'pending', ?, ?)");
  for (std::size_t i = 0; i < episodes.size(); ++i) {
    const api::EpisodeSpec& e = episodes[i];
    insert.Reset()
        .Bind(1, EpisodeId(job_id, i)).Bind(2, job_id).Bind(3, static_cast<std::int64_t>(i))
        .Bind(4, nlohmann::json(e).dump()).Bind(5, e.board).Bind(6, e.world).Bind(7, e.method)
        .Bind(8, static_cast<std::int64_t>(e.seed)).Bind(9, e.clock).Bind(10, now_ms)
        .Bind(11, std::string(e.ros ? "ros" : "")).Run();
  }
  if (collect) {
    db.Prepare("INSERT INTO collect_jobs (job_id, policy_hash, sample) VALUES (?, ?, ?)")
        .Bind(1, job_id).Bind(2, collect->policy_hash).Bind(3, collect->sample ? 1 : 0).Run();
  }
  tx.Commit();
  return job_id;
}

api::JobProgress JobStore::ProgressLocked(const std::string& job_id, std::int64_t now_ms) {
  Database& db = c_.db;
  api::JobProgress p;
  Statement& job = db.Prepare(
      "SELECT id, name, state, total, created_ms, started_ms, finished_ms FROM jobs WHERE id = ?");
  job.Bind(1, job_id);
  if (!job.Step()) return p;
  p.id = job.Text(0);
  p.name = job.Text(1);
  p.state = job.Text(2);
  p.total = static_cast<int>(job.Int(3));
  p.created_ms = job.Int(4);
  p.started_ms = job.IsNull(5) ? 0 : job.Int(5);
  p.finished_ms = job.IsNull(6) ? 0 : job.Int(6);
  p.now_ms = now_ms;
  job.Reset();
  if (HasColumn(db, "jobs", "provenance_json")) {
    Statement& prov = db.Prepare("SELECT provenance_json FROM jobs WHERE id = ?");
    prov.Bind(1, job_id);
    if (prov.Step()) {
      p.provenance = nlohmann::json::parse(prov.Text(0)).get<std::map<std::string, std::string>>();
    }
    prov.Reset();
  }
  if (HasColumn(db, "job_labels", "key")) {
    Statement& labels = db.Prepare("SELECT key, value FROM job_labels WHERE job_id = ?");
    labels.Bind(1, job_id);
    while (labels.Step()) p.labels[labels.Text(0)] = labels.Text(1);
  }
  Statement& counts =
      db.Prepare("SELECT state, COUNT(*) FROM episodes WHERE job_id = ? GROUP BY state");
  counts.Bind(1, job_id);
  while (counts.Step()) {
    const std::string state = counts.Text(0);
    const int n = static_cast<int>(counts.Int(1));
    if (state == "pending") p.pending = n;
    if (state == "leased") p.leased = n;
    if (state == "done") p.done = n;
    if (state == "failed") p.failed = n;
    if (state == "cancelled") p.cancelled = n;
  }
  if (p.pending > 0 && HasColumn(db, "episodes", "needs")) {
    Statement& needs = db.Prepare(
        "SELECT needs, COUNT(*) FROM episodes WHERE job_id = ? AND state = 'pending' AND needs != '' GROUP BY needs");
    needs.Bind(1, job_id);
    while (needs.Step()) p.pending_needs[needs.Text(0)] = static_cast<int>(needs.Int(1));
  }
  Statement& errors = db.Prepare(
      "SELECT id, last_error FROM episodes WHERE job_id = ? AND state = 'failed' "
      "ORDER BY updated_ms DESC LIMIT 5");
  errors.Bind(1, job_id);
  while (errors.Step()) p.errors.push_back(errors.Text(0) + ": " + errors.Text(1));
  return p;
}

std::optional<api::JobProgress> JobStore::Progress(const std::string& job_id, std::int64_t now_ms) {
  std::lock_guard lock(c_.mutex);
  api::JobProgress p = ProgressLocked(job_id, now_ms);
  if (p.id.empty()) return std::nullopt;
  return p;
}

std::vector<api::JobProgress> JobStore::ListJobs(std::int64_t now_ms) { return ListJobs(now_ms, {}); }

std::vector<api::JobProgress> JobStore::ListJobs(std::int64_t now_ms,
                                                 const std::map<std::string, std::string>& labels) {
  std::lock_guard lock(c_.mutex);
  Database& db = c_.db;
  std::vector<std::string> ids;
  if (labels.empty()) {
    Statement& list = db.Prepare("SELECT id FROM jobs ORDER BY created_ms, rowid");
    while (list.Step()) ids.push_back(list.Text(0));
  } else if (HasColumn(db, "job_labels", "key")) {
    // Jobs matching every filter: one row per matching label, so the count must be all of them.
    Statement& list = db.Prepare(
        "SELECT j.id FROM jobs j JOIN job_labels l ON l.job_id = j.id "
        "WHERE (l.key, l.value) IN (SELECT value ->> '$[0]', value ->> '$[1]' FROM json_each(?)) "
        "GROUP BY j.id HAVING COUNT(*) = ? ORDER BY j.created_ms, j.rowid");
    nlohmann::json pairs = nlohmann::json::array();
    for (const auto& [k, v] : labels) pairs.push_back({k, v});
    list.Bind(1, pairs.dump()).Bind(2, static_cast<std::int64_t>(labels.size()));
    while (list.Step()) ids.push_back(list.Text(0));
  }
  std::vector<api::JobProgress> out;
  for (const auto& id : ids) out.push_back(ProgressLocked(id, now_ms));
  return out;
}

std::optional<std::vector<ReleasedLease>> JobStore::CancelJob(const std::string& job_id,
                                                              std::int64_t now_ms) {
  std::lock_guard lock(c_.mutex);
  Database& db = c_.db;
  Transaction tx(db);
  Statement& job = db.Prepare("SELECT state FROM jobs WHERE id = ?");
  job.Bind(1, job_id);
  if (!job.Step()) return std::nullopt;
  const std::string state = job.Text(0);
  job.Reset();
  std::vector<ReleasedLease> revoked;
  if (state != "running") return revoked;  // done or already cancelled: nothing to do
  Statement& leased = db.Prepare(
      "SELECT id, lease_owner, attempts FROM episodes WHERE job_id = ? AND state = 'leased'");
  leased.Bind(1, job_id);
  while (leased.Step()) {
    revoked.push_back({leased.Text(0), job_id, leased.Text(1), static_cast<int>(leased.Int(2)),
                       false, "job cancelled"});
  }
  db.Prepare("UPDATE episodes SET state = 'cancelled', lease_owner = NULL, "
             "lease_deadline_ms = NULL, last_error = 'job cancelled', updated_ms = ? "
             "WHERE job_id = ? AND state IN ('pending', 'leased')")
      .Bind(1, now_ms).Bind(2, job_id).Run();
  db.Prepare("UPDATE jobs SET state = 'cancelled', finished_ms = ? WHERE id = ?")
      .Bind(1, now_ms).Bind(2, job_id).Run();
  tx.Commit();
  return revoked;
}

std::vector<EpisodeInfo> JobStore::Episodes(const std::string& job_id) {
  std::lock_guard lock(c_.mutex);
  std::vector<EpisodeInfo> out;
  Statement& q = c_.db.Prepare(
      "SELECT id, idx, state, attempts, lease_owner, lease_deadline_ms, last_error, spec_json "
      "FROM episodes WHERE job_id = ? ORDER BY idx");
  q.Bind(1, job_id);
  while (q.Step()) {
    EpisodeInfo e;
    e.id = q.Text(0);
    e.index = static_cast<int>(q.Int(1));
    e.state = q.Text(2);
    e.attempts = static_cast<int>(q.Int(3));
    e.lease_owner = q.Text(4);
    e.lease_deadline_ms = q.IsNull(5) ? 0 : q.Int(5);
    e.last_error = q.Text(6);
    e.spec = nlohmann::json::parse(q.Text(7)).get<api::EpisodeSpec>();
    out.push_back(std::move(e));
  }
  return out;
}

void FinishJobsIfComplete(Database& db, const std::vector<std::string>& job_ids, std::int64_t now_ms) {
  const std::set<std::string> unique(job_ids.begin(), job_ids.end());
  Statement& open = db.Prepare(
      "SELECT COUNT(*) FROM episodes WHERE job_id = ? AND state IN ('pending', 'leased')");
  Statement& finish = db.Prepare(
      "UPDATE jobs SET state = 'done', finished_ms = ? WHERE id = ? AND state = 'running'");
  for (const auto& id : unique) {
    open.Reset().Bind(1, id);
    open.Step();
    const std::int64_t remaining = open.Int(0);
    open.Reset();
    if (remaining == 0) finish.Reset().Bind(1, now_ms).Bind(2, id).Run();
  }
}

}  // namespace enavi::server
