// An output stream buffer that hands its bytes to a drain, a buffer at a time, and counts them:
// the tools' files (a descriptor) and a map's bytes written into an MRPT archive.
#pragma once

#include <cstddef>
#include <cstdint>
#include <streambuf>
#include <utility>

namespace rtog::detail {

template <class Drain>
class SinkBuf : public std::streambuf {
 public:
  explicit SinkBuf(Drain drain) : drain_(std::move(drain)) { setp(buf_, buf_ + sizeof(buf_)); }
  /// Bytes written so far, those still in the buffer included.
  std::uint64_t bytes() const { return drained_ + static_cast<std::uint64_t>(pptr() - pbase()); }

 protected:
  int_type overflow(int_type c) override {
    drain();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override {
    drain();
    return 0;
  }

 private:
  /// The buffer emptied first, so that a drain that throws leaves a usable (empty) buffer.
  void drain() {
    const auto n = static_cast<std::size_t>(pptr() - pbase());
    setp(buf_, buf_ + sizeof(buf_));
    drained_ += n;
    if (n > 0) drain_(static_cast<const char*>(buf_), n);
  }

  Drain drain_;
  std::uint64_t drained_ = 0;
  char buf_[1 << 16];
};

}  // namespace rtog::detail
