#pragma once
// A thin RAII layer over the SQLite C API for the store: a connection, cached prepared
// statements and IMMEDIATE transactions. Errors throw StoreError naming the SQL.
// Fault tests only: ENAVI_TEST_KILL_AFTER_SQLITE_STEPS=N makes the process SIGKILL itself at its
// N-th step inside a transaction (docs/reliability.md); unset, nothing happens.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

namespace enavi::server {

class StoreError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Statement {
 public:
  Statement(sqlite3* db, const std::string& sql);
  ~Statement();
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  /// Clears bindings and resets, ready to bind parameters 1..n again.
  Statement& Reset();
  Statement& Bind(int index, std::int64_t value);
  Statement& Bind(int index, int value) { return Bind(index, static_cast<std::int64_t>(value)); }
  Statement& Bind(int index, double value);
  Statement& Bind(int index, std::string_view text);
  Statement& Bind(int index, const char* text) { return Bind(index, std::string_view(text)); }
  Statement& Bind(int index, const std::string& text) { return Bind(index, std::string_view(text)); }
  Statement& BindBlob(int index, const std::vector<std::uint8_t>& blob);
  Statement& BindNull(int index);

  /// Steps once: true while a row is available.
  bool Step();
  /// Steps to completion (statements without rows).
  void Run();

  bool IsNull(int column) const;
  std::int64_t Int(int column) const;
  double Double(int column) const;
  std::string Text(int column) const;
  std::vector<std::uint8_t> Blob(int column) const;

 private:
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
  std::string sql_;
};

class Database {
 public:
  /// Opens (creating) the database file with WAL journaling, synchronous=FULL and a busy timeout;
  /// `read_only`: opens an existing file without write access (nothing is created or changed).
  Database(const std::filesystem::path& path, int busy_timeout_ms, bool read_only = false);
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  void Exec(const std::string& sql);
  /// A prepared statement kept for the connection's lifetime, reset and ready to bind.
  Statement& Prepare(const std::string& sql);
  std::int64_t Changes() const;
  sqlite3* handle() const { return db_; }

 private:
  sqlite3* db_ = nullptr;
  std::map<std::string, std::unique_ptr<Statement>> cache_;
};

/// BEGIN IMMEDIATE ... COMMIT; rolls back when destroyed without Commit().
class Transaction {
 public:
  explicit Transaction(Database& db);
  ~Transaction();
  void Commit();

 private:
  Database& db_;
  bool open_ = true;
};

}  // namespace enavi::server
