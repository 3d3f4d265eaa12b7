// Reading a map file for the rtog commands: either format, from a file or a pipe, whole.
#include <sys/stat.h>
#include <zlib.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include <mrpt/io/CStream.h>
#include <mrpt/serialization/CArchive.h>

#include "commands.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog::cli {
namespace {

/// A gzip stream inflated from a std::istream as it is read, for CArchive. Nothing is seeked,
/// so a pipe works as a file does, and the bytes after the gzip member can be counted (zlib's
/// gzread, which CFileGZInputStream uses, skips them without a word).
class GzipInput : public mrpt::io::CStream {
 public:
  explicit GzipInput(std::istream& in) : in_(in) {
    if (inflateInit2(&z_, 16 + MAX_WBITS) != Z_OK) throw std::runtime_error("zlib: cannot initialise");
  }
  ~GzipInput() override { inflateEnd(&z_); }

  size_t Read(void* buf, size_t n) override {
    z_.next_out = static_cast<Bytef*>(buf);
    z_.avail_out = static_cast<uInt>(n);
    while (z_.avail_out > 0 && !ended_) {
      if (z_.avail_in == 0 && !refill()) {
        truncated_ = true;
        break;
      }
      const int r = inflate(&z_, Z_NO_FLUSH);
      if (r == Z_STREAM_END) ended_ = true;
      else if (r != Z_OK) throw std::runtime_error(std::string("corrupt gzip stream (") + (z_.msg ? z_.msg : "zlib error") + ")");
    }
    return n - z_.avail_out;
  }
  size_t Write(const void*, size_t) override { throw std::logic_error("GzipInput: read only"); }
  uint64_t Seek(int64_t, mrpt::io::CStream::TSeekOrigin) override { throw std::logic_error("GzipInput: no seek"); }
  uint64_t getTotalBytesCount() const override { return 0; }
  uint64_t getPosition() const override { return z_.total_out; }

  bool truncated() const { return truncated_; }
  /// Bytes after what was read: the rest of the inflated data, then what follows the gzip member.
  std::uint64_t bytesLeft() {
    std::uint64_t left = 0;
    char scratch[1 << 14];
    for (std::size_t got; !ended_ && (got = Read(scratch, sizeof(scratch))) > 0;) left += got;
    left += z_.avail_in;
    z_.avail_in = 0;
    while (in_.read(scratch, sizeof(scratch)) || in_.gcount() > 0) left += static_cast<std::uint64_t>(in_.gcount());
    return left;
  }

 private:
  bool refill() {
    in_.read(in_buf_, sizeof(in_buf_));
    z_.next_in = reinterpret_cast<Bytef*>(in_buf_);
    z_.avail_in = static_cast<uInt>(in_.gcount());
    return z_.avail_in > 0;
  }

  std::istream& in_;
  z_stream z_{};
  char in_buf_[1 << 16];
  bool ended_ = false, truncated_ = false;
};

std::runtime_error trailing(std::uint64_t n) {
  return std::runtime_error(std::to_string(n) + " trailing byte" + (n == 1 ? "" : "s") +
                            " after the map (a damaged file, or not one map?)");
}

/// One line of what went wrong: MRPT wraps an exception thrown while reading an object in its
/// own ("==== MRPT exception ====", the original, a location, a call stack).
std::string reason(const std::exception& e) {
  std::string s = e.what();
  for (std::size_t at; (at = s.find("Original exception:\n")) != std::string::npos;) s = s.substr(at + 20);
  if (s.rfind("==== MRPT exception ====", 0) == 0) {
    const std::size_t at = s.find("Message:");
    s = at == std::string::npos ? std::string() : s.substr(at + 8);
    s.erase(0, s.find_first_not_of(' '));
  }
  s = s.substr(0, s.find('\n'));
  if (s.find("Cannot read requested number of bytes") != std::string::npos) return "truncated stream (the archive ends early)";
  return s.empty() ? "unreadable MRPT archive" : s;
}

OccupancyMap readMrptMap(std::istream& in) {
  GzipInput gz(in);
  auto ar = mrpt::serialization::archiveFrom(gz);
  mrpt::serialization::CSerializable::Ptr obj;
  try {
    obj = ar.ReadObject();
  } catch (const std::exception& e) {
    if (gz.truncated()) throw std::runtime_error("truncated gzip stream (the file ends early)");
    throw std::runtime_error(reason(e));
  }
  const auto m = std::dynamic_pointer_cast<CRTreeOccupancyGridMap>(obj);
  if (!m)
    throw std::runtime_error("holds a " + std::string(obj ? obj->GetRuntimeClass()->className : "null object") +
                             ", not an rtog::CRTreeOccupancyGridMap");
  if (const std::uint64_t n = gz.bytesLeft()) throw trailing(n);
  return m->map();
}

}  // namespace

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
    if (first == 0x1f) return readMrptMap(in);
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
