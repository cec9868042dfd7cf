#pragma once
// On-disk copies of results the server has not acknowledged yet: one JSON file per attempt,
// written atomically (temp file, fsync, rename), removed on acknowledgement, read back when a
// worker restarts so nothing it finished is lost.

#include <filesystem>
#include <string>
#include <vector>

#include "api/farm_messages.h"

namespace enavi::worker {

class ResultSpool {
 public:
  /// Creates `dir` if needed.
  explicit ResultSpool(std::filesystem::path dir);

  void Save(const api::ResultMessage& message);
  void Remove(const std::string& episode_id, int attempt);
  /// Every spooled result; unreadable files are renamed to *.bad, temporaries of interrupted
  /// writes removed, both reported in `problems`.
  std::vector<api::ResultMessage> LoadAll(std::vector<std::string>* problems);
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path FileFor(const std::string& episode_id, int attempt) const;
  std::filesystem::path dir_;
};

}  // namespace enavi::worker
