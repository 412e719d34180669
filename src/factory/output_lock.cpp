#include "hypershape/factory/output_lock.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <ctime>
#include <filesystem>
#include <regex>

#include "hypershape/core/input_error.hpp"
#include "hypershape/core/interrupt.hpp"
#include "text_file.hpp"

namespace hypershape::factory {

namespace fs = std::filesystem;

namespace {

/// An flock held on `path` (the file may be created), or -1 if another process holds it. A
/// file unlinked between open and flock is retried, so two runs never lock different inodes.
int try_lock(const std::string& path, bool create) {
  for (int attempt = 0; attempt < 10; ++attempt) {
    const int fd = ::open(path.c_str(), O_RDWR | (create ? O_CREAT : 0) | O_CLOEXEC, 0644);
    if (fd < 0) return -1;
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd);
      return -1;
    }
    struct stat a {}, b {};
    if (::fstat(fd, &a) == 0 && ::stat(path.c_str(), &b) == 0 && a.st_ino == b.st_ino) return fd;
    ::close(fd);  // unlinked by its former holder meanwhile: lock the new file
    if (!create) return -1;
  }
  return -1;
}

std::string holder(const std::string& path) {
  std::string h = detail::read_text(path);
  while (!h.empty() && (h.back() == '\n' || h.back() == ' ')) h.pop_back();
  return h.empty() ? "a run that has not written its name yet" : h;
}

std::string host_name() {
  char host[256] = "?";
  ::gethostname(host, sizeof host - 1);
  return host;
}

[[noreturn]] void refuse(const std::string& dir, const std::string& who, const std::string& why) {
  throw core::InputError("", "-o", fmt::format("{} is being written by another run ({}){}; wait for it to "
                                               "finish or stop it (its lock is released when it ends)",
                                               dir, who, why));
}

}  // namespace

OutputLock::OutputLock(const std::string& dir, int task_index, int task_count) {
  const fs::path locks = fs::path(dir) / ".locks";
  std::error_code ec;
  fs::create_directories(locks, ec);
  const std::string mine = fmt::format("task-{}-of-{}.lock", task_index, task_count);
  path_ = (locks / mine).string();
  const bool left_behind = fs::exists(path_, ec);
  fd_ = try_lock(path_, true);
  if (fd_ < 0) refuse(dir, holder(path_), "");
  if (left_behind) note_ += fmt::format("took over the stale lock {} ({})\n", mine, holder(path_));
  char since[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(since, sizeof since, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&now));
  const std::string me = fmt::format("host {}, pid {}, task {} of {}, since {}\n", host_name(), ::getpid(),
                                     task_index, task_count, since);
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, me.data(), me.size(), 0) != ssize_t(me.size())) {
    // A lock we cannot describe still excludes others; the disk may be full (reported later).
  }
  slot_ = core::register_temporary(path_);
  // Other slices: the same task count is a disjoint slice; any other count overlaps.
  static const std::regex name(R"(task-(\d+)-of-(\d+)\.lock)");
  for (const auto& e : fs::directory_iterator(locks, ec)) {
    std::smatch m;
    const std::string f = e.path().filename().string();
    if (f == mine || !std::regex_match(f, m, name)) continue;
    const int other = try_lock(e.path().string(), false);
    if (other < 0) {
      if (std::stoi(m[2]) == task_count) continue;  // a live task of the same array
      const std::string who = holder(e.path().string());
      release();
      refuse(dir, who, fmt::format(", whose --task-count is not {}: the slices would overlap", task_count));
    }
    note_ += fmt::format("took over the stale lock {} ({})\n", f, holder(e.path().string()));
    fs::remove(e.path(), ec);
    ::close(other);
  }
}

OutputLock::~OutputLock() { release(); }

void OutputLock::release() {
  if (fd_ < 0) return;
  core::unregister_temporary(slot_);
  std::error_code ec;
  fs::remove(path_, ec);
  ::close(fd_);
  fd_ = -1;
}

}  // namespace hypershape::factory
