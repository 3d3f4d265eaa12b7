#include "archive_read.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <streambuf>

#include <mrpt/core/reverse_bytes.h>

namespace rtog::archive {
namespace {
constexpr std::size_t kChunk = std::size_t{1} << 20;

std::runtime_error corrupt(const char* who, const char* what, const std::string& why) {
  return std::runtime_error(std::string(who) + ": corrupt stream (" + what + ": " + why + ")");
}

std::runtime_error truncated(const char* who, const char* what, std::uint64_t n, std::uint64_t got) {
  return std::runtime_error(std::string(who) + ": truncated stream (" + what + ": " + std::to_string(n) +
                            " bytes announced, the stream ends after " + std::to_string(got) + ")");
}

/// The next bytes of a CArchive, at most `n`, as a stream buffer filled a chunk at a time.
class BlockBuf : public std::streambuf {
 public:
  BlockBuf(mrpt::serialization::CArchive& in, std::uint64_t n) : in_(in), left_(n) {}
  /// The stream ended before the block's bytes did.
  bool ended() const { return ended_; }
  /// Bytes taken from the archive so far.
  std::uint64_t fetched() const { return fetched_; }
  /// Bytes of the block the reader has not consumed (fetched or not).
  std::uint64_t unread() const { return left_ + static_cast<std::uint64_t>(egptr() - gptr()); }
  /// Reads (and drops) what is left of the block, a chunk at a time.
  void drain() {
    setg(nullptr, nullptr, nullptr);
    while (left_ > 0 && !ended_) fill();
  }

 protected:
  int_type underflow() override {
    if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
    return fill() ? traits_type::to_int_type(*gptr()) : traits_type::eof();
  }

 private:
  bool fill() {
    if (left_ == 0 || ended_) return false;
    buf_.resize(static_cast<std::size_t>(std::min<std::uint64_t>(kChunk, left_)));
    std::size_t got = 0;
    while (got < buf_.size()) {
      std::size_t r = 0;
      try {
        r = in_.ReadBuffer(&buf_[got], buf_.size() - got);
      } catch (const std::exception&) {
        r = 0;  // CArchive throws when nothing at all is left
      }
      if (r == 0) break;
      got += r;
    }
    fetched_ += got;
    left_ -= got;
    if (got < buf_.size()) ended_ = true;
    setg(&buf_[0], &buf_[0], &buf_[0] + got);
    return got > 0;
  }

  mrpt::serialization::CArchive& in_;
  std::uint64_t left_;
  std::uint64_t fetched_ = 0;
  bool ended_ = false;
  std::string buf_;
};
}  // namespace

void parseBlock(mrpt::serialization::CArchive& in, std::uint64_t n, const char* who, const char* what,
                const std::function<void(std::istream&)>& parse) {
  BlockBuf buf(in, n);
  std::istream is(&buf);
  try {
    parse(is);
  } catch (const std::exception&) {
    if (buf.ended()) throw truncated(who, what, n, buf.fetched());
    throw;
  }
  const std::uint64_t rest = buf.unread();
  if (rest == 0) return;
  buf.drain();
  if (buf.ended()) throw truncated(who, what, n, buf.fetched());
  throw std::runtime_error(std::string(who) + ": corrupt stream (" + std::to_string(rest) +
                           " trailing bytes after the map in its block)");
}

void readBytes(mrpt::serialization::CArchive& in, std::uint64_t n, std::string& out, const char* who,
               const char* what) {
  out.clear();
  while (out.size() < n) {
    const std::size_t at = out.size();
    const std::size_t chunk = static_cast<std::size_t>(std::min<std::uint64_t>(kChunk, n - at));
    out.resize(at + chunk);
    std::size_t got = 0;
    try {
      got = in.ReadBuffer(&out[at], chunk);
    } catch (const std::exception&) {
      got = 0;  // CArchive throws when nothing at all is left
    }
    if (got != chunk) throw truncated(who, what, n, at + got);
  }
}

std::string readString(mrpt::serialization::CArchive& in, std::size_t max_len, const char* who, const char* what) {
  const auto n = in.ReadAs<uint32_t>();
  if (n > max_len)
    throw corrupt(who, what, "a " + std::to_string(n) + "-byte string, at most " + std::to_string(max_len) + " allowed");
  std::string s;
  readBytes(in, n, s, who, what);
  return s;
}

std::vector<float> readFloats(mrpt::serialization::CArchive& in, std::size_t max_count, const char* who,
                              const char* what) {
  const auto n = in.ReadAs<uint32_t>();
  if (n > max_count)
    throw corrupt(who, what, std::to_string(n) + " values, at most " + std::to_string(max_count) + " allowed");
  std::string bytes;
  readBytes(in, std::uint64_t{n} * sizeof(float), bytes, who, what);
  std::vector<float> v(n);
  if (n) std::memcpy(v.data(), bytes.data(), bytes.size());
#if MRPT_IS_BIG_ENDIAN
  for (float& f : v) mrpt::reverseBytesInPlace(f);  // CArchive is little-endian
#endif
  return v;
}

mrpt::serialization::CArchive& operator>>(mrpt::serialization::CArchive& in, Flag f) {
  const auto byte = in.ReadAs<std::uint8_t>();
  if (byte > 1)
    throw std::runtime_error(std::string("rtog: corrupt stream (") + f.what + ": a bool stored as " +
                             std::to_string(int(byte)) + ")");
  f.value = byte == 1;
  return in;
}

void readGenericParams(mrpt::serialization::CArchive& in, mrpt::maps::TMapGenericParams& generic) {
  in >> generic;
  for (const bool* b : {&generic.enableSaveAs3DObject, &generic.enableObservationLikelihood,
                        &generic.enableObservationInsertion}) {
    unsigned char byte;
    std::memcpy(&byte, b, 1);  // the object's byte, not a load of a bool that may be invalid
    if (byte > 1)
      throw std::runtime_error("rtog: corrupt stream (genericMapParams: a bool stored as " + std::to_string(int(byte)) +
                               ")");
  }
}

}  // namespace rtog::archive
