// Every use of zlib in rtog, in one place: the MRPT map's files read from a stream (a pipe works),
// the gzip files the rtog tool writes in MRPT's formats, and the size of a log as MRPT reads it.
// (MRPT's own CFileGZ* streams, used through MRPT's API, are MRPT's.) Built as the static
// library rtog_gzip, linked by librtog_mrpt and the rtog tool; zlib stays behind this header.
#pragma once

#include <cstddef>
#include <cstdint>
#include <istream>
#include <memory>
#include <ostream>
#include <string>

namespace rtog::gzip {

/// Whether a stream whose first byte is `first_byte` (peeked, as a pipe cannot seek) holds a gzip
/// member: every one starts with 0x1f (RFC 1952's ID1), which no other format rtog reads does.
inline bool startsMember(int first_byte) { return first_byte == 0x1f; }

/// A gzip member inflated as it is read, forward only, from `in`.
class Inflater {
 public:
  /// Throws std::runtime_error "zlib: cannot initialise".
  explicit Inflater(std::istream& in);
  ~Inflater();
  Inflater(const Inflater&) = delete;
  Inflater& operator=(const Inflater&) = delete;

  /// Up to `n` inflated bytes into `buf`; fewer at the member's end or where `in` ends early
  /// (then truncated()). Throws std::runtime_error "corrupt gzip stream (<zlib's reason>)".
  std::size_t read(void* buf, std::size_t n);
  /// Inflated bytes read so far.
  std::uint64_t inflated() const;
  /// Whether `in` ended before the member did.
  bool truncated() const;
  /// The rest of the inflated data plus the bytes after the member that were read from `in`
  /// already (what `in` still holds is the caller's to count).
  std::uint64_t bytesLeft();

 private:
  struct State;
  std::unique_ptr<State> s_;
};

/// `n` bytes of `data` gzip-compressed into `out`, in memory, with a gzip header and trailer as
/// gzopen writes them (so MRPT's readers take it). Throws std::runtime_error "zlib: cannot
/// initialise" / "zlib: deflate failed".
void compress(const void* data, std::size_t n, std::ostream& out);

/// Bytes of the file `path` as MRPT's readers see them: a gzip file (magic 0x1f 0x8b)
/// decompressed (counted, not kept; a damaged stream counts up to the damage), any other file
/// its size. Throws std::runtime_error "cannot open <what> '<path>'" if a gzip file cannot be opened.
std::uint64_t fileBytes(const std::string& path, const char* what);

}  // namespace rtog::gzip
