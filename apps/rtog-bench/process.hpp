// rtog-bench's child processes (the fresh-process rows, the chunked builds): the one place that
// starts them.
#pragma once

#include <string>
#include <sys/types.h>
#include <vector>

namespace rtog::bench {

/// Starts argv[0] with `args`; its stdout goes to `stdout_fd` (-1: /dev/null), its stderr to ours.
/// Throws std::runtime_error if it cannot start.
pid_t startProcess(const std::vector<std::string>& args, int stdout_fd = -1);
/// Waits for `pid`; throws std::runtime_error naming `what` unless it exited with 0.
void waitSucceeded(pid_t pid, const std::string& what);
/// Runs argv[0] and returns what it printed on stdout; throws as the two above.
std::string runCapturingStdout(const std::vector<std::string>& args, const std::string& what);

}  // namespace rtog::bench
