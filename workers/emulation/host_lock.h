#pragma once
// The host-wide lock of the cgroup code: admission and the creation and removal of the `enavi`
// parent are serialised among the workers of one host (flock(2) on a lock file).

#include <string>

namespace enavi::emulation {

/// Holds an exclusive flock on `path` for its lifetime; error() says why it could not.
class HostLock {
 public:
  explicit HostLock(const std::string& path);
  ~HostLock();
  HostLock(const HostLock&) = delete;
  HostLock& operator=(const HostLock&) = delete;
  const std::string& error() const { return error_; }

 private:
  int fd_ = -1;
  std::string error_;
};

}  // namespace enavi::emulation
