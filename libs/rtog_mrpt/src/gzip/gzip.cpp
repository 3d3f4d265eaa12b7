#include "gzip.hpp"

#include <zlib.h>

#include <algorithm>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace rtog::gzip {

struct Inflater::State {
  explicit State(std::istream& i) : in(i) {}
  std::istream& in;
  z_stream z{};
  char in_buf[1 << 16];
  bool ended = false, truncated = false;

  bool refill() {
    in.read(in_buf, sizeof(in_buf));
    z.next_in = reinterpret_cast<Bytef*>(in_buf);
    z.avail_in = static_cast<uInt>(in.gcount());
    return z.avail_in > 0;
  }
};

Inflater::Inflater(std::istream& in) : s_(std::make_unique<State>(in)) {
  if (inflateInit2(&s_->z, 16 + MAX_WBITS) != Z_OK) throw std::runtime_error("zlib: cannot initialise");
}

Inflater::~Inflater() { inflateEnd(&s_->z); }

std::size_t Inflater::read(void* buf, std::size_t n) {
  z_stream& z = s_->z;
  z.next_out = static_cast<Bytef*>(buf);
  z.avail_out = static_cast<uInt>(n);
  while (z.avail_out > 0 && !s_->ended) {
    if (z.avail_in == 0 && !s_->refill()) {
      s_->truncated = true;
      break;
    }
    const int r = inflate(&z, Z_NO_FLUSH);
    if (r == Z_STREAM_END) s_->ended = true;
    else if (r != Z_OK) throw std::runtime_error(std::string("corrupt gzip stream (") + (z.msg ? z.msg : "zlib error") + ")");
  }
  return n - z.avail_out;
}

std::uint64_t Inflater::inflated() const { return s_->z.total_out; }

bool Inflater::truncated() const { return s_->truncated; }

std::uint64_t Inflater::bytesLeft() {
  std::uint64_t left = 0;
  char scratch[1 << 14];
  for (std::size_t got; !s_->ended && (got = read(scratch, sizeof(scratch))) > 0;) left += got;
  left += s_->z.avail_in;
  s_->z.avail_in = 0;
  return left;
}

void compress(const void* data, std::size_t n, std::ostream& out) {
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

std::uint64_t fileBytes(const std::string& path, const char* what) {
  std::ifstream f(path, std::ios::binary);
  unsigned char magic[2] = {0, 0};
  f.read(reinterpret_cast<char*>(magic), 2);
  if (!(magic[0] == 0x1f && magic[1] == 0x8b)) {
    f.clear();
    f.seekg(0, std::ios::end);
    return static_cast<std::uint64_t>(f.tellg());
  }
  gzFile gz = gzopen(path.c_str(), "rb");
  if (!gz) throw std::runtime_error(std::string("cannot open ") + what + " '" + path + "'");
  std::uint64_t n = 0;
  std::vector<char> buf(std::size_t{1} << 16);
  int got = 0;
  while ((got = gzread(gz, buf.data(), static_cast<unsigned>(buf.size()))) > 0) n += static_cast<std::uint64_t>(got);
  gzclose(gz);
  return n;  // a damaged gzip stream counts up to the damage: the entry there is truncated
}

}  // namespace rtog::gzip
