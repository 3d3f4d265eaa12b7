// The checks of the tools' command-line values (rtog, rtog-accuracy), in one place so that every
// option of every tool and subcommand means the same by them. CLI11 prefixes the message with
// the option's name.
// (CLI11's own PositiveNumber lets "nan" and "inf" through: NaN compares false with everything.)
#pragma once

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <CLI/CLI.hpp>

namespace rtog::app::checks {

enum class Sign { Any, NonNegative, Positive };

/// A bound as the messages print it (1e+04 as 10000, 1e-04 as 0.0001).
inline std::string bound(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.10g", v);
  return buf;
}

/// The largest length [m] the tools turn into a count of cells or pixels (an int): 1e4 m is
/// 1e8 cells at the finest resolution a map may have (1e-4 m), well inside int; a longer
/// --radius, --blur or Hough length would wrap (--hough-min-length 1e9 became a negative
/// number of pixels) or describe nothing a map can hold.
constexpr double kMaxCellLength = 1e4;

/// A finite number of the given sign, at most `max` (given: the option converts to an int or
/// a float, or has a stated range); the whole value must be the number.
inline CLI::Validator number(Sign sign, double max = HUGE_VAL) {
  std::string desc = sign == Sign::Positive ? "POSITIVE" : sign == Sign::NonNegative ? "NON-NEGATIVE" : "FINITE";
  if (max != HUGE_VAL) desc += " <= " + bound(max);
  return CLI::Validator(
      [sign, max](std::string& s) -> std::string {
        errno = 0;
        char* end = nullptr;
        const double v = std::strtod(s.c_str(), &end);
        if (s.empty() || end != s.c_str() + s.size()) return "'" + s + "' is not a number";
        if (errno == ERANGE) return "'" + s + "' is out of range";
        if (!std::isfinite(v)) return "must be a finite number, got '" + s + "'";
        if (sign == Sign::Positive && !(v > 0)) return "must be > 0, got " + s;
        if (sign == Sign::NonNegative && !(v >= 0)) return "must be >= 0, got " + s;
        if (v > max) return "must be at most " + bound(max) + ", got " + s;
        return {};
      },
      desc);
}

/// A finite number in [lo, hi]. (CLI11's own Range lets "nan" through: NaN compares false.)
inline CLI::Validator within(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        const std::string finite = number(Sign::Any)(s);
        if (!finite.empty()) return finite;
        const double v = std::strtod(s.c_str(), nullptr);
        if (v < lo || v > hi) return "must lie in [" + bound(lo) + ", " + bound(hi) + "], got " + s;
        return {};
      },
      "NUMBER in [" + bound(lo) + " - " + bound(hi) + "]");
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
