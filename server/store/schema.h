#pragma once
// The store's tables: schema version 1 and the additive migrations since (docs/dashboard.md,
// "Aggregates"). A database written by an older build gains the new tables and columns when a
// writer opens it; a read-only opening changes nothing, so readers ask HasColumn first.

#include <string>

namespace enavi::server {

class Database;

inline constexpr int kStoreSchemaVersion = 1;

/// Refuses a database this build cannot read: a newer schema version, or (read_only) a file
/// without the jobs table. @throws StoreError naming `path`.
void CheckSchema(Database& db, const std::string& path, bool read_only);

/// Creates what a database lacks and migrates an older one, in one transaction.
void CreateOrMigrateSchema(Database& db);

/// Whether `table` has `column` (false when the table does not exist).
bool HasColumn(Database& db, const std::string& table, const std::string& column);

}  // namespace enavi::server
