#include "server/store/ingest.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <nlohmann/json.hpp>

#include "api/result_metrics.h"
#include "server/store/connection.h"
#include "server/store/jobs.h"
#include "server/store/series_codec.h"
#include "worlds/generators.h"

namespace enavi::server {
namespace {

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

// Step count from a rollout blob's header: u32 at offset 12 in both forms ("ENR1" obs_dim,
// num_actions, steps; "ENV1" width, height, steps).
std::uint32_t RolloutSteps(const std::string& blob) {
  std::uint32_t steps = 0;
  if (blob.size() >= 16) std::memcpy(&steps, blob.data() + 12, sizeof steps);
  return steps;
}

}  // namespace

std::vector<IngestOutcome> ResultIngest::Ingest(const std::vector<api::ResultMessage>& results,
                                                std::int64_t now_ms) {
  std::vector<IngestOutcome> outcomes;
  outcomes.reserve(results.size());
  std::lock_guard lock(c_.mutex);
  Database& db = c_.db;
  Transaction tx(db);
  Statement& lookup = db.Prepare(
      "SELECT e.state, e.attempts, e.lease_owner, e.job_id, j.state, c.policy_hash, e.spec_json FROM episodes e "
      "JOIN jobs j ON j.id = e.job_id LEFT JOIN collect_jobs c ON c.job_id = e.job_id "
      "WHERE e.id = ?");
  Statement& insert_rollout = db.Prepare(
      "INSERT OR REPLACE INTO rollouts (episode_id, job_id, attempt, policy_hash, steps, data) "
      "VALUES (?, ?, ?, ?, ?, ?)");
  Statement& insert = db.Prepare(
      "INSERT OR IGNORE INTO results (episode_id, job_id, worker, attempt, board, scenario, world, "
      "method, seed, clock, success, collided, timed_out, end_reason, flight_time_s, "
      "path_length_m, velocity_mean_mps, velocity_std_mps, nav_cpu_util_pct, "
      "deadline_miss_ratio, replans, wall_time_s, received_ms, result_json, series, metrics_json) "
      "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  Statement& set_state = db.Prepare(
      "UPDATE episodes SET state = ?, attempts = ?, lease_owner = NULL, lease_deadline_ms = NULL, "
      "last_error = ?, updated_ms = ? WHERE id = ?");
  Statement& add_cell = db.Prepare(kAddCellMetrics);
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
        const bool failed = attempts >= c_.options.max_attempts;
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
  FinishJobsIfComplete(db, touched_jobs, now_ms);
  tx.Commit();
  return outcomes;
}

}  // namespace enavi::server
