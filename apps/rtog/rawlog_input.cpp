// `rtog build --rawlog` / `--simplemap`: an MRPT archive file read entry by entry, its damage
// found and named.
//
// MRPT's CRawlog::loadFromRawLogFile stops at the first entry it cannot read and keeps the ones
// before: a truncated or corrupt log reads as a shorter one, silently. And each class's reader
// sizes its buffers from the counts the file states before it reads a byte of them: a scan
// announcing 2^32 - 1 beams in a 179-byte file makes MRPT zero-fill gigabytes (or write through
// the null pointer its aligned allocator returns when that fails). rtog cannot check every
// class's counts from outside, so a child process reads the log first, with its address space
// bounded entry by entry by the bytes left in the file; a count the file cannot hold makes the
// allocation fail there, and the child names the entry. The tool reads the log only if it passed.
// A simplemap file is the same kind of file (one entry: the whole CSimpleMap), checked the same way.
#include <sys/resource.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include "build_log.hpp"
#include "gzip.hpp"

namespace rtog::cli {
namespace {

/// What an MRPT exception says, in one line: the objects it was reading, outermost first, and
/// the innermost message (its text nests one banner, message and backtrace per object).
std::string reason(const std::string& what) {
  std::istringstream in(what);
  std::string line, chain, last;
  const std::string typed = "Exception while parsing typed object '";
  while (std::getline(in, line)) {
    if (line.rfind("Message:", 0) != 0) continue;
    const auto a = line.find_first_not_of(' ', 8);
    if (a == std::string::npos) continue;
    line = line.substr(a);
    if (line.rfind(typed, 0) == 0) {
      const std::string name = line.substr(typed.size(), line.find('\'', typed.size()) - typed.size());
      if (name.find(' ') == std::string::npos) chain += (chain.empty() ? "" : " > ") + name;
      continue;
    }
    last = line;
  }
  if (last.empty()) {  // not an MRPT exception: its first line
    last = what.substr(0, what.find('\n'));
  }
  return chain.empty() ? last : "in " + chain + ": " + last;
}

/// The address space this process maps now [bytes].
std::uint64_t mappedBytes() {
  std::ifstream statm("/proc/self/statm");
  std::uint64_t pages = 0;
  statm >> pages;
  return pages * static_cast<std::uint64_t>(sysconf(_SC_PAGESIZE));
}

void say(int fd, const std::string& s) {
  std::size_t done = 0;
  while (done < s.size()) {
    const ssize_t w = write(fd, s.data() + done, s.size() - done);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return;
    done += static_cast<std::size_t>(w);
  }
}

/// In the child: every entry read under an address-space bound of what it may need (twice the
/// bytes left, plus 64 MiB for MRPT's own tables), one line per entry to `fd` before it is read.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif

[[noreturn]] void checkEntries(const std::string& path, std::uint64_t total, int fd) {
  const rlimit no_core{0, 0};
  setrlimit(RLIMIT_CORE, &no_core);  // a crash here is an answer, not something to keep
  // So is what a crash prints (a sanitizer's report, MRPT's messages): the parent says what
  // happened, in one line.
  if (const int null = open("/dev/null", O_WRONLY); null >= 0) dup2(null, STDERR_FILENO);
  std::size_t entry = 0;
  try {
    mrpt::io::CFileGZInputStream f(path);
    auto ar = mrpt::serialization::archiveFrom(f);
    for (;; ++entry) {
      const std::uint64_t at = f.getPosition();
      if (at >= total) break;
      say(fd, "at " + std::to_string(entry) + " " + std::to_string(at) + "\n");
      // The soft limit only: it may rise again for the next entry.
      rlimit lim{};
      const std::uint64_t mapped = mappedBytes();
      // AddressSanitizer reserves terabytes of address space for its shadow, which no cap on
      // it leaves room for; its build bounds single allocations instead (.ci/asan:
      // max_allocation_size_mb, allocator_may_return_null: a refused one is std::bad_alloc).
      if (!kAddressSanitizer && mapped > 0 && getrlimit(RLIMIT_AS, &lim) == 0) {
        lim.rlim_cur = static_cast<rlim_t>(mapped + 2 * (total - at) + (std::uint64_t{64} << 20));
        if (lim.rlim_max != RLIM_INFINITY && lim.rlim_cur > lim.rlim_max) lim.rlim_cur = lim.rlim_max;
        setrlimit(RLIMIT_AS, &lim);
      }
      try {
        ar.ReadObject();
      } catch (const std::bad_alloc&) {
        say(fd, "memory\n");
        _exit(1);
      } catch (const std::exception& e) {
        // MRPT wraps what its readers throw: an allocation refused (or a size beyond a vector's
        // max_size) is known by its text.
        const std::string w = e.what();
        if (w.find("bad_alloc") != std::string::npos || w.find("max_size") != std::string::npos ||
            w.find("_M_default_append") != std::string::npos) {
          say(fd, "memory\n");
          _exit(1);
        }
        const bool cut = f.getPosition() >= total;
        std::string r = reason(e.what());
        for (char& c : r)
          if (c == '\n') c = ' ';
        say(fd, std::string(cut ? "truncated " : "corrupt ") + r + "\n");
        _exit(1);
      }
    }
  } catch (const std::exception& e) {
    say(fd, std::string("corrupt ") + reason(e.what()) + "\n");
    _exit(1);
  }
  say(fd, "entries " + std::to_string(entry) + "\n");
  _exit(0);
}

}  // namespace

ArchiveCheck checkArchive(const std::string& path, const char* what) {
  ArchiveCheck r;
  r.bytes = gzip::fileBytes(path, what);  // the log as MRPT reads it: a gzip file decompressed
  const std::string name = std::string(what) + " '" + path + "'";
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("cannot check " + name + ": no pipe");
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("cannot check " + name + ": cannot fork");
  if (pid == 0) {
    close(fds[0]);
    checkEntries(path, r.bytes, fds[1]);
  }
  close(fds[1]);
  std::string said;
  char buf[4096];
  for (ssize_t got; (got = read(fds[0], buf, sizeof buf)) != 0;) {
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) break;
    said.append(buf, static_cast<std::size_t>(got));
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  // The last lines: where the child was, and what it found there (nothing if it was killed).
  std::istringstream lines(said);
  std::string line, verdict;
  while (std::getline(lines, line)) {
    if (line.rfind("at ", 0) == 0) {
      std::istringstream at(line.substr(3));
      at >> r.entries >> r.offset;
      verdict.clear();
    } else {
      verdict = line;
    }
  }
  if (verdict.rfind("entries ", 0) == 0 && WIFEXITED(status) && WEXITSTATUS(status) == 0) {
    r.entries = std::stoull(verdict.substr(8));
    r.offset = r.bytes;
    return r;
  }
  const std::string where = "entry " + std::to_string(r.entries) + " (byte " + std::to_string(r.offset) + " of " +
                            std::to_string(r.bytes) + ")";
  if (verdict.rfind("truncated ", 0) == 0) {
    r.truncated = true;
    r.problem = "truncated: the file ends inside " + where + " (" + verdict.substr(10) + ")";
  } else if (verdict.rfind("corrupt ", 0) == 0) {
    r.problem = "corrupt " + where + ", " + std::to_string(r.bytes - r.offset) + " bytes before the end: " +
                verdict.substr(8);
  } else {
    r.problem = where + " announces more data than the " + std::to_string(r.bytes - r.offset) +
                " bytes left in the file (a damaged length field?)";
  }
  return r;
}

std::size_t checkRawlog(const std::string& path, bool allow_truncated, std::ostream& out) {
  const ArchiveCheck c = checkArchive(path, "rawlog");
  if (!c.problem.empty() && !(c.truncated && allow_truncated))
    throw std::runtime_error("cannot read rawlog '" + path + "': " + c.problem);
  if (c.entries == 0) throw std::runtime_error("cannot read rawlog '" + path + "': it holds no entry");
  if (c.truncated)
    out << "warning: rawlog '" << path << "' " << c.problem << "; --allow-truncated: reading its first " << c.entries
        << " entries, " << (c.bytes - c.offset) << " bytes dropped\n";
  return c.entries;
}

void forEachRawlogObservation(const std::string& path, std::size_t entries, const OdometryVisit& visit) {
  OdometryWalk walk;
  const auto fn = [&](const mrpt::serialization::CSerializable::Ptr& e, std::size_t i) { walk.feed(e, i, visit); };
  // The same bytes again, now known to be readable (they were, in the child).
  mrpt::io::CFileGZInputStream f(path);
  auto ar = mrpt::serialization::archiveFrom(f);
  for (std::size_t i = 0; i < entries; ++i) {
    const auto obj = ar.ReadObject();
    // As CRawlog::loadFromRawLogFile takes them: a whole CRawlog, comments, actions, frames and
    // observations (CRawlog::insert refuses anything else, as that reader stops at it).
    if (const auto whole = std::dynamic_pointer_cast<mrpt::obs::CRawlog>(obj)) {
      for (std::size_t k = 0; k < whole->size(); ++k) fn(whole->getAsGeneric(k), k);
    } else if (std::dynamic_pointer_cast<mrpt::obs::CObservationComment>(obj)) {
      continue;
    } else if (std::dynamic_pointer_cast<mrpt::obs::CActionCollection>(obj) ||
               std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(obj) ||
               std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj)) {
      fn(obj, i);
    } else {
      throw std::runtime_error("cannot read rawlog '" + path + "': entry " + std::to_string(i) + " is a " +
                               (obj ? obj->GetRuntimeClass()->className : "null object") +
                               ", not an action, a sensory frame or an observation");
    }
  }
}

void checkSimplemap(const std::string& path) {
  const ArchiveCheck c = checkArchive(path, "simplemap");
  const std::string name = "cannot read simplemap '" + path + "': ";
  if (!c.problem.empty()) throw std::runtime_error(name + c.problem);
  if (c.entries == 0) throw std::runtime_error(name + "it holds no entry");
  // MRPT's loader reads the first object and ignores the rest: the rest would be lost silently.
  if (c.entries > 1)
    throw std::runtime_error(name + "it holds " + std::to_string(c.entries) + " objects, a simplemap file one");
}

}  // namespace rtog::cli
