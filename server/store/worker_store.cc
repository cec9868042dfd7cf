#include "server/store/worker_store.h"

#include "server/store/connection.h"
#include "server/store/schema.h"

namespace enavi::server {

void WorkerStore::RecordWorker(const api::WorkerStatus& s, std::int64_t now_ms) {
  std::lock_guard lock(c_.mutex);
  c_.db.Prepare(
         "INSERT INTO workers (worker_id, host, version, calibration_id, slots, boards, "
         "first_seen_ms, last_seen_ms) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?7) "
         "ON CONFLICT (worker_id) DO UPDATE SET host = ?2, version = ?3, calibration_id = ?4, "
         "slots = ?5, boards = ?6, last_seen_ms = ?7")
      .Bind(1, s.worker_id).Bind(2, s.host).Bind(3, s.version).Bind(4, s.calibration_id)
      .Bind(5, s.slots).Bind(6, nlohmann::json(s.boards).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)).Bind(7, now_ms).Run();
}

nlohmann::json WorkerStore::KnownWorkers() {
  std::lock_guard lock(c_.mutex);
  nlohmann::json list = nlohmann::json::array();
  if (!HasColumn(c_.db, "workers", "host")) return list;
  Statement& q = c_.db.Prepare(
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
