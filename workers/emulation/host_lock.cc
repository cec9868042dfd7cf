#include "workers/emulation/host_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace enavi::emulation {

HostLock::HostLock(const std::string& path) {
  fd_ = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    error_ = "cannot open lock file " + path + ": " + std::strerror(errno);
    return;
  }
  while (flock(fd_, LOCK_EX) != 0) {
    if (errno != EINTR) {
      error_ = "cannot lock " + path + ": " + std::strerror(errno);
      return;
    }
  }
}

HostLock::~HostLock() {
  if (fd_ >= 0) close(fd_);  // releases the lock
}

}  // namespace enavi::emulation
