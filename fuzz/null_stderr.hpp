// The plugin warns on std::cerr (unknown .ini keys, skipped observations). A fuzz target would
// spend its time writing those lines: they go to a stream that formats and discards them.
// Sanitizer and libFuzzer reports write to the file descriptor directly and are not affected.
#pragma once

#include <iostream>
#include <streambuf>

namespace rtog_fuzz {

inline void discardStdErr() {
  struct Discard : std::streambuf {
    int overflow(int c) override { return traits_type::not_eof(c); }
  };
  static Discard sink;
  std::cerr.rdbuf(&sink);
}

}  // namespace rtog_fuzz
