// The checks of the tools' command-line values (rtog, rtog-accuracy), in one place so that every
// option of every tool and subcommand means the same by them. CLI11 prefixes the message with
// the option's name.
// (CLI11's own PositiveNumber lets "nan" and "inf" through: NaN compares false with everything.)
#pragma once

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <string>

#include <CLI/CLI.hpp>

namespace rtog::app::checks {

enum class Sign { Any, NonNegative, Positive };

/// A finite number of the given sign; the whole value must be the number.
inline CLI::Validator number(Sign sign) {
  const char* desc = sign == Sign::Positive ? "POSITIVE" : sign == Sign::NonNegative ? "NON-NEGATIVE" : "FINITE";
  return CLI::Validator(
      [sign](std::string& s) -> std::string {
        errno = 0;
        char* end = nullptr;
        const double v = std::strtod(s.c_str(), &end);
        if (s.empty() || end != s.c_str() + s.size()) return "'" + s + "' is not a number";
        if (errno == ERANGE) return "'" + s + "' is out of range";
        if (!std::isfinite(v)) return "must be a finite number, got '" + s + "'";
        if (sign == Sign::Positive && !(v > 0)) return "must be > 0, got " + s;
        if (sign == Sign::NonNegative && !(v >= 0)) return "must be >= 0, got " + s;
        return {};
      },
      desc);
}

/// A whole number in [lo, hi].
inline CLI::Validator integer(long lo, long hi) {
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        errno = 0;
        char* end = nullptr;
        const long v = std::strtol(s.c_str(), &end, 10);
        if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE) return "'" + s + "' is not a whole number";
        if (v < lo || v > hi) return "must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + s;
        return {};
      },
      "INT in [" + std::to_string(lo) + " - " + std::to_string(hi) + "]");
}

/// A file name: an empty value (`--out ""`) names no file and would silently save nothing.
inline CLI::Validator path() {
  return CLI::Validator(
      [](std::string& s) -> std::string { return s.empty() ? "the path is empty (give a file name)" : ""; }, "PATH");
}

}  // namespace rtog::app::checks
