// What a benchmark report states about the machine, read from the system and from the version
// macros the bench was compiled with: no shell, no other program's output format to parse.
#include <sys/utsname.h>
#include <unistd.h>

#include <cstdio>
#include <ctime>
#include <fstream>
#include <string>

#include <mrpt/version.h>

#include "bench.hpp"

#ifndef RTOG_OCTOMAP_VERSION
#define RTOG_OCTOMAP_VERSION "unknown"  // set by CMake from octomap's package version
#endif

namespace rtog::bench {
namespace {

std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("model name", 0) != 0) continue;
    const std::size_t colon = line.find(':');
    if (colon == std::string::npos) break;
    const std::size_t first = line.find_first_not_of(" \t", colon + 1);
    return first == std::string::npos ? std::string() : line.substr(first);
  }
  return "unknown";  // e.g. an architecture whose cpuinfo names the model otherwise
}

std::string gibibytes(double bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f GiB", bytes / (1024.0 * 1024.0 * 1024.0));
  return buf;
}

std::string compiler() {
#if defined(__clang__)
  return std::string("clang ") + __clang_version__;
#elif defined(__GNUC__)
  return std::string("GCC ") + __VERSION__;
#else
  return __VERSION__;
#endif
}

std::string mrptVersion() {
  // MRPT_VERSION is 0xMmp, one hexadecimal digit a part (2.5.8 is 0x258).
  return std::to_string((MRPT_VERSION >> 8) & 0xF) + '.' + std::to_string((MRPT_VERSION >> 4) & 0xF) + '.' +
         std::to_string(MRPT_VERSION & 0xF);
}

std::string utcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%MZ", &tm);
  return buf;
}

}  // namespace

std::map<std::string, std::string> machineFacts() {
  std::map<std::string, std::string> m;
  m["cpu"] = cpuModel();
  m["cores"] = std::to_string(sysconf(_SC_NPROCESSORS_ONLN));
  m["memory"] = gibibytes(double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE)));
  utsname u{};
  m["os"] = uname(&u) == 0 ? std::string(u.sysname) + " " + u.release + " " + u.machine : "unknown";
  m["compiler"] = compiler();
  m["octomap"] = RTOG_OCTOMAP_VERSION;
  m["mrpt"] = mrptVersion();
  m["date"] = utcNow();
  return m;
}

}  // namespace rtog::bench
