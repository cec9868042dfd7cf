#include "server/store/schema.h"

#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "api/result_metrics.h"
#include "server/store/sqlite.h"

namespace enavi::server {
namespace {

// Schema version 1. Episode state is a small text enum; the result row keeps the flat result
// JSON plus the columns tables filter and group by.
constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS jobs (
  id          TEXT PRIMARY KEY,
  name        TEXT NOT NULL,
  spec_yaml   TEXT NOT NULL,
  state       TEXT NOT NULL CHECK (state IN ('running', 'done', 'cancelled')),
  total       INTEGER NOT NULL,
  created_ms  INTEGER NOT NULL,
  started_ms  INTEGER,
  finished_ms INTEGER
);
CREATE TABLE IF NOT EXISTS episodes (
  id                TEXT PRIMARY KEY,
  job_id            TEXT NOT NULL REFERENCES jobs(id),
  idx               INTEGER NOT NULL,
  spec_json         TEXT NOT NULL,
  board             TEXT NOT NULL,
  world             TEXT NOT NULL,
  method            TEXT NOT NULL,
  seed              INTEGER NOT NULL,
  clock             TEXT NOT NULL,
  state             TEXT NOT NULL
                    CHECK (state IN ('pending', 'leased', 'done', 'failed', 'cancelled')),
  attempts          INTEGER NOT NULL DEFAULT 0,
  lease_owner       TEXT,
  lease_deadline_ms INTEGER,
  last_error        TEXT,
  updated_ms        INTEGER NOT NULL,
  UNIQUE (job_id, idx)
);
CREATE INDEX IF NOT EXISTS episodes_by_state ON episodes(state, job_id);
CREATE INDEX IF NOT EXISTS episodes_by_owner ON episodes(lease_owner) WHERE state = 'leased';
CREATE TABLE IF NOT EXISTS results (
  episode_id          TEXT PRIMARY KEY REFERENCES episodes(id),
  job_id              TEXT NOT NULL,
  worker              TEXT NOT NULL,
  attempt             INTEGER NOT NULL,
  board               TEXT NOT NULL,
  scenario            TEXT NOT NULL,
  world               TEXT NOT NULL,
  method              TEXT NOT NULL,
  seed                INTEGER NOT NULL,
  clock               TEXT NOT NULL,
  success             INTEGER NOT NULL,
  collided            INTEGER NOT NULL,
  timed_out           INTEGER NOT NULL,
  end_reason          TEXT NOT NULL,
  flight_time_s       REAL NOT NULL,
  path_length_m       REAL NOT NULL,
  velocity_mean_mps   REAL NOT NULL,
  velocity_std_mps    REAL NOT NULL,
  nav_cpu_util_pct    REAL NOT NULL,
  deadline_miss_ratio REAL NOT NULL,
  replans             INTEGER NOT NULL,
  wall_time_s         REAL NOT NULL,
  received_ms         INTEGER NOT NULL,
  result_json         TEXT NOT NULL,
  series              BLOB NOT NULL
);
CREATE INDEX IF NOT EXISTS results_by_job ON results(job_id, board, scenario, method, seed);
)sql";

// Collection jobs (RL rollouts): added tables only, so an existing database gains them on open.
// A rollout row is written in the transaction that stores its episode's result, keyed by episode:
// exactly one per done episode.
constexpr const char* kCollectSchema = R"sql(
CREATE TABLE IF NOT EXISTS policies (
  hash       TEXT PRIMARY KEY,
  json       TEXT NOT NULL,
  created_ms INTEGER NOT NULL
);
CREATE TABLE IF NOT EXISTS collect_jobs (
  job_id      TEXT PRIMARY KEY REFERENCES jobs(id),
  policy_hash TEXT NOT NULL REFERENCES policies(hash),
  sample      INTEGER NOT NULL
);
CREATE TABLE IF NOT EXISTS rollouts (
  episode_id  TEXT PRIMARY KEY REFERENCES episodes(id),
  job_id      TEXT NOT NULL,
  attempt     INTEGER NOT NULL,
  policy_hash TEXT NOT NULL,
  steps       INTEGER NOT NULL,
  data        BLOB NOT NULL
);
CREATE INDEX IF NOT EXISTS rollouts_by_job ON rollouts(job_id);
)sql";

// Additions since schema version 1, all additive so an existing database opens unchanged:
// labels (queryable), the workers seen (host, version, calibration: provenance of results).
// Columns added to existing tables are in Migrate.
constexpr const char* kSchemaAdditions = R"sql(
CREATE TABLE IF NOT EXISTS job_labels (
  job_id TEXT NOT NULL REFERENCES jobs(id),
  key    TEXT NOT NULL,
  value  TEXT NOT NULL,
  PRIMARY KEY (job_id, key)
);
CREATE INDEX IF NOT EXISTS job_labels_by_value ON job_labels(key, value, job_id);
CREATE INDEX IF NOT EXISTS results_unsuccessful ON results(job_id) WHERE success = 0;
CREATE TABLE IF NOT EXISTS workers (
  worker_id      TEXT PRIMARY KEY,
  host           TEXT NOT NULL,
  version        TEXT NOT NULL,
  calibration_id TEXT NOT NULL,
  slots          INTEGER NOT NULL,
  boards         TEXT NOT NULL,
  first_seen_ms  INTEGER NOT NULL,
  last_seen_ms   INTEGER NOT NULL
);
)sql";

void Migrate(Database& db) {
  if (!HasColumn(db, "jobs", "provenance_json")) {
    db.Exec("ALTER TABLE jobs ADD COLUMN provenance_json TEXT NOT NULL DEFAULT '{}'");
  }
  // What a worker needs besides the board and clock to run an episode: "ros" for a ROS method
  // (api::WorkerStatus::features); '' for the rest.
  if (!HasColumn(db, "episodes", "needs")) db.Exec("ALTER TABLE episodes ADD COLUMN needs TEXT NOT NULL DEFAULT ''");
  // The flat metrics of each result, so aggregates read ~1 kB per row instead of the record
  // with its notes and events. Rows stored before the column existed are filled in here.
  if (!HasColumn(db, "results", "metrics_json")) {
    db.Exec("ALTER TABLE results ADD COLUMN metrics_json TEXT");
  }
  std::vector<std::pair<std::string, std::string>> missing;
  Statement& old = db.Prepare("SELECT episode_id, result_json FROM results WHERE metrics_json IS NULL");
  while (old.Step()) {
    missing.emplace_back(old.Text(0),
                         nlohmann::json(api::ResultMetrics(nlohmann::json::parse(old.Text(1)))).dump());
  }
  old.Reset();
  Statement& fill = db.Prepare("UPDATE results SET metrics_json = ? WHERE episode_id = ?");
  for (const auto& [id, metrics] : missing) fill.Reset().Bind(1, metrics).Bind(2, id).Run();
  // Per cell and metric running sums, kept by every ingest (ingest.cc), so a job page reads ~1
  // row per cell and metric instead of every result. Built from the results once.
  if (!HasColumn(db, "cell_metrics", "n")) {
    db.Exec(R"sql(
CREATE TABLE cell_metrics (
  job_id TEXT NOT NULL, board TEXT NOT NULL, scenario TEXT NOT NULL, method TEXT NOT NULL,
  name TEXT NOT NULL,
  n INTEGER NOT NULL, sum REAL NOT NULL, sum_sq REAL NOT NULL, min REAL NOT NULL, max REAL NOT NULL,
  n_ok INTEGER NOT NULL, sum_ok REAL NOT NULL, sum_sq_ok REAL NOT NULL, min_ok REAL, max_ok REAL,
  PRIMARY KEY (job_id, board, scenario, method, name)
);
INSERT INTO cell_metrics
SELECT r.job_id, r.board, r.scenario, r.method, m.key, COUNT(*), SUM(m.value), SUM(m.value * m.value),
       MIN(m.value), MAX(m.value), SUM(r.success), SUM(r.success * m.value),
       SUM(r.success * m.value * m.value), MIN(CASE WHEN r.success THEN m.value END),
       MAX(CASE WHEN r.success THEN m.value END)
FROM results r, json_each(r.metrics_json) m WHERE m.type IN ('integer', 'real', 'true', 'false')
GROUP BY r.job_id, r.board, r.scenario, r.method, m.key;
)sql");
  }
}

}  // namespace

bool HasColumn(Database& db, const std::string& table, const std::string& column) {
  Statement& q = db.Prepare("SELECT 1 FROM pragma_table_info(?) WHERE name = ?");
  q.Bind(1, table).Bind(2, column);
  const bool found = q.Step();
  q.Reset();
  return found;
}

void CheckSchema(Database& db, const std::string& path, bool read_only) {
  Statement& version = db.Prepare("PRAGMA user_version");
  version.Step();
  const std::int64_t found = version.Int(0);
  version.Reset();
  if (found > kStoreSchemaVersion) {
    throw StoreError("database '" + path + "' has schema version " + std::to_string(found) +
                     ", newer than this build's " + std::to_string(kStoreSchemaVersion));
  }
  if (read_only && !HasColumn(db, "jobs", "id")) {
    throw StoreError("database '" + path + "' is not an enavi farm database");
  }
}

void CreateOrMigrateSchema(Database& db) {
  Transaction tx(db);
  db.Exec(kSchema);
  db.Exec(kCollectSchema);
  db.Exec(kSchemaAdditions);
  Migrate(db);
  db.Exec("PRAGMA user_version = " + std::to_string(kStoreSchemaVersion));
  tx.Commit();
}

}  // namespace enavi::server
