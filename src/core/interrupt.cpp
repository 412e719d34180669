#include "hypershape/core/interrupt.hpp"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstring>

namespace hypershape::core {

namespace {

// Only async-signal-safe state: fixed buffers, atomics, no allocation in the handler.
constexpr int n_slots = 16;
constexpr std::size_t path_max = 4096;
char paths[n_slots][path_max];
std::atomic<bool> used[n_slots];
char message[512];
std::size_t message_len = 0;
bool installed = false;
struct sigaction previous_int, previous_term;

void on_signal(int sig) {
  for (int i = 0; i < n_slots; ++i)
    if (used[i].load()) ::unlink(paths[i]);
  if (message_len) {
    const char* name = sig == SIGINT ? "SIGINT" : "SIGTERM";
    ssize_t ignored = ::write(STDERR_FILENO, message, message_len);
    ignored = ::write(STDERR_FILENO, name, std::strlen(name));
    static constexpr char tail[] =
        ": complete shards are kept, no temporary file is left; run the same command again to resume\n";
    ignored = ::write(STDERR_FILENO, tail, sizeof tail - 1);
    (void)ignored;
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

}  // namespace

void install_interrupt_handlers(const std::string& what, int rank) {
  const std::string m = rank == 0 ? "[" + what + "] stopped by " : "";
  message_len = std::min(m.size(), sizeof message);
  std::memcpy(message, m.data(), message_len);
  if (installed) return;
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, &previous_int);
  sigaction(SIGTERM, &sa, &previous_term);
  installed = true;
}

void remove_interrupt_handlers() {
  if (!installed) return;
  sigaction(SIGINT, &previous_int, nullptr);
  sigaction(SIGTERM, &previous_term, nullptr);
  installed = false;
}

int register_temporary(const std::string& path) {
  if (path.size() >= path_max) return -1;
  for (int i = 0; i < n_slots; ++i) {
    if (used[i].load()) continue;
    std::memcpy(paths[i], path.c_str(), path.size() + 1);
    used[i].store(true);
    return i;
  }
  return -1;
}

void unregister_temporary(int slot) {
  if (slot >= 0 && slot < n_slots) used[slot].store(false);
}

}  // namespace hypershape::core
