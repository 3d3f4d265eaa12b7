#include "temporaries.hpp"

#include <signal.h>
#include <stdlib.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <mutex>

namespace rtog::app::temporaries {
namespace {

constexpr int kSlots = 64;
constexpr std::size_t kPathBytes = 4096;
constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};

// A slot's path is written before its flag is set, and the flag cleared before the slot is
// reused: the handler reads only slots whose flag it sees set.
char g_paths[kSlots][kPathBytes];
std::atomic<int> g_used[kSlots];
std::mutex g_mutex;  // between threads registering (never taken by the handler)

static_assert(std::atomic<int>::is_always_lock_free, "the handler reads the flags");

extern "C" void removeTemporaries(int sig) {
  const int saved = errno;
  for (int i = 0; i < kSlots; ++i)
    if (g_used[i].load(std::memory_order_acquire)) ::unlink(g_paths[i]);
  // Die of the signal, as without the handler: the caller sees how the process ended.
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  ::sigaction(sig, &dfl, nullptr);
  ::raise(sig);
  errno = saved;
}

void installOnce() {
  static const bool installed = [] {
    for (const int sig : kSignals) {
      struct sigaction old {};
      if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) continue;
      if (old.sa_handler != SIG_DFL) continue;  // the program's own handler stays
      struct sigaction sa {};
      sa.sa_handler = removeTemporaries;
      sigemptyset(&sa.sa_mask);
      for (const int other : kSignals) sigaddset(&sa.sa_mask, other);
      ::sigaction(sig, &sa, nullptr);
    }
    return true;
  }();
  (void)installed;
}

sigset_t handledSignals() {
  sigset_t s;
  sigemptyset(&s);
  for (const int sig : kSignals) sigaddset(&s, sig);
  return s;
}

}  // namespace

int create(std::string& tmpl, int flags) {
  installOnce();
  const sigset_t held = handledSignals();
  sigset_t old;
  ::pthread_sigmask(SIG_BLOCK, &held, &old);
  const int fd = ::mkostemp(tmpl.data(), flags);
  const int err = errno;
  if (fd >= 0 && tmpl.size() < kPathBytes) {
    const std::lock_guard<std::mutex> lock(g_mutex);
    for (int i = 0; i < kSlots; ++i)
      if (!g_used[i].load(std::memory_order_relaxed)) {
        std::memcpy(g_paths[i], tmpl.c_str(), tmpl.size() + 1);
        g_used[i].store(1, std::memory_order_release);
        break;
      }
  }
  ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
  errno = err;
  return fd;
}

void forget(const std::string& path) {
  const std::lock_guard<std::mutex> lock(g_mutex);
  for (int i = 0; i < kSlots; ++i)
    if (g_used[i].load(std::memory_order_relaxed) && path == g_paths[i]) g_used[i].store(0, std::memory_order_release);
}

HoldSignals::HoldSignals() {
  static_assert(sizeof(old_) >= sizeof(sigset_t), "room for a sigset_t");
  const sigset_t held = handledSignals();
  ::pthread_sigmask(SIG_BLOCK, &held, reinterpret_cast<sigset_t*>(old_));
}

HoldSignals::~HoldSignals() { ::pthread_sigmask(SIG_SETMASK, reinterpret_cast<const sigset_t*>(old_), nullptr); }

}  // namespace rtog::app::temporaries
