// A map file read from a std::istream, gzip or not, without seeking (a pipe works as a file
// does), counting the bytes after the map: zlib's gzread, which CFileGZInputStream uses, skips
// what follows a gzip member without a word. The inflating is gzip/gzip.hpp's.
#pragma once

#include <istream>
#include <memory>

namespace rtog {

class CRTreeOccupancyGridMap;

/// The one map a stream holds (gzip CArchive, as saveToFile writes, or the plain CArchive).
/// Throws std::runtime_error: "truncated gzip stream (the file ends early)", "corrupt gzip
/// stream (…)", MRPT's own exception for a damaged archive, "holds a X, not an
/// rtog::CRTreeOccupancyGridMap", "N trailing bytes after the map (…)", "the file is empty".
std::shared_ptr<CRTreeOccupancyGridMap> readMapStream(std::istream& in);

}  // namespace rtog
