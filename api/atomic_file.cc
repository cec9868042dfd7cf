#include "api/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

namespace enavi::api {
namespace {

[[noreturn]] void Fail(const std::string& what, const std::filesystem::path& file, int err) {
  throw std::runtime_error("cannot write " + file.string() + ": " + what + ": " + std::strerror(err));
}

}  // namespace

void WriteFileAtomic(const std::filesystem::path& path, std::string_view bytes) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  const int fd = open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) Fail("open " + tmp.string(), path, errno);
  // Any failure before the rename leaves `path` untouched and removes the temporary file.
  auto abandon = [&](const std::string& what) {
    const int err = errno;
    close(fd);
    std::remove(tmp.c_str());
    Fail(what, path, err);
  };
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      abandon("write");
    }
    done += static_cast<std::size_t>(n);
  }
  if (fsync(fd) != 0) abandon("fsync");
  if (close(fd) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    Fail("close", path, err);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    Fail("rename from " + tmp.string(), path, err);
  }
  // The rename is an entry of the directory: sync it so the new file survives a crash.
  const std::filesystem::path parent = path.has_parent_path() ? path.parent_path() : ".";
  const int dir = open(parent.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir < 0) Fail("open directory " + parent.string(), path, errno);
  const int rc = fsync(dir);
  const int err = errno;
  close(dir);
  if (rc != 0) Fail("fsync directory " + parent.string(), path, err);
}

}  // namespace enavi::api
