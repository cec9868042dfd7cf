#include "workers/emulation/cgroup_files.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

namespace enavi::emulation::cgroupfs {

std::string Join(const std::string& dir, const std::string& name) {
  if (dir.empty()) return name;
  if (dir.back() == '/') return dir + name;
  return dir + "/" + name;
}

std::string MountPlusPath(const std::string& mount, const std::string& path) {
  if (path.empty() || path == "/") return mount;
  return mount + (path.front() == '/' ? path : "/" + path);
}

bool Exists(const std::string& path) {
  struct stat st{};
  return stat(path.c_str(), &st) == 0;
}

bool IsDir(const std::string& path) {
  struct stat st{};
  return stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

bool ReadFile(const std::string& path, std::string* out) {
  std::ifstream in(path);
  if (!in) return false;
  std::stringstream ss;
  ss << in.rdbuf();
  *out = ss.str();
  return true;
}

std::string Trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  std::size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  return s.substr(i);
}

std::string ReadTrimmed(const std::string& path) {
  std::string s;
  if (!ReadFile(path, &s)) return {};
  return Trim(s);
}

CgroupStatus WriteValue(const std::string& path, const std::string& value, bool create) {
  const int flags = O_WRONLY | O_CLOEXEC | (create ? (O_CREAT | O_TRUNC) : 0);
  const int fd = open(path.c_str(), flags, 0644);
  if (fd < 0) {
    return {false, "cannot open " + path + " for writing: " + std::strerror(errno)};
  }
  const ssize_t n = write(fd, value.data(), value.size());
  const int err = errno;
  close(fd);
  if (n != static_cast<ssize_t>(value.size())) {
    return {false, "writing '" + value + "' to " + path + ": " + std::strerror(err)};
  }
  return {};
}

std::vector<std::string> Subdirs(const std::string& dir) {
  std::vector<std::string> names;
  DIR* d = opendir(dir.c_str());
  if (d == nullptr) return names;
  while (dirent* e = readdir(d)) {
    const std::string name = e->d_name;
    if (name == "." || name == "..") continue;
    if (IsDir(Join(dir, name))) names.push_back(name);
  }
  closedir(d);
  return names;
}

std::vector<pid_t> ReadPids(const std::string& path) {
  std::vector<pid_t> pids;
  std::ifstream in(path);
  long v = 0;
  while (in >> v) pids.push_back(static_cast<pid_t>(v));
  return pids;
}

std::set<std::string> Words(const std::string& s) {
  std::set<std::string> words;
  std::istringstream in(s);
  std::string w;
  while (in >> w) words.insert(w);
  return words;
}

}  // namespace enavi::emulation::cgroupfs
