#include "server/store/store.h"

#include <cmath>
#include <cstring>
#include <tuple>
#include <iomanip>
#include <random>
#include <set>
#include <sstream>

#include "api/job_spec.h"
#include "api/result_metrics.h"
#include "server/store/sqlite.h"
#include "worlds/generators.h"

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
// Columns added to existing tables are in Store::Migrate.
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

// Adds one result's metrics (?6, metrics_json) to its cell's running sums; ?5 = success.
constexpr const char* kAddCellMetrics = R"sql(
INSERT INTO cell_metrics (job_id, board, scenario, method, name, n, sum, sum_sq, min, max,
                          n_ok, sum_ok, sum_sq_ok, min_ok, max_ok)
SELECT ?1, ?2, ?3, ?4, m.key, 1, m.value, m.value * m.value, m.value, m.value,
       ?5, ?5 * m.value, ?5 * m.value * m.value, CASE WHEN ?5 THEN m.value END,
       CASE WHEN ?5 THEN m.value END
FROM json_each(?6) m WHERE m.type IN ('integer', 'real', 'true', 'false')
ON CONFLICT (job_id, board, scenario, method, name) DO UPDATE SET
  n = n + 1, sum = sum + excluded.sum, sum_sq = sum_sq + excluded.sum_sq,
  min = MIN(min, excluded.min), max = MAX(max, excluded.max),
  n_ok = n_ok + excluded.n_ok, sum_ok = sum_ok + excluded.sum_ok,
  sum_sq_ok = sum_sq_ok + excluded.sum_sq_ok,
  min_ok = COALESCE(MIN(min_ok, excluded.min_ok), min_ok, excluded.min_ok),
  max_ok = COALESCE(MAX(max_ok, excluded.max_ok), max_ok, excluded.max_ok)
)sql";

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

// Step count from a rollout blob's header ("ENR1", obs_dim, num_actions, steps: u32 each).
std::uint32_t RolloutSteps(const std::string& blob) {
  std::uint32_t steps = 0;
  if (blob.size() >= 16) std::memcpy(&steps, blob.data() + 12, sizeof steps);
  return steps;
}

bool Accepts(const std::vector<std::string>& list, const std::string& value) {
  return list.empty() || std::find(list.begin(), list.end(), value) != list.end();
}

// Series blob: "ENS1", then per column (t, position, velocity, eci, f_per, f_col, f_dif, res,
// utilisation) a u32 element count and the doubles (vectors flattened xyz). Host byte order:
// every platform the farm runs on (x86-64, aarch64) is little-endian.
constexpr char kSeriesMagic[4] = {'E', 'N', 'S', '1'};

void PutColumn(std::vector<std::uint8_t>* out, const double* data, std::uint32_t count) {
  const std::size_t at = out->size();
  out->resize(at + sizeof(count) + count * sizeof(double));
  std::memcpy(out->data() + at, &count, sizeof(count));
  if (count > 0) std::memcpy(out->data() + at + sizeof(count), data, count * sizeof(double));
}

}  // namespace

std::vector<std::uint8_t> PackSeries(const api::TimeSeries& s) {
  std::vector<std::uint8_t> out(kSeriesMagic, kSeriesMagic + 4);
  auto put = [&](const std::vector<double>& v) {
    PutColumn(&out, v.data(), static_cast<std::uint32_t>(v.size()));
  };
  auto put3 = [&](const std::vector<api::Vec3>& v) {
    PutColumn(&out, v.empty() ? nullptr : v.front().data(), static_cast<std::uint32_t>(3 * v.size()));
  };
  put(s.t);
  put3(s.position);
  put3(s.velocity);
  put(s.eci);
  put(s.f_per);
  put(s.f_col);
  put(s.f_dif);
  put(s.res);
  put(s.utilisation);
  return out;
}

api::TimeSeries UnpackSeries(const std::vector<std::uint8_t>& blob) {
  if (blob.size() < 4 || std::memcmp(blob.data(), kSeriesMagic, 4) != 0) {
    throw std::invalid_argument("series blob: bad magic");
  }
  std::size_t at = 4;
  auto get = [&](std::vector<double>* v) {
    std::uint32_t count = 0;
    if (at + sizeof(count) > blob.size()) throw std::invalid_argument("series blob: truncated");
    std::memcpy(&count, blob.data() + at, sizeof(count));
    at += sizeof(count);
    if (at + std::size_t{count} * sizeof(double) > blob.size()) {
      throw std::invalid_argument("series blob: truncated");
    }
    v->resize(count);
    if (count > 0) std::memcpy(v->data(), blob.data() + at, count * sizeof(double));
    at += count * sizeof(double);
  };
  auto get3 = [&](std::vector<api::Vec3>* v) {
    std::vector<double> flat;
    get(&flat);
    if (flat.size() % 3 != 0) throw std::invalid_argument("series blob: vector column length");
    v->resize(flat.size() / 3);
    for (std::size_t i = 0; i < v->size(); ++i) (*v)[i] = {flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]};
  };
  api::TimeSeries s;
  get(&s.t);
  get3(&s.position);
  get3(&s.velocity);
  get(&s.eci);
  get(&s.f_per);
  get(&s.f_col);
  get(&s.f_dif);
  get(&s.res);
  get(&s.utilisation);
  return s;
}

Store::Store(const std::filesystem::path& path, StoreOptions options)
    : options_(options) {
  if (options_.max_attempts < 1) throw std::invalid_argument("max_attempts: must be >= 1");
  if (options_.read_only && !std::filesystem::is_regular_file(path)) {
    throw StoreError("database '" + path.string() + "': no such file");
  }
  db_ = std::make_unique<Database>(path, options.busy_timeout_ms, options_.read_only);
  Statement& version = db_->Prepare("PRAGMA user_version");
  version.Step();
  const std::int64_t found = version.Int(0);
  version.Reset();
  if (found > kStoreSchemaVersion) {
    throw StoreError("database '" + path.string() + "' has schema version " +
                     std::to_string(found) + ", newer than this build's " +
                     std::to_string(kStoreSchemaVersion));
  }
  if (options_.read_only) {
    if (!HasColumn("jobs", "id")) {
      throw StoreError("database '" + path.string() + "' is not an enavi farm database");
    }
    return;
  }
  Transaction tx(*db_);
  db_->Exec(kSchema);
  db_->Exec(kCollectSchema);
  db_->Exec(kSchemaAdditions);
  Migrate();
  db_->Exec("PRAGMA user_version = " + std::to_string(kStoreSchemaVersion));
  tx.Commit();
  db_->Exec("PRAGMA wal_autocheckpoint = 0");
  checkpointer_ = std::thread([this, path] { CheckpointLoop(path); });
}

bool Store::HasColumn(const std::string& table, const std::string& column) {
  Statement& q = db_->Prepare("SELECT 1 FROM pragma_table_info(?) WHERE name = ?");
  q.Bind(1, table).Bind(2, column);
  const bool found = q.Step();
  q.Reset();
  return found;
}

void Store::Migrate() {
  if (!HasColumn("jobs", "provenance_json")) {
    db_->Exec("ALTER TABLE jobs ADD COLUMN provenance_json TEXT NOT NULL DEFAULT '{}'");
  }
  // The flat metrics of each result, so aggregates read ~1 kB per row instead of the record
  // with its notes and events. Rows stored before the column existed are filled in here.
  if (!HasColumn("results", "metrics_json")) {
    db_->Exec("ALTER TABLE results ADD COLUMN metrics_json TEXT");
  }
  std::vector<std::pair<std::string, std::string>> missing;
  Statement& old = db_->Prepare("SELECT episode_id, result_json FROM results WHERE metrics_json IS NULL");
  while (old.Step()) {
    missing.emplace_back(old.Text(0),
                         nlohmann::json(api::ResultMetrics(nlohmann::json::parse(old.Text(1)))).dump());
  }
  old.Reset();
  Statement& fill = db_->Prepare("UPDATE results SET metrics_json = ? WHERE episode_id = ?");
  for (const auto& [id, metrics] : missing) fill.Reset().Bind(1, metrics).Bind(2, id).Run();
  // Per cell and metric running sums, kept by every ingest (kAddCellMetrics), so a job page
  // reads ~1 row per cell and metric instead of every result. Built from the results once.
  if (!HasColumn("cell_metrics", "n")) {
    db_->Exec(R"sql(
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

Store::~Store() {
  if (options_.read_only) return;
  {
    std::lock_guard lock(checkpoint_mutex_);
    stop_checkpoints_ = true;
  }
  checkpoint_cv_.notify_all();
  if (checkpointer_.joinable()) checkpointer_.join();
  // Fold the WAL into the database file, so the file alone is the whole store.
  try {
    db_->Exec("PRAGMA wal_checkpoint(TRUNCATE)");
  } catch (const StoreError&) {
    // Another connection is reading: the WAL stays and is replayed on the next open.
  }
}

void Store::CheckpointLoop(std::filesystem::path path) {
  // PASSIVE: copies what no reader still needs and never blocks the writer. Once everything is
  // copied, the next commit starts the WAL from its beginning, so the WAL stays bounded.
  Database db(path, options_.busy_timeout_ms);
  std::unique_lock lock(checkpoint_mutex_);
  while (!stop_checkpoints_) {
    checkpoint_cv_.wait_for(lock, std::chrono::milliseconds(500));
    if (stop_checkpoints_) break;
    lock.unlock();
    try {
      db.Exec("PRAGMA wal_checkpoint(PASSIVE)");
    } catch (const StoreError&) {
      // Busy: the next round catches up.
    }
    lock.lock();
  }
}

// ---------------------------------------------------------------- jobs

std::string Store::CreateJob(const std::string& name, const std::string& spec_yaml,
                             const std::vector<api::EpisodeSpec>& episodes, std::int64_t now_ms,
                             const JobMeta& meta, const std::optional<CollectionInfo>& collect) {
  if (episodes.empty()) throw std::invalid_argument("job '" + name + "': no episodes");
  std::lock_guard lock(mutex_);
  Transaction tx(*db_);
  std::string job_id = NewJobId();
  db_->Prepare("INSERT INTO jobs (id, name, spec_yaml, state, total, created_ms) "
               "VALUES (?, ?, ?, 'running', ?, ?)")
      .Bind(1, job_id).Bind(2, name).Bind(3, spec_yaml)
      .Bind(4, static_cast<std::int64_t>(episodes.size())).Bind(5, now_ms).Run();
  db_->Prepare("UPDATE jobs SET provenance_json = ? WHERE id = ?")
      .Bind(1, nlohmann::json(meta.provenance).dump()).Bind(2, job_id).Run();
  Statement& label = db_->Prepare("INSERT INTO job_labels (job_id, key, value) VALUES (?, ?, ?)");
  for (const auto& [key, value] : meta.labels) label.Reset().Bind(1, job_id).Bind(2, key).Bind(3, value).Run();
  Statement& insert = db_->Prepare(
      "INSERT INTO episodes (id, job_id, idx, spec_json, board, world, method, seed, clock, "
      "state, updated_ms) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, 'pending', ?)");
  for (std::size_t i = 0; i < episodes.size(); ++i) {
    const api::EpisodeSpec& e = episodes[i];
    insert.Reset()
        .Bind(1, EpisodeId(job_id, i)).Bind(2, job_id).Bind(3, static_cast<std::int64_t>(i))
        .Bind(4, nlohmann::json(e).dump()).Bind(5, e.board).Bind(6, e.world).Bind(7, e.method)
        .Bind(8, static_cast<std::int64_t>(e.seed)).Bind(9, e.clock).Bind(10, now_ms).Run();
  }
  if (collect) {
    db_->Prepare("INSERT INTO collect_jobs (job_id, policy_hash, sample) VALUES (?, ?, ?)")
        .Bind(1, job_id).Bind(2, collect->policy_hash).Bind(3, collect->sample ? 1 : 0).Run();
  }
  tx.Commit();
  return job_id;
}

api::JobProgress Store::ProgressLocked(const std::string& job_id, std::int64_t now_ms) {
  api::JobProgress p;
  Statement& job = db_->Prepare(
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
  if (HasColumn("jobs", "provenance_json")) {
    Statement& prov = db_->Prepare("SELECT provenance_json FROM jobs WHERE id = ?");
    prov.Bind(1, job_id);
    if (prov.Step()) {
      p.provenance = nlohmann::json::parse(prov.Text(0)).get<std::map<std::string, std::string>>();
    }
    prov.Reset();
  }
  if (HasColumn("job_labels", "key")) {
    Statement& labels = db_->Prepare("SELECT key, value FROM job_labels WHERE job_id = ?");
    labels.Bind(1, job_id);
    while (labels.Step()) p.labels[labels.Text(0)] = labels.Text(1);
  }
  Statement& counts =
      db_->Prepare("SELECT state, COUNT(*) FROM episodes WHERE job_id = ? GROUP BY state");
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
  Statement& errors = db_->Prepare(
      "SELECT id, last_error FROM episodes WHERE job_id = ? AND state = 'failed' "
      "ORDER BY updated_ms DESC LIMIT 5");
  errors.Bind(1, job_id);
  while (errors.Step()) p.errors.push_back(errors.Text(0) + ": " + errors.Text(1));
  return p;
}

std::optional<api::JobProgress> Store::Progress(const std::string& job_id, std::int64_t now_ms) {
  std::lock_guard lock(mutex_);
  api::JobProgress p = ProgressLocked(job_id, now_ms);
  if (p.id.empty()) return std::nullopt;
  return p;
}

std::vector<api::JobProgress> Store::ListJobs(std::int64_t now_ms) { return ListJobs(now_ms, {}); }

std::vector<api::JobProgress> Store::ListJobs(std::int64_t now_ms,
                                              const std::map<std::string, std::string>& labels) {
  std::lock_guard lock(mutex_);
  std::vector<std::string> ids;
  if (labels.empty()) {
    Statement& list = db_->Prepare("SELECT id FROM jobs ORDER BY created_ms, rowid");
    while (list.Step()) ids.push_back(list.Text(0));
  } else if (HasColumn("job_labels", "key")) {
    // Jobs matching every filter: one row per matching label, so the count must be all of them.
    Statement& list = db_->Prepare(
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

std::optional<std::vector<ReleasedLease>> Store::CancelJob(const std::string& job_id,
                                                           std::int64_t now_ms) {
  std::lock_guard lock(mutex_);
  Transaction tx(*db_);
  Statement& job = db_->Prepare("SELECT state FROM jobs WHERE id = ?");
  job.Bind(1, job_id);
  if (!job.Step()) return std::nullopt;
  const std::string state = job.Text(0);
  job.Reset();
  std::vector<ReleasedLease> revoked;
  if (state != "running") return revoked;  // done or already cancelled: nothing to do
  Statement& leased = db_->Prepare(
      "SELECT id, lease_owner, attempts FROM episodes WHERE job_id = ? AND state = 'leased'");
  leased.Bind(1, job_id);
  while (leased.Step()) {
    revoked.push_back({leased.Text(0), job_id, leased.Text(1), static_cast<int>(leased.Int(2)),
                       false, "job cancelled"});
  }
  db_->Prepare("UPDATE episodes SET state = 'cancelled', lease_owner = NULL, "
               "lease_deadline_ms = NULL, last_error = 'job cancelled', updated_ms = ? "
               "WHERE job_id = ? AND state IN ('pending', 'leased')")
      .Bind(1, now_ms).Bind(2, job_id).Run();
  db_->Prepare("UPDATE jobs SET state = 'cancelled', finished_ms = ? WHERE id = ?")
      .Bind(1, now_ms).Bind(2, job_id).Run();
  tx.Commit();
  return revoked;
}

std::vector<EpisodeInfo> Store::Episodes(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  std::vector<EpisodeInfo> out;
  Statement& q = db_->Prepare(
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

// ---------------------------------------------------------------- scheduling

std::vector<Lease> Store::LeaseEpisodes(const std::string& worker_id, int count,
                                        const WorkerCapabilities& caps, std::int64_t deadline_ms,
                                        std::int64_t now_ms) {
  std::vector<Lease> leases;
  if (count <= 0) return leases;
  std::lock_guard lock(mutex_);
  Transaction tx(*db_);
  // Oldest job first, then episode order. Capability filters are applied here rather than in
  // SQL so the statement stays cacheable; scanning stops once `count` are found.
  Statement& pending = db_->Prepare(
      "SELECT e.id, e.job_id, e.attempts, e.spec_json, e.board, e.clock FROM episodes e "
      "JOIN jobs j ON j.id = e.job_id WHERE e.state = 'pending' AND j.state = 'running' "
      "ORDER BY j.created_ms, j.rowid, e.idx");
  std::vector<std::string> jobs;
  while (static_cast<int>(leases.size()) < count && pending.Step()) {
    if (!Accepts(caps.boards, pending.Text(4)) || !Accepts(caps.clocks, pending.Text(5))) continue;
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
  Statement& update = db_->Prepare(
      "UPDATE episodes SET state = 'leased', attempts = ?, lease_owner = ?, "
      "lease_deadline_ms = ?, updated_ms = ? WHERE id = ? AND state = 'pending'");
  Statement& started = db_->Prepare(
      "UPDATE jobs SET started_ms = ? WHERE id = ? AND started_ms IS NULL");
  for (const Lease& l : leases) {
    update.Reset().Bind(1, l.attempt).Bind(2, worker_id).Bind(3, deadline_ms).Bind(4, now_ms)
        .Bind(5, l.episode_id).Run();
    started.Reset().Bind(1, now_ms).Bind(2, l.job_id).Run();
  }
  tx.Commit();
  return leases;
}

int Store::RenewLeases(const std::string& worker_id, const std::vector<api::EpisodeRef>& running,
                       std::int64_t deadline_ms) {
  return RenewLeases(std::map<std::string, std::vector<api::EpisodeRef>>{{worker_id, running}},
                     deadline_ms);
}

int Store::RenewLeases(const std::map<std::string, std::vector<api::EpisodeRef>>& running_by_worker,
                       std::int64_t deadline_ms) {
  const bool any = std::any_of(running_by_worker.begin(), running_by_worker.end(),
                               [](const auto& kv) { return !kv.second.empty(); });
  if (!any) return 0;
  std::lock_guard lock(mutex_);
  Transaction tx(*db_);
  Statement& renew = db_->Prepare(
      "UPDATE episodes SET lease_deadline_ms = ? WHERE id = ? AND state = 'leased' "
      "AND lease_owner = ? AND attempts = ?");
  int renewed = 0;
  for (const auto& [worker_id, running] : running_by_worker) {
    for (const auto& ref : running) {
      renew.Reset().Bind(1, deadline_ms).Bind(2, ref.episode_id).Bind(3, worker_id)
          .Bind(4, ref.attempt).Run();
      renewed += static_cast<int>(db_->Changes());
    }
  }
  tx.Commit();
  return renewed;
}

std::vector<ReleasedLease> Store::ReleaseWhere(const std::string& where, const std::string& arg,
                                               std::int64_t value, const std::string& reason,
                                               std::int64_t now_ms) {
  Transaction tx(*db_);
  std::vector<ReleasedLease> released;
  Statement& select = db_->Prepare(
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
    r.failed = r.attempt >= options_.max_attempts;
    r.reason = reason + " (worker " + r.worker + ", attempt " + std::to_string(r.attempt) + ")";
    if (r.failed) {
      r.reason += "; gave up after " + std::to_string(r.attempt) + " attempts";
    }
    released.push_back(std::move(r));
  }
  select.Reset();
  Statement& update = db_->Prepare(
      "UPDATE episodes SET state = ?, lease_owner = NULL, lease_deadline_ms = NULL, "
      "last_error = ?, updated_ms = ? WHERE id = ? AND state = 'leased'");
  std::vector<std::string> jobs;
  for (const auto& r : released) {
    update.Reset().Bind(1, r.failed ? "failed" : "pending").Bind(2, r.reason).Bind(3, now_ms)
        .Bind(4, r.episode_id).Run();
    if (r.failed) jobs.push_back(r.job_id);
  }
  FinishJobsIfComplete(jobs, now_ms);
  tx.Commit();
  return released;
}

std::vector<ReleasedLease> Store::ExpireLeases(std::int64_t now_ms) {
  std::lock_guard lock(mutex_);
  return ReleaseWhere("lease_deadline_ms < ?", "", now_ms, "lease expired", now_ms);
}

std::vector<Lease> Store::HeldLeases() {
  std::lock_guard lock(mutex_);
  std::vector<Lease> leases;
  Statement& q = db_->Prepare(
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

std::vector<ReleasedLease> Store::ReleaseWorker(const std::string& worker_id,
                                                const std::string& reason, std::int64_t now_ms) {
  std::lock_guard lock(mutex_);
  return ReleaseWhere("lease_owner = ?", worker_id, 0, reason, now_ms);
}

std::map<std::string, int> Store::LeasedCounts() {
  std::lock_guard lock(mutex_);
  std::map<std::string, int> counts;
  Statement& q = db_->Prepare(
      "SELECT lease_owner, COUNT(*) FROM episodes WHERE state = 'leased' GROUP BY lease_owner");
  while (q.Step()) counts[q.Text(0)] = static_cast<int>(q.Int(1));
  return counts;
}

bool Store::HoldsLease(const std::string& episode_id, int attempt, const std::string& worker_id) {
  std::lock_guard lock(mutex_);
  Statement& q = db_->Prepare(
      "SELECT 1 FROM episodes WHERE id = ? AND state = 'leased' AND attempts = ? "
      "AND lease_owner = ?");
  q.Bind(1, episode_id).Bind(2, attempt).Bind(3, worker_id);
  const bool held = q.Step();
  q.Reset();
  return held;
}

void Store::FinishJobsIfComplete(const std::vector<std::string>& job_ids, std::int64_t now_ms) {
  const std::set<std::string> unique(job_ids.begin(), job_ids.end());
  Statement& open = db_->Prepare(
      "SELECT COUNT(*) FROM episodes WHERE job_id = ? AND state IN ('pending', 'leased')");
  Statement& finish = db_->Prepare(
      "UPDATE jobs SET state = 'done', finished_ms = ? WHERE id = ? AND state = 'running'");
  for (const auto& id : unique) {
    open.Reset().Bind(1, id);
    open.Step();
    const std::int64_t remaining = open.Int(0);
    open.Reset();
    if (remaining == 0) finish.Reset().Bind(1, now_ms).Bind(2, id).Run();
  }
}

// ---------------------------------------------------------------- results

std::vector<IngestOutcome> Store::Ingest(const std::vector<api::ResultMessage>& results,
                                         std::int64_t now_ms) {
  std::vector<IngestOutcome> outcomes;
  outcomes.reserve(results.size());
  std::lock_guard lock(mutex_);
  Transaction tx(*db_);
  Statement& lookup = db_->Prepare(
      "SELECT e.state, e.attempts, e.lease_owner, e.job_id, j.state, c.policy_hash, e.spec_json FROM episodes e "
      "JOIN jobs j ON j.id = e.job_id LEFT JOIN collect_jobs c ON c.job_id = e.job_id "
      "WHERE e.id = ?");
  Statement& insert_rollout = db_->Prepare(
      "INSERT OR REPLACE INTO rollouts (episode_id, job_id, attempt, policy_hash, steps, data) "
      "VALUES (?, ?, ?, ?, ?, ?)");
  Statement& insert = db_->Prepare(
      "INSERT OR IGNORE INTO results (episode_id, job_id, worker, attempt, board, scenario, world, "
      "method, seed, clock, success, collided, timed_out, end_reason, flight_time_s, "
      "path_length_m, velocity_mean_mps, velocity_std_mps, nav_cpu_util_pct, "
      "deadline_miss_ratio, replans, wall_time_s, received_ms, result_json, series, metrics_json) "
      "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  Statement& set_state = db_->Prepare(
      "UPDATE episodes SET state = ?, attempts = ?, lease_owner = NULL, lease_deadline_ms = NULL, "
      "last_error = ?, updated_ms = ? WHERE id = ?");
  Statement& add_cell = db_->Prepare(kAddCellMetrics);
  std::vector<std::string> touched_jobs;

  for (const api::ResultMessage& m : results) {
    IngestOutcome out;
    lookup.Reset().Bind(1, m.episode_id);
    if (!lookup.Step()) {
      out.ack = api::AckStatus::kUnknown;
      out.detail = "no episode " + m.episode_id + " in this farm's database";
      outcomes.push_back(out);
      continue;
    }
    const std::string state = lookup.Text(0);
    const int attempts = static_cast<int>(lookup.Int(1));
    const std::string owner = lookup.Text(2);
    out.job_id = lookup.Text(3);
    const std::string job_state = lookup.Text(4);
    const std::string collect_hash = lookup.IsNull(5) ? std::string() : lookup.Text(5);
    const api::EpisodeSpec spec = nlohmann::json::parse(lookup.Text(6)).get<api::EpisodeSpec>();
    lookup.Reset();
    // A collection episode's result counts only with a rollout of the job's policy: a rollout of
    // another (stale) policy is refused by its hash, and the episode runs again.
    api::ResultMessage refused;
    const api::ResultMessage* msg = &m;
    if (!collect_hash.empty() && m.status == api::ResultStatus::kOk &&
        (m.rollout.empty() || m.policy_hash != collect_hash)) {
      refused = m;
      refused.status = api::ResultStatus::kError;
      refused.error = m.rollout.empty() ? "collection episode without a rollout"
                                        : "rollout of policy " + m.policy_hash.substr(0, 12) +
                                              ", not the job's " + collect_hash.substr(0, 12) +
                                              " (stale policy)";
      msg = &refused;
    }
    // A result of another episode or with non-finite metrics (a rogue or broken worker) is the
    // attempt's error, not data.
    if (msg->status == api::ResultStatus::kOk) {
      std::string why = api::ResultError(m.result, spec);
      if (why.empty() && !std::isfinite(m.wall_time_s)) why = "wall_time_s: not a finite number";
      if (!why.empty()) {
        refused = m;
        refused.status = api::ResultStatus::kError;
        refused.error = "result refused: " + why;
        msg = &refused;
      }
    }
    const bool current_lease = state == "leased" && attempts == m.attempt && owner == m.worker_id;

    if (msg->status == api::ResultStatus::kOk) {
      if (state == "done") {
        out.ack = api::AckStatus::kDuplicate;
        out.detail = "episode already has a result";
      } else if (state == "cancelled" || job_state == "cancelled") {
        out.ack = api::AckStatus::kDiscarded;
        out.detail = "job cancelled";
      } else {
        // pending/leased (any attempt: episodes are deterministic) or failed (a late success).
        const api::EpisodeResult& r = m.result;
        const nlohmann::json flat = api::ResultSummaryJson(r);
        const std::string metrics = nlohmann::json(api::ResultMetrics(flat)).dump();
        const std::string summary = [&] {
          nlohmann::json j = flat;
          j["spec"] = r.spec;
          nlohmann::json events = nlohmann::json::array();
          for (const auto& e : r.events) events.push_back({{"t", e.t}, {"kind", e.kind}, {"detail", e.detail}});
          j["events"] = std::move(events);
          // A worker's strings are bytes (DDS does not check UTF-8): replace what is not UTF-8
          // rather than throw, which failed the whole batch, every worker's results with it.
          return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
        }();
        insert.Reset()
            .Bind(1, m.episode_id).Bind(2, out.job_id).Bind(3, m.worker_id).Bind(4, m.attempt)
            .Bind(5, r.spec.board).Bind(6, r.scenario.empty() ? worlds::ScenarioOf(r.spec.world) : r.scenario)
            .Bind(7, r.spec.world).Bind(8, r.spec.method)
            .Bind(9, static_cast<std::int64_t>(r.spec.seed)).Bind(10, r.spec.clock)
            .Bind(11, r.success ? 1 : 0).Bind(12, r.collided ? 1 : 0).Bind(13, r.timed_out ? 1 : 0)
            .Bind(14, r.end_reason).Bind(15, r.flight_time_s).Bind(16, r.path_length_m)
            .Bind(17, r.velocity_mean_mps).Bind(18, r.velocity_std_mps)
            .Bind(19, r.nav_cpu_util_pct).Bind(20, r.deadline_miss_ratio)
            .Bind(21, r.replans).Bind(22, m.wall_time_s).Bind(23, now_ms).Bind(24, summary)
            .BindBlob(25, PackSeries(r.series)).Bind(26, metrics).Run();
        add_cell.Reset()
            .Bind(1, out.job_id).Bind(2, r.spec.board)
            .Bind(3, r.scenario.empty() ? worlds::ScenarioOf(r.spec.world) : r.scenario)
            .Bind(4, r.spec.method).Bind(5, r.success ? 1 : 0).Bind(6, metrics).Run();
        if (!m.rollout.empty()) {
          insert_rollout.Reset().Bind(1, m.episode_id).Bind(2, out.job_id).Bind(3, m.attempt)
              .Bind(4, m.policy_hash).Bind(5, static_cast<std::int64_t>(RolloutSteps(m.rollout)))
              .BindBlob(6, std::vector<std::uint8_t>(m.rollout.begin(), m.rollout.end())).Run();
        }
        set_state.Reset().Bind(1, "done").Bind(2, std::max(attempts, m.attempt)).BindNull(3)
            .Bind(4, now_ms).Bind(5, m.episode_id).Run();
        out.ack = api::AckStatus::kStored;
        out.event = "episode_done";
        touched_jobs.push_back(out.job_id);
      }
    } else if (msg->status == api::ResultStatus::kError) {
      if (!current_lease) {
        out.ack = state == "done" ? api::AckStatus::kDuplicate : api::AckStatus::kDiscarded;
        out.detail = "not the current lease of this episode (" + state + ")";
      } else {
        const bool failed = attempts >= options_.max_attempts;
        std::string reason = msg->error;
        if (failed) reason += " (gave up after " + std::to_string(attempts) + " attempts)";
        set_state.Reset().Bind(1, failed ? "failed" : "pending").Bind(2, attempts)
            .Bind(3, reason).Bind(4, now_ms).Bind(5, m.episode_id).Run();
        out.ack = api::AckStatus::kRecorded;
        out.detail = std::string(msg != &m ? msg->error + ": " : "") + (failed ? "episode failed" : "episode re-queued");
        out.event = failed ? "episode_failed" : "requeued";
        touched_jobs.push_back(out.job_id);
      }
    } else {  // rejected: the attempt did not run, so it does not count
      if (!current_lease) {
        out.ack = api::AckStatus::kDiscarded;
        out.detail = "not the current lease of this episode (" + state + ")";
      } else {
        set_state.Reset().Bind(1, "pending").Bind(2, attempts - 1)
            .Bind(3, "rejected by " + m.worker_id + ": " + m.error).Bind(4, now_ms)
            .Bind(5, m.episode_id).Run();
        out.ack = api::AckStatus::kRecorded;
        out.detail = "episode re-queued";
        out.event = "requeued";
      }
    }
    outcomes.push_back(std::move(out));
  }
  FinishJobsIfComplete(touched_jobs, now_ms);
  tx.Commit();
  return outcomes;
}

std::string Store::ResultsQuery(bool paged) {
  const bool hosts = HasColumn("workers", "host");
  // Driven by the episodes' (job_id, idx) index: a page reads only its rows, unsorted.
  return std::string("SELECT r.episode_id, r.worker, r.attempt, r.wall_time_s, r.result_json, ") +
         (hosts ? "w.host" : "NULL") + " FROM episodes e JOIN results r ON r.episode_id = e.id " +
         (hosts ? "LEFT JOIN workers w ON w.worker_id = r.worker " : "") +
         "WHERE e.job_id = ? ORDER BY e.idx" + (paged ? " LIMIT ? OFFSET ?" : "");
}

nlohmann::json Store::ResultObject(const Statement& q) {
  nlohmann::json j = nlohmann::json::parse(q.Text(4));
  j.erase("spec");
  j.erase("events");
  j["episode_id"] = q.Text(0);
  j["worker"] = q.Text(1);
  j["worker_host"] = q.Text(5);
  j["attempt"] = q.Int(2);
  j["wall_time_s"] = q.Double(3);
  return j;
}

nlohmann::json Store::Results(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  nlohmann::json list = nlohmann::json::array();
  Statement& q = db_->Prepare(ResultsQuery(false));
  q.Bind(1, job_id);
  while (q.Step()) list.push_back(ResultObject(q));
  return list;
}

std::optional<api::EpisodeResult> Store::FullResult(const std::string& episode_id) {
  std::lock_guard lock(mutex_);
  Statement& q = db_->Prepare("SELECT result_json, series FROM results WHERE episode_id = ?");
  q.Bind(1, episode_id);
  if (!q.Step()) return std::nullopt;
  api::EpisodeResult r = nlohmann::json::parse(q.Text(0)).get<api::EpisodeResult>();
  r.series = UnpackSeries(q.Blob(1));
  q.Reset();
  return r;
}

// ---------------------------------------------------------------- dashboard aggregates

namespace {

double SampleStd(std::int64_t n, double mean, double mean_sq) {
  if (n < 2) return 0.0;
  const double var = std::max(0.0, mean_sq - mean * mean) * static_cast<double>(n) / (n - 1);
  return std::sqrt(var);
}

nlohmann::json Stats(std::int64_t n, double mean, double min, double max, double mean_sq) {
  return {{"n", n}, {"mean", mean}, {"std", SampleStd(n, mean, mean_sq)}, {"min", min}, {"max", max}};
}

nlohmann::json PageJson(const Page& page, std::int64_t total) {
  return {{"offset", page.offset}, {"limit", page.limit}, {"total", total}};
}

}  // namespace

nlohmann::json Store::JobSummary(const std::string& job_id, const Page& page) {
  std::lock_guard lock(mutex_);
  const std::string metrics = HasColumn("results", "metrics_json") ? "r.metrics_json" : "r.result_json";
  nlohmann::json out = PageJson(page, 0);
  Statement& count = db_->Prepare(
      "SELECT COUNT(*) FROM (SELECT 1 FROM results WHERE job_id = ? GROUP BY board, scenario, method)");
  count.Bind(1, job_id);
  count.Step();
  out["total"] = count.Int(0);
  count.Reset();
  // Per cell and metric, all episodes and successful ones: from the running sums when the
  // database has them, else (a read-only database written before them) from every result.
  const std::string sums =
      HasColumn("cell_metrics", "n")
          ? "SELECT board, scenario, method, name, n, sum / n, min, max, sum_sq / n, n_ok, "
            "  sum_ok / NULLIF(n_ok, 0), min_ok, max_ok, sum_sq_ok / NULLIF(n_ok, 0) "
            "FROM cell_metrics WHERE job_id = ?1 AND (board, scenario, method) IN ("
            "  SELECT board, scenario, method FROM cell_metrics WHERE job_id = ?1 "
            "  GROUP BY board, scenario, method ORDER BY board, scenario, method LIMIT ?2 OFFSET ?3) "
            "ORDER BY board, scenario, method"
          : "WITH cells AS (SELECT board, scenario, method FROM results WHERE job_id = ?1 "
            "  GROUP BY board, scenario, method ORDER BY board, scenario, method LIMIT ?2 OFFSET ?3) "
            "SELECT r.board, r.scenario, r.method, m.key, "
            "  COUNT(*), AVG(m.value), MIN(m.value), MAX(m.value), AVG(m.value * m.value), "
            "  COUNT(*) FILTER (WHERE r.success = 1), AVG(m.value) FILTER (WHERE r.success = 1), "
            "  MIN(m.value) FILTER (WHERE r.success = 1), MAX(m.value) FILTER (WHERE r.success = 1), "
            "  AVG(m.value * m.value) FILTER (WHERE r.success = 1) "
            "FROM results r JOIN cells c ON c.board = r.board AND c.scenario = r.scenario "
            "  AND c.method = r.method, json_each(" + metrics + ") m "
            "WHERE r.job_id = ?1 AND m.type IN ('integer', 'real', 'true', 'false') "
            "GROUP BY r.board, r.scenario, r.method, m.key ORDER BY r.board, r.scenario, r.method";
  Statement& q = db_->Prepare(sums);
  q.Bind(1, job_id).Bind(2, page.limit).Bind(3, page.offset);
  nlohmann::json cells = nlohmann::json::array();
  while (q.Step()) {
    const std::string board = q.Text(0), scenario = q.Text(1), method = q.Text(2);
    if (cells.empty() || cells.back()["board"] != board || cells.back()["scenario"] != scenario ||
        cells.back()["method"] != method) {
      cells.push_back({{"board", board}, {"scenario", scenario}, {"method", method},
                       {"results", 0}, {"metrics", nlohmann::json::object()},
                       {"success_only", nlohmann::json::object()}});
    }
    nlohmann::json& cell = cells.back();
    cell["results"] = std::max(cell["results"].get<std::int64_t>(), q.Int(4));
    cell["metrics"][q.Text(3)] = Stats(q.Int(4), q.Double(5), q.Double(6), q.Double(7), q.Double(8));
    if (q.Int(9) > 0) {
      cell["success_only"][q.Text(3)] =
          Stats(q.Int(9), q.Double(10), q.Double(11), q.Double(12), q.Double(13));
    }
  }
  q.Reset();
  // Episodes that never produced a result (failed after all attempts) count against the cell.
  Statement& failed = db_->Prepare(
      "SELECT board, world, method, COUNT(*) FROM episodes WHERE job_id = ? AND state = 'failed' "
      "GROUP BY board, world, method");
  failed.Bind(1, job_id);
  std::map<std::tuple<std::string, std::string, std::string>, std::int64_t> failures;
  while (failed.Step()) {
    failures[{failed.Text(0), worlds::ScenarioOf(failed.Text(1)), failed.Text(2)}] += failed.Int(3);
  }
  for (auto& cell : cells) {
    const auto it = failures.find({cell["board"], cell["scenario"], cell["method"]});
    cell["failed_episodes"] = it == failures.end() ? 0 : it->second;
  }
  out["cells"] = std::move(cells);
  return out;
}

nlohmann::json Store::ResultsPage(const std::string& job_id, const Page& page) {
  std::lock_guard lock(mutex_);
  Statement& count = db_->Prepare("SELECT COUNT(*) FROM results WHERE job_id = ?");
  count.Bind(1, job_id);
  count.Step();
  nlohmann::json out = PageJson(page, count.Int(0));
  count.Reset();
  nlohmann::json list = nlohmann::json::array();
  Statement& q = db_->Prepare(ResultsQuery(true));
  q.Bind(1, job_id).Bind(2, page.limit).Bind(3, page.offset);
  while (q.Step()) list.push_back(ResultObject(q));
  q.Reset();
  out["results"] = std::move(list);
  return out;
}

nlohmann::json Store::JobFailures(const std::string& job_id, const Page& page) {
  std::lock_guard lock(mutex_);
  // Failed episodes have no result (a late success makes them done), so the two sets are
  // disjoint; each comes from its own index.
  Statement& count = db_->Prepare(
      "SELECT (SELECT COUNT(*) FROM episodes WHERE state = 'failed' AND job_id = ?1) + "
      "(SELECT COUNT(*) FROM results WHERE job_id = ?1 AND success = 0)");
  count.Bind(1, job_id);
  count.Step();
  nlohmann::json out = PageJson(page, count.Int(0));
  count.Reset();
  Statement& q = db_->Prepare(
      "SELECT e.id, e.board, e.world, e.method, e.seed, e.state, e.attempts, "
      "COALESCE(r.end_reason, e.last_error, '') FROM episodes e "
      "LEFT JOIN results r ON r.episode_id = e.id WHERE e.id IN ("
      "  SELECT id FROM episodes WHERE state = 'failed' AND job_id = ?1 UNION ALL "
      "  SELECT episode_id FROM results WHERE job_id = ?1 AND success = 0) "
      "ORDER BY e.idx LIMIT ?2 OFFSET ?3");
  q.Bind(1, job_id).Bind(2, page.limit).Bind(3, page.offset);
  nlohmann::json list = nlohmann::json::array();
  while (q.Step()) {
    list.push_back({{"episode_id", q.Text(0)}, {"board", q.Text(1)},
                    {"scenario", worlds::ScenarioOf(q.Text(2))}, {"world", q.Text(2)},
                    {"method", q.Text(3)}, {"seed", q.Int(4)}, {"state", q.Text(5)},
                    {"attempts", q.Int(6)}, {"reason", q.Text(7)}});
  }
  q.Reset();
  out["failures"] = std::move(list);
  return out;
}

nlohmann::json Store::Trend(const std::string& key, const std::string& value,
                            const std::string& metric, const Page& page) {
  if (metric.empty() || !std::all_of(metric.begin(), metric.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.';
      })) {
    throw std::invalid_argument("metric: '" + metric + "': letters, digits, _ and . only");
  }
  std::lock_guard lock(mutex_);
  nlohmann::json out = PageJson(page, 0);
  out["points"] = nlohmann::json::array();
  if (!HasColumn("job_labels", "key")) return out;
  const std::string metrics = HasColumn("results", "metrics_json") ? "r.metrics_json" : "r.result_json";
  Statement& count = db_->Prepare("SELECT COUNT(*) FROM job_labels WHERE key = ? AND value = ?");
  count.Bind(1, key).Bind(2, value);
  count.Step();
  out["total"] = count.Int(0);
  count.Reset();
  // The spread that matters between two jobs of the same matrix is the seeds' draw within each
  // scenario, not the difference between scenarios (every job flies the same ones): pool the
  // within-cell sums of squares.
  Statement& q = db_->Prepare(
      "WITH series AS (SELECT j.id, j.name, j.created_ms, j.rowid AS seq FROM jobs j "
      "  JOIN job_labels l ON l.job_id = j.id WHERE l.key = ?1 AND l.value = ?2 "
      "  ORDER BY j.created_ms, j.rowid LIMIT ?4 OFFSET ?5), "
      "vals AS (SELECT s.id, s.name, s.created_ms, s.seq, r.board, r.method, r.scenario, "
      "  json_extract(" + metrics + ", ?3) AS v FROM series s JOIN results r ON r.job_id = s.id), "
      "cells AS (SELECT id, name, created_ms, seq, board, method, COUNT(v) AS n, SUM(v) AS sx, "
      "  SUM(v * v) AS sxx FROM vals GROUP BY id, board, method, scenario) "
      "SELECT id, name, created_ms, board, method, SUM(n), SUM(sx), "
      "  SUM(CASE WHEN n > 0 THEN MAX(sxx - sx * sx / n, 0) ELSE 0 END), SUM(MAX(n - 1, 0)) "
      "FROM cells GROUP BY id, board, method ORDER BY created_ms, seq, board, method");
  q.Bind(1, key).Bind(2, value).Bind(3, "$.\"" + metric + "\"").Bind(4, page.limit).Bind(5, page.offset);
  while (q.Step()) {
    const std::int64_t n = q.Int(5);
    if (n == 0) continue;  // the metric is not in these results
    const std::int64_t df = q.Int(8);
    nlohmann::json point = {{"job_id", q.Text(0)}, {"name", q.Text(1)}, {"created_ms", q.Int(2)},
                            {"board", q.Text(3)}, {"method", q.Text(4)}, {"n", n},
                            {"mean", q.Double(6) / static_cast<double>(n)}, {"df", df}, {"seed_std", nullptr}};
    if (df > 0) point["seed_std"] = std::sqrt(q.Double(7) / static_cast<double>(df));
    out["points"].push_back(std::move(point));
  }
  q.Reset();
  return out;
}

// ---------------------------------------------------------------- workers

void Store::RecordWorker(const api::WorkerStatus& s, std::int64_t now_ms) {
  std::lock_guard lock(mutex_);
  db_->Prepare(
         "INSERT INTO workers (worker_id, host, version, calibration_id, slots, boards, "
         "first_seen_ms, last_seen_ms) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?7) "
         "ON CONFLICT (worker_id) DO UPDATE SET host = ?2, version = ?3, calibration_id = ?4, "
         "slots = ?5, boards = ?6, last_seen_ms = ?7")
      .Bind(1, s.worker_id).Bind(2, s.host).Bind(3, s.version).Bind(4, s.calibration_id)
      .Bind(5, s.slots).Bind(6, nlohmann::json(s.boards).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)).Bind(7, now_ms).Run();
}

nlohmann::json Store::KnownWorkers() {
  std::lock_guard lock(mutex_);
  nlohmann::json list = nlohmann::json::array();
  if (!HasColumn("workers", "host")) return list;
  Statement& q = db_->Prepare(
      "SELECT worker_id, host, version, calibration_id, slots, boards, first_seen_ms, "
      "last_seen_ms FROM workers ORDER BY worker_id");
  while (q.Step()) {
    list.push_back({{"worker_id", q.Text(0)}, {"host", q.Text(1)}, {"version", q.Text(2)},
                    {"calibration_id", q.Text(3)}, {"slots", q.Int(4)},
                    {"boards", nlohmann::json::parse(q.Text(5))}, {"first_seen_ms", q.Int(6)},
                    {"last_seen_ms", q.Int(7)}});
  }
  return list;
}

}  // namespace enavi::server
