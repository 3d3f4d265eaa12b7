// The temporaries of OutputSet (output_files.cpp) that a signal must not leave behind: on SIGINT,
// SIGTERM or SIGHUP the process removes them, then dies of the signal as it would have. The
// handler only reads a fixed table (no allocation, no locks: async-signal-safe), filled before
// each temporary is created and cleared when it is renamed or removed.
#pragma once

#include <string>

namespace rtog::app::temporaries {

/// Installs the handlers (once; a signal the process ignores, as under nohup, stays ignored),
/// then creates a temporary from `tmpl` (mkostemp) and registers it, signals held off between
/// the two so that no temporary exists unregistered. Returns the descriptor, or -1 (errno set).
/// A full table (64 temporaries at once) or a path over 4,095 bytes: created, not registered.
int create(std::string& tmpl, int flags);

/// The temporary at `path` is gone or about to be renamed away: no longer removed by a signal.
void forget(const std::string& path);

/// Holds SIGINT, SIGTERM and SIGHUP off for its lifetime (the renames of a commit are all done or
/// all undone, which a handler cannot do); a signal that came meanwhile is delivered after.
class HoldSignals {
 public:
  HoldSignals();
  ~HoldSignals();
  HoldSignals(const HoldSignals&) = delete;
  HoldSignals& operator=(const HoldSignals&) = delete;

 private:
  unsigned long long old_[16];  // a sigset_t (128 bytes on Linux) without <signal.h> here
};

}  // namespace rtog::app::temporaries
