#include "options_check.hpp"

#include "rtog/mrpt/ini_checks.h"

#include <strings.h>

#include <cctype>
#include <cerrno>
#include <limits>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <set>
#include <stdexcept>
#include <vector>

namespace rtog {

namespace {

/// Tells `line` once per process for `id`. At most kMaxTold ids are remembered: a process that
/// reads many generated sections (a fuzzer, a tool) must not grow without bound.
void tellOnce(const std::string& id, const std::string& line) {
  constexpr std::size_t kMaxTold = 1000;
  static std::mutex mutex;
  static std::set<std::string> reported;
  static bool capped = false;
  std::lock_guard<std::mutex> lk(mutex);
  if (reported.size() >= kMaxTold) {
    if (!capped) std::cerr << "rtog: warning: further unknown keys are ignored without a warning, as are keys without effect\n";
    capped = true;
  } else if (reported.insert(id).second) {
    std::cerr << line << "\n";
  }
}

[[noreturn]] void badValue(const std::string& section, const std::string& key, const std::string& rule,
                           const std::string& value, const std::string& who = "rtog") {
  throw std::invalid_argument(who + ": invalid option [" + section + "] " + key + ": " + rule + ", got '" + value + "'");
}

/// The key's value as MRPT gives it (trimmed, without a " //" comment), or nothing if absent.
bool valueOf(const mrpt::config::CConfigFileBase& s, const std::string& sec, const std::string& key, std::string& v) {
  if (!s.keyExists(sec, key)) return false;
  v = s.read_string(sec, key, "");
  return true;
}

constexpr const char* kBoolRule = "must be a boolean: true/false, yes/no, on/off or 1/0";

bool parseBool(const std::string& sec, const std::string& key, const std::string& v, const std::string& who = "rtog") {
  std::string l = v;
  for (char& c : l) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (l == "true" || l == "yes" || l == "on" || l == "1") return true;
  if (l == "false" || l == "no" || l == "off" || l == "0") return false;
  badValue(sec, key, kBoolRule, v, who);
}

double parseReal(const std::string& sec, const std::string& key, const std::string& v, double max,
                 const std::string& who = "rtog") {
  errno = 0;
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (v.empty() || end != v.c_str() + v.size()) badValue(sec, key, "must be a number and nothing else", v, who);
  if ((errno == ERANGE && std::isinf(d)) || (std::isfinite(d) && std::fabs(d) > max))
    badValue(sec, key, "is out of range", v, who);
  return d;
}

int parseInt(const std::string& sec, const std::string& key, const std::string& v, const std::string& who = "rtog") {
  errno = 0;
  char* end = nullptr;
  const long long n = std::strtoll(v.c_str(), &end, 10);
  if (v.empty() || end != v.c_str() + v.size()) badValue(sec, key, "must be a whole number and nothing else", v, who);
  if (errno == ERANGE || n < std::numeric_limits<int>::min() || n > std::numeric_limits<int>::max())
    badValue(sec, key, "is out of range", v, who);
  return static_cast<int>(n);
}

}  // namespace

void reportUnknownKeys(const mrpt::config::CConfigFileBase& source, const std::string& section,
                       std::initializer_list<const char*> known) {
  std::vector<std::string> keys;
  source.getAllKeys(section, keys);
  for (const std::string& k : keys) {
    bool ok = false;
    for (const char* name : known) ok = ok || strcasecmp(k.c_str(), name) == 0;  // MRPT keys ignore case
    if (!ok) tellOnce(section + "/" + k, "rtog: warning: [" + section + "] unknown key '" + k + "' is ignored");
  }
}

void reportInertKey(const std::string& section, const std::string& key, const std::string& why) {
  tellOnce(section + "/" + key, "rtog: warning: [" + section + "] " + key + " has no effect: " + why);
}

bool readBool(const mrpt::config::CConfigFileBase& s, const std::string& sec, const std::string& key, bool def,
              const std::string& who) {
  std::string v;
  return valueOf(s, sec, key, v) ? parseBool(sec, key, v, who) : def;
}

double readDouble(const mrpt::config::CConfigFileBase& s, const std::string& sec, const std::string& key, double def) {
  std::string v;
  return valueOf(s, sec, key, v) ? parseReal(sec, key, v, std::numeric_limits<double>::max()) : def;
}

float readFloat(const mrpt::config::CConfigFileBase& s, const std::string& sec, const std::string& key, float def) {
  std::string v;
  return valueOf(s, sec, key, v) ? static_cast<float>(parseReal(sec, key, v, std::numeric_limits<float>::max())) : def;
}

int readInt(const mrpt::config::CConfigFileBase& s, const std::string& sec, const std::string& key, int def) {
  std::string v;
  return valueOf(s, sec, key, v) ? parseInt(sec, key, v) : def;
}

void checkIniValues(const mrpt::config::CConfigFileBase& s, const std::string& sec, const std::string& who,
                    std::initializer_list<std::pair<const char*, IniValue>> keys) {
  for (const auto& [key, kind] : keys) {
    std::string v;
    if (!valueOf(s, sec, key, v)) continue;
    if (kind == IniValue::Bool) parseBool(sec, key, v, who);
    if (kind == IniValue::Int) parseInt(sec, key, v, who);
    if (kind == IniValue::Count && parseInt(sec, key, v, who) < 1) badValue(sec, key, "must be a whole number >= 1", v, who);
    if (kind == IniValue::Real) parseReal(sec, key, v, std::numeric_limits<float>::max(), who);
  }
}

void readGridExtent(const mrpt::config::CConfigFileBase& source, const std::string& section, float& min_x,
                    float& max_x, float& min_y, float& max_y) {
  min_x = readFloat(source, section, "min_x", min_x);
  max_x = readFloat(source, section, "max_x", max_x);
  min_y = readFloat(source, section, "min_y", min_y);
  max_y = readFloat(source, section, "max_y", max_y);
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
