// Reading what a CArchive holds without trusting its lengths. MRPT's own operator>> for a
// std::string or a std::vector allocates (and zero-fills) whatever 32-bit count the stream
// states before it reads a byte, and a 64-bit block length read into one buffer does the same:
// a 170-byte file could ask for a terabyte. Here every count is checked against a stated cap
// before anything is allocated, and blocks grow only as their bytes actually arrive (the
// remaining size of a gzip stream is unknown until it ends).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <istream>
#include <string>
#include <vector>

#include <mrpt/maps/metric_map_types.h>
#include <mrpt/serialization/CArchive.h>

namespace rtog::archive {

/// Longest name field of the map types' options ("octomap", "beam", ...).
constexpr std::size_t kMaxName = 256;
/// Most weights of likelihoodOptions.OWA_weights (MRPT's configs use a handful).
constexpr std::size_t kMaxWeights = std::size_t{1} << 16;
/// Most cells of a 2D grid: COccupancyGridMap2D indexes its cells with an int.
constexpr std::uint64_t kMaxGridCells = std::uint64_t{1} << 31;

/// A std::string as CArchive writes it (uint32 length, bytes); a length over `max_len` throws
/// std::runtime_error "<who>: corrupt stream (<what> ...)".
std::string readString(mrpt::serialization::CArchive& in, std::size_t max_len, const char* who, const char* what);
/// A std::vector<float> as CArchive writes it (uint32 count, floats), at most `max_count`.
std::vector<float> readFloats(mrpt::serialization::CArchive& in, std::size_t max_count, const char* who,
                              const char* what);
/// `n` bytes, read in chunks: what a false length costs is the bytes the stream holds, not n.
/// Throws "<who>: truncated stream (<what>: ...)" if the stream ends first.
void readBytes(mrpt::serialization::CArchive& in, std::uint64_t n, std::string& out, const char* who,
               const char* what);

/// A block of `n` announced bytes parsed by `parse` as a std::istream that pulls the bytes from
/// `in` in chunks of 1 MiB as the parser asks for them: its magic, version and counts are checked
/// as the first bytes arrive, and a false length costs what the parser reads before it fails,
/// not n (a block buffered whole first cost 2 GiB for a 1 MB gzip file of zeros). Bytes the
/// parser leaves are read in chunks too, to tell a truncated stream ("<who>: truncated stream
/// (<what>: n bytes announced, the stream ends after m)") from bytes after the map ("<who>:
/// corrupt stream (k trailing bytes after the map in its block)"). An error of the parser in a
/// stream that ended early is reported as the truncation; else it is rethrown as it is.
void parseBlock(mrpt::serialization::CArchive& in, std::uint64_t n, const char* who, const char* what,
                const std::function<void(std::istream&)>& parse);

/// A bool as CArchive writes it (one byte), read as a byte and checked: MRPT's operator>> copies
/// the byte into the bool, and a byte other than 0 or 1 is then not a valid bool (undefined
/// behaviour wherever it is read). Use as `in >> archive::Flag{b, "name"}`.
struct Flag {
  bool& value;
  const char* what;
};
mrpt::serialization::CArchive& operator>>(mrpt::serialization::CArchive& in, Flag f);

/// The generic map parameters as MRPT reads them (`in >> generic`), then their bools checked byte
/// by byte before anything reads them as bools: MRPT copies each stored byte into its bool.
/// Throws std::runtime_error "corrupt stream (genericMapParams: a bool stored as N)".
void readGenericParams(mrpt::serialization::CArchive& in, mrpt::maps::TMapGenericParams& generic);

}  // namespace rtog::archive
