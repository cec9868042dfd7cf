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
    if (name.size() > 12 && name.compare(name.size() - 12, 12, ".result.json") == 0) {
      files.push_back(entry.path());
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
