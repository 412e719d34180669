#pragma once
/// Small text-file helpers of the factory (internal): whole-file reads, and writes that appear
/// atomically (temporary name with the pid, written, fsynced, then renamed), so a reader never
/// sees half a file and a full disk leaves nothing behind but a clear error.
#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "hypershape/core/interrupt.hpp"

namespace hypershape::factory::detail {

inline std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Writes all of `text` to a new file `path` and fsyncs it; false (errno set) on failure.
inline bool write_file(const std::string& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) return false;
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    done += std::size_t(n);
  }
  const bool ok = done == text.size() && ::fsync(fd) == 0;
  const int saved = errno;
  const bool closed = ::close(fd) == 0;
  errno = ok ? errno : saved;
  return ok && closed;
}

/// Throws std::runtime_error naming the file and the system's reason (e.g. no space left).
inline void write_atomically(const std::filesystem::path& path, const std::string& text) {
  const std::string tmp = path.string() + fmt::format(".tmp-{}", ::getpid());
  core::TemporaryFile guard(tmp);
  if (!write_file(tmp, text)) {
    const std::string why = std::strerror(errno);
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error("cannot write " + path.string() + ": " + why);
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace hypershape::factory::detail
