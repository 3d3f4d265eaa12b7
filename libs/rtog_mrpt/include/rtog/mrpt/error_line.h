// One line a person reads from an exception, whether MRPT's (which carry a call stack and the
// thrower's location) or anyone else's: what the rtog tool prints and the Python module raises.
#pragma once

#include <exception>
#include <string>

namespace rtog {

/// What went wrong in one line: an MRPT exception's original message without its call stack and
/// "file:line: [function]"; any other exception its first line. kNoReason if nothing is left.
std::string errorLine(const std::exception& e);
inline constexpr const char* kNoReason = "unknown error (the exception said nothing)";

}  // namespace rtog
