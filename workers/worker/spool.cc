#include "workers/worker/spool.h"

#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "api/atomic_file.h"

namespace enavi::worker {

namespace fs = std::filesystem;

ResultSpool::ResultSpool(std::filesystem::path dir) : dir_(std::move(dir)) {
  fs::create_directories(dir_);
}

fs::path ResultSpool::FileFor(const std::string& episode_id, int attempt) const {
  return dir_ / (episode_id + "." + std::to_string(attempt) + ".result.json");
}

void ResultSpool::Save(const api::ResultMessage& message) {
  api::WriteFileAtomic(FileFor(message.episode_id, message.attempt), api::ToJson(message).dump());
}

void ResultSpool::Remove(const std::string& episode_id, int attempt) {
  std::error_code ec;
  fs::remove(FileFor(episode_id, attempt), ec);
}

std::vector<api::ResultMessage> ResultSpool::LoadAll(std::vector<std::string>* problems) {
  std::vector<api::ResultMessage> out;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    const std::string name = entry.path().filename().string();
    if (name.ends_with(".result.json")) files.push_back(entry.path());
    // A write cut off by a crash (the atomic write's temporary): the result was never sent (Send
    // spools before it publishes), so its episode's lease runs out and it runs again elsewhere.
    if (name.ends_with(".result.json.tmp")) {
      if (problems) problems->push_back(entry.path().string() + ": an interrupted write, removed");
      std::error_code ec;
      fs::remove(entry.path(), ec);
    }
  }
  std::sort(files.begin(), files.end());
  for (const auto& file : files) {
    try {
      std::ifstream in(file, std::ios::binary);
      out.push_back(api::ResultMessageFromJson(nlohmann::json::parse(in)));
    } catch (const std::exception& e) {
      if (problems) problems->push_back(file.string() + ": " + e.what());
      std::error_code ec;
      fs::rename(file, file.string() + ".bad", ec);
    }
  }
  return out;
}

}  // namespace enavi::worker
