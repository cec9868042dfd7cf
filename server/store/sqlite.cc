#include "server/store/sqlite.h"

#include <signal.h>
#include <sqlite3.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>

namespace enavi::server {
namespace {

// Test hook of the fault tests (tests/fault, docs/reliability.md): with
// ENAVI_TEST_KILL_AFTER_SQLITE_STEPS=N the process SIGKILLs itself at its N-th SQLite step
// (sqlite3_step or sqlite3_exec: a statement, a row, a COMMIT) inside a transaction, so the kill
// lands in the middle of a store transition. Unset (the default): off.
long KillAfterSteps() {
  static const long n = [] {
    const char* v = std::getenv("ENAVI_TEST_KILL_AFTER_SQLITE_STEPS");
    return v != nullptr && *v != '\0' ? std::atol(v) : 0L;
  }();
  return n;
}

void CountStep(sqlite3* db) {
  static std::atomic<long> steps{0};
  if (KillAfterSteps() <= 0 || sqlite3_get_autocommit(db) || ++steps != KillAfterSteps()) return;
  std::fprintf(stderr, "ENAVI_TEST_KILL_AFTER_SQLITE_STEPS: SIGKILL at step %ld inside a transaction\n",
               steps.load());
  std::fflush(stderr);
  raise(SIGKILL);
}

[[noreturn]] void Fail(sqlite3* db, int rc, const std::string& what) {
  const char* msg = db != nullptr ? sqlite3_errmsg(db) : sqlite3_errstr(rc);
  throw StoreError("sqlite: " + what + ": " + msg + " (" + sqlite3_errstr(rc) + ")");
}

}  // namespace

Statement::Statement(sqlite3* db, const std::string& sql) : db_(db), sql_(sql) {
  const int rc = sqlite3_prepare_v2(db_, sql.c_str(), static_cast<int>(sql.size()), &stmt_, nullptr);
  if (rc != SQLITE_OK) Fail(db_, rc, "prepare '" + sql + "'");
}

Statement::~Statement() { sqlite3_finalize(stmt_); }

Statement& Statement::Reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
  return *this;
}

Statement& Statement::Bind(int index, std::int64_t value) {
  const int rc = sqlite3_bind_int64(stmt_, index, value);
  if (rc != SQLITE_OK) Fail(db_, rc, "bind in '" + sql_ + "'");
  return *this;
}

Statement& Statement::Bind(int index, double value) {
  const int rc = sqlite3_bind_double(stmt_, index, value);
  if (rc != SQLITE_OK) Fail(db_, rc, "bind in '" + sql_ + "'");
  return *this;
}

Statement& Statement::Bind(int index, std::string_view text) {
  const int rc = sqlite3_bind_text64(stmt_, index, text.data(), text.size(), SQLITE_TRANSIENT,
                                     SQLITE_UTF8);
  if (rc != SQLITE_OK) Fail(db_, rc, "bind in '" + sql_ + "'");
  return *this;
}

Statement& Statement::BindBlob(int index, const std::vector<std::uint8_t>& blob) {
  const int rc = sqlite3_bind_blob64(stmt_, index, blob.data(), blob.size(), SQLITE_TRANSIENT);
  if (rc != SQLITE_OK) Fail(db_, rc, "bind in '" + sql_ + "'");
  return *this;
}

Statement& Statement::BindNull(int index) {
  const int rc = sqlite3_bind_null(stmt_, index);
  if (rc != SQLITE_OK) Fail(db_, rc, "bind in '" + sql_ + "'");
  return *this;
}

bool Statement::Step() {
  CountStep(db_);
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  Fail(db_, rc, "step '" + sql_ + "'");
}

void Statement::Run() {
  while (Step()) {
  }
}

bool Statement::IsNull(int column) const {
  return sqlite3_column_type(stmt_, column) == SQLITE_NULL;
}
std::int64_t Statement::Int(int column) const { return sqlite3_column_int64(stmt_, column); }
double Statement::Double(int column) const { return sqlite3_column_double(stmt_, column); }
std::string Statement::Text(int column) const {
  const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, column));
  return p == nullptr ? std::string() : std::string(p, sqlite3_column_bytes(stmt_, column));
}
std::vector<std::uint8_t> Statement::Blob(int column) const {
  const auto* p = static_cast<const std::uint8_t*>(sqlite3_column_blob(stmt_, column));
  return p == nullptr ? std::vector<std::uint8_t>()
                      : std::vector<std::uint8_t>(p, p + sqlite3_column_bytes(stmt_, column));
}

Database::Database(const std::filesystem::path& path, int busy_timeout_ms, bool read_only) {
  const int flags = (read_only ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE) |
                    SQLITE_OPEN_NOMUTEX;
  const int rc = sqlite3_open_v2(path.c_str(), &db_, flags, nullptr);
  if (rc != SQLITE_OK) {
    const std::string msg = db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(rc);
    sqlite3_close(db_);
    throw StoreError("sqlite: cannot open '" + path.string() + "': " + msg);
  }
  sqlite3_busy_timeout(db_, busy_timeout_ms);
  if (read_only) return;
  // WAL: readers do not block the writer; FULL: a committed result survives power loss.
  Exec("PRAGMA journal_mode=WAL");
  Exec("PRAGMA synchronous=FULL");
  Exec("PRAGMA foreign_keys=ON");
}

Database::~Database() {
  cache_.clear();  // finalize statements before closing
  sqlite3_close(db_);
}

void Database::Exec(const std::string& sql) {
  CountStep(db_);
  char* err = nullptr;
  const int rc = sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err);
  if (rc != SQLITE_OK) {
    const std::string msg = err ? err : sqlite3_errstr(rc);
    sqlite3_free(err);
    throw StoreError("sqlite: '" + sql.substr(0, 80) + "': " + msg);
  }
}

Statement& Database::Prepare(const std::string& sql) {
  auto it = cache_.find(sql);
  if (it == cache_.end()) it = cache_.emplace(sql, std::make_unique<Statement>(db_, sql)).first;
  return it->second->Reset();
}

std::int64_t Database::Changes() const { return sqlite3_changes64(db_); }

Transaction::Transaction(Database& db) : db_(db) { db_.Exec("BEGIN IMMEDIATE"); }

Transaction::~Transaction() {
  if (open_) {
    try {
      db_.Exec("ROLLBACK");
    } catch (...) {
    }
  }
}

void Transaction::Commit() {
  db_.Exec("COMMIT");
  open_ = false;
}

}  // namespace enavi::server
