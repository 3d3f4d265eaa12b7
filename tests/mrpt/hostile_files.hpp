// Hostile MRPT-format map files, crafted from real ones: a valid archive whose length fields
// are then set to what a flipped bit or an attacker would put there.
#pragma once

#include <sys/resource.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog_test {

/// The uncompressed CArchive of an object, as CFileGZOutputStream would compress it.
template <class T>
std::string archiveBytes(const T& obj) {
  mrpt::io::CMemoryStream mem;
  auto ar = mrpt::serialization::archiveFrom(mem);
  ar << obj;
  const auto* p = static_cast<const char*>(mem.getRawBufferData());
  return std::string(p, p + mem.getTotalBytesCount());
}

/// A file of its own in /tmp (mkstemp), removed with this object.
struct ScratchFile {
  std::string path;
  ScratchFile() {
    char name[] = "/tmp/rtog_test_XXXXXX";
    const int fd = ::mkstemp(name);
    if (fd < 0) throw std::runtime_error("mkstemp failed");
    ::close(fd);
    path = name;
  }
  ~ScratchFile() { std::remove(path.c_str()); }
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;
};

/// `plain` gzip-compressed by MRPT's CFileGZOutputStream, the stream saveToFile() writes with.
/// (Not mrpt::io::zip::compress_gz_data_block: it goes through a /tmp file named by the clock,
/// which two test processes started in the same microsecond share.)
inline std::string gzip(const std::string& plain) {
  ScratchFile f;
  {
    mrpt::io::CFileGZOutputStream out;
    if (!out.open(f.path)) throw std::runtime_error("gzip: cannot open " + f.path);
    out.Write(plain.data(), plain.size());
  }
  std::ifstream in(f.path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// The inverse, by CFileGZInputStream.
inline std::string gunzip(const std::string& gz) {
  ScratchFile f;
  std::ofstream(f.path, std::ios::binary) << gz;
  mrpt::io::CFileGZInputStream in;
  if (!in.open(f.path)) throw std::runtime_error("gunzip: cannot open " + f.path);
  std::string plain;
  char buf[1 << 14];
  for (std::size_t got; (got = in.Read(buf, sizeof(buf))) > 0;) plain.append(buf, got);
  return plain;
}

template <class T>
void poke(std::string& bytes, std::size_t at, T value) {
  if (at + sizeof(T) > bytes.size()) throw std::logic_error("poke beyond the end");
  std::memcpy(&bytes[at], &value, sizeof(T));  // CArchive is little-endian, as is this host
}

/// Where the 64-bit length of the core map block stands: right before the block's magic.
inline std::size_t blockLengthOffset(const std::string& archive) {
  const std::size_t magic = archive.find(std::string("RTOGMAP\0", 8));
  if (magic == std::string::npos || magic < 8) throw std::logic_error("no map block");
  return magic - 8;
}

/// Where the 32-bit length of the first string field holding `value` stands.
inline std::size_t stringLengthOffset(const std::string& archive, const std::string& value) {
  std::string field(4, '\0');
  poke(field, 0, static_cast<std::uint32_t>(value.size()));
  const std::size_t at = archive.find(field + value);
  if (at == std::string::npos) throw std::logic_error("no string field '" + value + "'");
  return at;
}

/// An empty map's file (gzip CArchive) whose map block says it holds `n` bytes.
inline std::string hugeBlockFile(std::uint64_t n) {
  std::string a = archiveBytes(rtog::CRTreeOccupancyGridMap(0.1));
  poke(a, blockLengthOffset(a), n);
  return gzip(a);
}

/// An empty map's file whose sensorModel string says it holds `n` bytes.
inline std::string hugeStringFile(std::uint32_t n) {
  std::string a = archiveBytes(rtog::CRTreeOccupancyGridMap(0.1));
  poke(a, stringLengthOffset(a, "beam"), n);
  return gzip(a);
}

/// Peak resident memory of this process so far [MiB].
inline double peakMiB() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss / 1024.0;
}

}  // namespace rtog_test
