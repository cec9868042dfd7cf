// The collection-job tables (collect_store.h); their schema is in schema.cc.
#include "server/store/collect_store.h"
#include "server/store/connection.h"

namespace enavi::server {

void CollectStore::PutPolicy(const std::string& hash, const std::string& json, std::int64_t now_ms) {
  std::lock_guard lock(c_.mutex);
  c_.db.Prepare("INSERT OR IGNORE INTO policies (hash, json, created_ms) VALUES (?, ?, ?)")
      .Bind(1, hash).Bind(2, json).Bind(3, now_ms).Run();
}

std::optional<std::string> CollectStore::Policy(const std::string& hash) {
  std::lock_guard lock(c_.mutex);
  Statement& q = c_.db.Prepare("SELECT json FROM policies WHERE hash = ?");
  q.Bind(1, hash);
  std::optional<std::string> out;
  if (q.Step()) out = q.Text(0);
  q.Reset();
  return out;
}

std::optional<CollectionInfo> CollectStore::Collection(const std::string& job_id) {
  std::lock_guard lock(c_.mutex);
  Statement& q = c_.db.Prepare("SELECT policy_hash, sample FROM collect_jobs WHERE job_id = ?");
  q.Bind(1, job_id);
  std::optional<CollectionInfo> out;
  if (q.Step()) out = CollectionInfo{q.Text(0), q.Int(1) != 0};
  q.Reset();
  return out;
}

std::map<std::string, std::string> CollectStore::ActivePolicies() {
  std::lock_guard lock(c_.mutex);
  Statement& q = c_.db.Prepare(
      "SELECT DISTINCT p.hash, p.json FROM collect_jobs c JOIN jobs j ON j.id = c.job_id "
      "JOIN policies p ON p.hash = c.policy_hash WHERE j.state = 'running'");
  std::map<std::string, std::string> out;
  while (q.Step()) out[q.Text(0)] = q.Text(1);
  q.Reset();
  return out;
}

std::vector<api::StoredRollout> CollectStore::Rollouts(const std::string& job_id) {
  std::lock_guard lock(c_.mutex);
  Statement& q = c_.db.Prepare(
      "SELECT r.episode_id, e.idx, r.attempt, s.worker, s.board, s.scenario, s.world, s.seed, "
      "r.policy_hash, s.success, s.collided, s.flight_time_s, s.nav_cpu_util_pct, r.data "
      "FROM rollouts r JOIN episodes e ON e.id = r.episode_id "
      "JOIN results s ON s.episode_id = r.episode_id WHERE r.job_id = ? ORDER BY e.idx");
  q.Bind(1, job_id);
  std::vector<api::StoredRollout> out;
  while (q.Step()) {
    api::StoredRollout r;
    r.episode_id = q.Text(0);
    r.index = static_cast<int>(q.Int(1));
    r.attempt = static_cast<int>(q.Int(2));
    r.worker = q.Text(3);
    r.board = q.Text(4);
    r.scenario = q.Text(5);
    r.world = q.Text(6);
    r.seed = static_cast<std::uint64_t>(q.Int(7));
    r.policy_hash = q.Text(8);
    r.success = q.Int(9) != 0;
    r.collided = q.Int(10) != 0;
    r.flight_time_s = q.Double(11);
    r.nav_cpu_util_pct = q.Double(12);
    const std::vector<std::uint8_t> blob = q.Blob(13);
    r.rollout.assign(blob.begin(), blob.end());
    out.push_back(std::move(r));
  }
  q.Reset();
  return out;
}

}  // namespace enavi::server
