#pragma once
/// SIGINT / SIGTERM during a run that writes files: the handler removes the files registered as
/// temporary (a shard being written, a manifest being replaced, the run's lock), prints one line
/// on rank 0 and ends the process with the signal's usual status (128 + signal). What is
/// complete on disk stays (shards appear by rename), so the same command resumes the run.
#include <string>

namespace hypershape::core {

/// Installs the handlers (idempotent); `what` is the run's name in the message, `rank` the
/// caller's rank (only rank 0 prints). Not collective.
void install_interrupt_handlers(const std::string& what, int rank);
/// Restores the handlers that were there before install_interrupt_handlers.
void remove_interrupt_handlers();

/// Registers a path the handler removes (a file in the making). Returns a slot for
/// unregister_temporary; at most 16 at a time (further ones are not registered: -1).
int register_temporary(const std::string& path);
void unregister_temporary(int slot);

/// A registered temporary path for the lifetime of the guard.
class TemporaryFile {
 public:
  explicit TemporaryFile(const std::string& path) : slot_(register_temporary(path)) {}
  ~TemporaryFile() { unregister_temporary(slot_); }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;

 private:
  int slot_;
};

}  // namespace hypershape::core
