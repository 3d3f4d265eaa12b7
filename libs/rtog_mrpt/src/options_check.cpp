#include "options_check.hpp"

#include "rtog/mrpt/ini_checks.h"

#include <strings.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <set>
#include <stdexcept>
#include <vector>

namespace rtog {

void reportUnknownKeys(const mrpt::config::CConfigFileBase& source, const std::string& section,
                       std::initializer_list<const char*> known) {
  // Each key is told once per process, and at most kMaxTold keys are remembered: a process that
  // reads many generated sections (a fuzzer, a tool) must not grow without bound.
  constexpr std::size_t kMaxTold = 1000;
  static std::mutex mutex;
  static std::set<std::string> reported;
  static bool capped = false;
  std::vector<std::string> keys;
  source.getAllKeys(section, keys);
  for (const std::string& k : keys) {
    bool ok = false;
    for (const char* name : known) ok = ok || strcasecmp(k.c_str(), name) == 0;  // MRPT keys ignore case
    if (ok) continue;
    std::lock_guard<std::mutex> lk(mutex);
    if (reported.size() >= kMaxTold) {
      if (!capped) std::cerr << "rtog: warning: further unknown keys are ignored without a warning\n";
      capped = true;
    } else if (reported.insert(section + "/" + k).second) {
      std::cerr << "rtog: warning: [" << section << "] unknown key '" << k << "' is ignored\n";
    }
  }
}

void readGridExtent(const mrpt::config::CConfigFileBase& source, const std::string& section, float& min_x,
                    float& max_x, float& min_y, float& max_y) {
  min_x = source.read_float(section, "min_x", min_x);
  max_x = source.read_float(section, "max_x", max_x);
  min_y = source.read_float(section, "min_y", min_y);
  max_y = source.read_float(section, "max_y", max_y);
  checkGridExtent(section, min_x, max_x, min_y, max_y);
}

void checkGridExtent(const std::string& section, float min_x, float max_x, float min_y, float max_y) {
  const auto bad = [&](const char* key) {
    throw std::invalid_argument("rtog: invalid option [" + section + "] " + key +
                                ": the grid extent needs finite min_x < max_x and min_y < max_y");
  };
  if (!(std::isfinite(min_x) && std::isfinite(max_x) && min_x < max_x)) bad("min_x/max_x");
  if (!(std::isfinite(min_y) && std::isfinite(max_y) && min_y < max_y)) bad("min_y/max_y");
}

void checkMapCounts(const mrpt::config::CConfigFileBase& cfg, const std::string& section) {
  std::vector<std::string> keys;
  cfg.getAllKeys(section, keys);
  for (const std::string& key : keys) {
    constexpr const char* kSuffix = "_count";  // MRPT's keys are case-insensitive
    if (key.size() <= 6 || strcasecmp(key.c_str() + key.size() - 6, kSuffix) != 0) continue;
    const std::string value = cfg.read_string(section, key, "");
    // As MRPT reads it: the leading number, whatever follows (a comment).
    const char* p = value.c_str();
    while (std::isspace(static_cast<unsigned char>(*p))) ++p;
    char* end = nullptr;
    const long long n = std::strtoll(p, &end, 10);
    if (end == p || n < 0 || n > kMaxMapCount)
      throw std::invalid_argument("rtog: invalid option [" + section + "] " + key + ": must be a map count in [0, " +
                                  std::to_string(kMaxMapCount) + "], got '" + value + "'");
  }
}

}  // namespace rtog
