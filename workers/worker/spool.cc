#include "workers/worker/spool.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace enavi::worker {
namespace {

namespace fs = std::filesystem;

void WriteDurably(const fs::path& path, const std::string& data) {
  const fs::path tmp = path.string() + ".tmp";
  const int fd = open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("spool: cannot write " + tmp.string() + ": " + std::strerror(errno));
  std::size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = write(fd, data.data() + done, data.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      close(fd);
      throw std::runtime_error("spool: write " + tmp.string() + ": " + std::strerror(err));
    }
    done += static_cast<std::size_t>(n);
  }
  if (fsync(fd) != 0 || close(fd) != 0) {
    throw std::runtime_error("spool: fsync " + tmp.string() + ": " + std::strerror(errno));
  }
  fs::rename(tmp, path);
  // The rename itself must survive a crash: sync the directory.
  const int dir = open(path.parent_path().c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir >= 0) {
    fsync(dir);
    close(dir);
  }
}

}  // namespace

ResultSpool::ResultSpool(std::filesystem::path dir) : dir_(std::move(dir)) {
  fs::create_directories(dir_);
}

fs::path ResultSpool::FileFor(const std::string& episode_id, int attempt) const {
  return dir_ / (episode_id + "." + std::to_string(attempt) + ".result.json");
}

void ResultSpool::Save(const api::ResultMessage& message) {
  WriteDurably(FileFor(message.episode_id, message.attempt), api::ToJson(message).dump());
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
