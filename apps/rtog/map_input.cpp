// Reading a map file for the rtog commands: either format, from a file or a pipe, whole.
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <regex>
#include <stdexcept>

#include "commands.hpp"
#include "gzip.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

#include <mrpt/core/exceptions.h>

namespace rtog::cli {
namespace {

std::runtime_error trailing(std::uint64_t n) {
  return std::runtime_error(std::to_string(n) + " trailing byte" + (n == 1 ? "" : "s") +
                            " after the map (a damaged file, or not one map?)");
}

/// One line of what went wrong reading a map; a short stream in MRPT's words said plainly.
std::string reason(const std::exception& e) {
  const std::string s = oneLine(e);
  if (s.find("Cannot read requested number of bytes") != std::string::npos) return "truncated stream (the archive ends early)";
  return s == kNoReason ? "unreadable MRPT archive" : s;
}

/// The MRPT map type reads its own files (gzip, forward only, trailing bytes counted).
OccupancyMap readMrptMap(std::istream& in) {
  try {
    return CRTreeOccupancyGridMap::loadFromStream(in)->map();
  } catch (const std::exception& e) {
    throw std::runtime_error(reason(e));
  }
}

}  // namespace

std::string oneLine(const std::exception& e) {
  // MRPT's exceptions keep the message they were made of: ours as thrown (wrapped by MRPT_END on
  // the way out of MRPT's code), or MRPT's own "file:line: [function] message".
  const auto* mrpt_error = dynamic_cast<const mrpt::ExceptionWithCallBackBase*>(&e);
  std::string s = mrpt_error ? mrpt_error->originalWhat : e.what();
  for (std::size_t at; (at = s.find("Original exception:\n")) != std::string::npos;) s = s.substr(at + 20);
  if (s.rfind("==== MRPT exception ====", 0) == 0) {  // a what() of MRPT's, passed on as text
    const std::size_t at = s.find("Message:");
    s = at == std::string::npos ? std::string() : s.substr(at + 8);
  }
  s = s.substr(0, s.find('\n'));
  static const std::regex mrpt_location(R"(^\S+:[0-9]+: \[)");
  if (std::regex_search(s, mrpt_location)) {
    int depth = 0;  // the function's name may hold brackets of its own (operator[], lambdas)
    for (std::size_t i = s.find('['); i < s.size(); ++i) {
      depth += s[i] == '[' ? 1 : s[i] == ']' ? -1 : 0;
      if (depth == 0) {
        s = s.substr(i + 1);
        break;
      }
    }
  }
  s.erase(0, s.find_first_not_of(' '));
  s.erase(s.find_last_not_of(" \t\r") + 1);
  return s.empty() ? kNoReason : s;
}

OccupancyMap loadMap(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw std::runtime_error("cannot open map file '" + path + "': " + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) throw std::runtime_error("cannot open map file '" + path + "': it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open map file '" + path + "': " + std::strerror(errno));
  try {
    // A gzip stream is the MRPT map's own file (CRTreeOccupancyGridMap::saveToFile, as the MRPT
    // apps write it); anything else must be the core format. Peeked, not seeked: a pipe cannot.
    const int first = in.peek();
    if (first == std::char_traits<char>::eof()) throw std::runtime_error("the file is empty");
    if (gzip::startsMember(first)) return readMrptMap(in);
    OccupancyMap map = OccupancyMap::read(in);
    std::uint64_t left = 0;
    char scratch[1 << 14];
    while (in.read(scratch, sizeof(scratch)) || in.gcount() > 0) left += static_cast<std::uint64_t>(in.gcount());
    if (left) throw trailing(left);
    return map;
  } catch (const std::exception& e) {
    throw std::runtime_error("'" + path + "': " + e.what());
  }
}

}  // namespace rtog::cli
