// gzip compression in memory, for the files rtog writes in MRPT's gzip formats.
#include <zlib.h>

#include <algorithm>
#include <ostream>
#include <stdexcept>

#include "commands.hpp"

namespace rtog::cli {

void writeGzip(const void* data, std::size_t n, std::ostream& out) {
  z_stream z{};
  // 16 + MAX_WBITS: a gzip header and trailer, as gzopen writes them, so MRPT's readers take it.
  if (deflateInit2(&z, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw std::runtime_error("zlib: cannot initialise");
  z.next_in = static_cast<Bytef*>(const_cast<void*>(data));  // zlib's API is not const-correct
  char buf[1 << 16];
  int r = Z_OK;
  std::size_t left = n;
  while (r != Z_STREAM_END) {
    // avail_in is 32 bits: a block over 4 GiB goes in in pieces.
    if (z.avail_in == 0 && left > 0) {
      z.avail_in = static_cast<uInt>(std::min<std::size_t>(left, 1u << 30));
      left -= z.avail_in;
    }
    z.next_out = reinterpret_cast<Bytef*>(buf);
    z.avail_out = sizeof(buf);
    r = deflate(&z, left == 0 ? Z_FINISH : Z_NO_FLUSH);
    if (r != Z_OK && r != Z_STREAM_END && r != Z_BUF_ERROR) {
      deflateEnd(&z);
      throw std::runtime_error("zlib: deflate failed");
    }
    out.write(buf, static_cast<std::streamsize>(sizeof(buf) - z.avail_out));
  }
  deflateEnd(&z);
}

}  // namespace rtog::cli
