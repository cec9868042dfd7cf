#include "server/store/queries.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "server/store/connection.h"
#include "server/store/schema.h"
#include "server/store/series_codec.h"
#include "worlds/generators.h"

namespace enavi::server {
namespace {

std::string ResultsQuery(Database& db, bool paged) {
  const bool hosts = HasColumn(db, "workers", "host");
  // Driven by the episodes' (job_id, idx) index: a page reads only its rows, unsorted.
  return std::string("SELECT r.episode_id, r.worker, r.attempt, r.wall_time_s, r.result_json, ") +
         (hosts ? "w.host" : "NULL") + " FROM episodes e JOIN results r ON r.episode_id = e.id " +
         (hosts ? "LEFT JOIN workers w ON w.worker_id = r.worker " : "") +
         "WHERE e.job_id = ? ORDER BY e.idx" + (paged ? " LIMIT ? OFFSET ?" : "");
}

nlohmann::json ResultObject(const Statement& q) {
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

// The metric names of the results of the jobs labelled key=value: from the running sums, or from
// the results themselves in a database written before them.
std::vector<std::string> SeriesMetrics(Database& db, const std::string& key, const std::string& value) {
  const bool sums = HasColumn(db, "cell_metrics", "n");
  const std::string metrics = HasColumn(db, "results", "metrics_json") ? "r.metrics_json" : "r.result_json";
  Statement& q = db.Prepare(
      sums ? "SELECT DISTINCT c.name FROM cell_metrics c JOIN job_labels l ON l.job_id = c.job_id "
             "WHERE l.key = ? AND l.value = ? ORDER BY c.name"
           : "SELECT DISTINCT m.key FROM job_labels l JOIN results r ON r.job_id = l.job_id, json_each(" + metrics +
                 ") m WHERE l.key = ? AND l.value = ? AND m.type IN ('integer', 'real', 'true', 'false') "
                 "ORDER BY m.key");
  q.Bind(1, key).Bind(2, value);
  std::vector<std::string> out;
  while (q.Step()) out.push_back(q.Text(0));
  q.Reset();
  return out;
}

// Levenshtein distance, for "did you mean".
std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// "; did you mean flight_time_s?": the known names containing the typed one or within a few edits
// of it (at most three), else where the names are listed.
std::string Suggestion(const std::string& typed, const std::vector<std::string>& known) {
  std::vector<std::string> close;
  for (const std::string& name : known) {
    const bool contains = name.find(typed) != std::string::npos || typed.find(name) != std::string::npos;
    if (contains || EditDistance(typed, name) <= std::max<std::size_t>(2, typed.size() / 4)) close.push_back(name);
  }
  if (close.empty()) return " (`enavi results JOB --format json` shows a result's metrics)";
  std::string out = "; did you mean ";
  for (std::size_t i = 0; i < close.size() && i < 3; ++i) out += (i ? ", " : "") + close[i];
  return out + "?";
}

}  // namespace

nlohmann::json ResultQueries::Results(const std::string& job_id) {
  std::lock_guard lock(c_.mutex);
  nlohmann::json list = nlohmann::json::array();
  Statement& q = c_.db.Prepare(ResultsQuery(c_.db, false));
  q.Bind(1, job_id);
  while (q.Step()) list.push_back(ResultObject(q));
  return list;
}

std::optional<api::EpisodeResult> ResultQueries::FullResult(const std::string& episode_id) {
  std::lock_guard lock(c_.mutex);
  Statement& q = c_.db.Prepare("SELECT result_json, series FROM results WHERE episode_id = ?");
  q.Bind(1, episode_id);
  if (!q.Step()) return std::nullopt;
  api::EpisodeResult r = nlohmann::json::parse(q.Text(0)).get<api::EpisodeResult>();
  r.series = UnpackSeries(q.Blob(1));
  q.Reset();
  return r;
}

nlohmann::json ResultQueries::JobSummary(const std::string& job_id, const Page& page) {
  std::lock_guard lock(c_.mutex);
  Database& db = c_.db;
  const std::string metrics = HasColumn(db, "results", "metrics_json") ? "r.metrics_json" : "r.result_json";
  nlohmann::json out = PageJson(page, 0);
  Statement& count = db.Prepare(
      "SELECT COUNT(*) FROM (SELECT 1 FROM results WHERE job_id = ? GROUP BY board, scenario, method)");
  count.Bind(1, job_id);
  count.Step();
  out["total"] = count.Int(0);
  count.Reset();
  // Per cell and metric, all episodes and successful ones: from the running sums when the
  // database has them, else (a read-only database written before them) from every result.
  const std::string sums =
      HasColumn(db, "cell_metrics", "n")
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
  Statement& q = db.Prepare(sums);
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
  Statement& failed = db.Prepare(
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

nlohmann::json ResultQueries::ResultsPage(const std::string& job_id, const Page& page) {
  std::lock_guard lock(c_.mutex);
  Database& db = c_.db;
  Statement& count = db.Prepare("SELECT COUNT(*) FROM results WHERE job_id = ?");
  count.Bind(1, job_id);
  count.Step();
  nlohmann::json out = PageJson(page, count.Int(0));
  count.Reset();
  nlohmann::json list = nlohmann::json::array();
  Statement& q = db.Prepare(ResultsQuery(db, true));
  q.Bind(1, job_id).Bind(2, page.limit).Bind(3, page.offset);
  while (q.Step()) list.push_back(ResultObject(q));
  q.Reset();
  out["results"] = std::move(list);
  return out;
}

nlohmann::json ResultQueries::JobFailures(const std::string& job_id, const Page& page) {
  std::lock_guard lock(c_.mutex);
  Database& db = c_.db;
  // Failed episodes have no result (a late success makes them done), so the two sets are
  // disjoint; each comes from its own index.
  Statement& count = db.Prepare(
      "SELECT (SELECT COUNT(*) FROM episodes WHERE state = 'failed' AND job_id = ?1) + "
      "(SELECT COUNT(*) FROM results WHERE job_id = ?1 AND success = 0)");
  count.Bind(1, job_id);
  count.Step();
  nlohmann::json out = PageJson(page, count.Int(0));
  count.Reset();
  Statement& q = db.Prepare(
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

nlohmann::json ResultQueries::Trend(const std::string& key, const std::string& value,
                            const std::string& metric, const Page& page) {
  if (metric.empty() || !std::all_of(metric.begin(), metric.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.';
      })) {
    throw std::invalid_argument("metric: '" + metric + "': letters, digits, _ and . only");
  }
  std::lock_guard lock(c_.mutex);
  Database& db = c_.db;
  nlohmann::json out = PageJson(page, 0);
  out["points"] = nlohmann::json::array();
  if (!HasColumn(db, "job_labels", "key")) return out;
  const std::string metrics = HasColumn(db, "results", "metrics_json") ? "r.metrics_json" : "r.result_json";
  Statement& count = db.Prepare("SELECT COUNT(*) FROM job_labels WHERE key = ? AND value = ?");
  count.Bind(1, key).Bind(2, value);
  count.Step();
  out["total"] = count.Int(0);
  count.Reset();
  // The spread that matters between two jobs of the same matrix is the seeds' draw within each
  // scenario, not the difference between scenarios (every job flies the same ones): pool the
  // within-cell sums of squares.
  Statement& q = db.Prepare(
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
  // No point although the series has results: a metric no result has is a name mistyped (a
  // trend that is empty is not one that stayed flat).
  if (out["points"].empty() && out["total"].get<std::int64_t>() > 0) {
    const std::vector<std::string> known = SeriesMetrics(db, key, value);
    if (!known.empty() && std::find(known.begin(), known.end(), metric) == known.end()) {
      throw std::invalid_argument("metric: '" + metric + "': no result of the jobs labelled " + key + "=" + value +
                                  " has it" + Suggestion(metric, known));
    }
  }
  return out;
}

}  // namespace enavi::server
