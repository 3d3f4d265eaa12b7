#include "rtog/mrpt/error_line.h"

#include <regex>

#include <mrpt/core/exceptions.h>

namespace rtog {

std::string errorLine(const std::exception& e) {
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

}  // namespace rtog
