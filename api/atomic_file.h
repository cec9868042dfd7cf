#pragma once
// The one way files are written whole or not at all (docs/design.md, "Reliability rules"; after
// SQLite's os_unix.c, which syncs file and directory on one path): a reader, or the machine
// after a crash, sees the old file or the new one, never a part of either.

#include <filesystem>
#include <string_view>

namespace enavi::api {

/// Writes `bytes` to `PATH.tmp`, fsyncs it, renames it over `path` and fsyncs the directory, so
/// the rename survives a crash too. The directory must exist.
/// @throws std::runtime_error naming the file and the system's reason; the temporary file is
/// removed and `path` is left as it was.
void WriteFileAtomic(const std::filesystem::path& path, std::string_view bytes);

}  // namespace enavi::api
