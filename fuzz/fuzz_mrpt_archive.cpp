// libFuzzer target: MRPT-format maps (what CRTreeOccupancyGridMap::saveToFile writes, without its
// gzip layer) read back through mrpt::serialization::CArchive::ReadObject, with the plugin's two
// classes registered. Whatever object comes out is exercised as a map: a bug in loading shows
// up as a sanitizer report here, not in a robot's process.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/rtti/CObject.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "rtog/mrpt/register_classes.h"

namespace {

[[noreturn]] void fail(const std::string& why) {
  std::fprintf(stderr, "rtog_fuzz_mrpt_archive: %s\n", why.c_str());
  std::abort();
}

void exercise(const rtog::CRTreeOccupancyGridMap& m) {
  if (const std::string why = m.map().checkInvariants(); !why.empty()) fail("loaded map is unsound: " + why);
  (void)m.asString();
  (void)m.isEmpty();
  (void)m.castRay({0.01, 0.02, 0.03}, {1.0, 0.5, 0.0}, 5.0);
  (void)m.nearestObstacleDistance({0.01, 0.02, 0.03}, 2.0);
  // A loaded map writes itself again and reads back the same (its options were valid enough to
  // be accepted, so they must survive).
  mrpt::io::CMemoryStream buf;
  auto ar = mrpt::serialization::archiveFrom(buf);
  ar << m;
  buf.Seek(0);
  auto back = std::dynamic_pointer_cast<rtog::CRTreeOccupancyGridMap>(ar.ReadObject());
  if (!back) fail("a loaded map does not read back");
  if (back->map().leafCount() != m.map().leafCount()) fail("leaf count changed in a round trip");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // Loading the library must have registered both classes (built with clang it once did not:
  // doc/reliability.md). Checked before registerMrptClasses() could paper over it, so that
  // the CI run of this clang-built target fails if that comes back.
  for (const char* name : {"rtog::CRTreeOccupancyGridMap", "rtog::CRTreeBackedGridMap2D"})
    if (!mrpt::rtti::findRegisteredClass(name)) fail(std::string(name) + " is not registered after loading");
  rtog::registerMrptClasses();
  return 0;
}

// The archive names the object's class first (a length byte with bit 7 set, then the name).
// Only streams naming one of the plugin's classes go on: any other class would fuzz MRPT's own
// loaders, which are not this project's code.
bool namesPluginClass(const std::uint8_t* data, std::size_t size) {
  if (size < 1 || !(data[0] & 0x80)) return false;
  const std::size_t n = data[0] & 0x7F;
  if (size < 1 + n) return false;
  const std::string name(reinterpret_cast<const char*>(data + 1), n);
  return name == "rtog::CRTreeOccupancyGridMap" || name == "rtog::CRTreeBackedGridMap2D";
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (!namesPluginClass(data, size)) return 0;
  mrpt::io::CMemoryStream in;
  in.assignMemoryNotOwn(data, size);
  auto ar = mrpt::serialization::archiveFrom(in);
  mrpt::serialization::CSerializable::Ptr obj;
  try {
    obj = ar.ReadObject();
  } catch (const std::exception&) {
    return 0;  // rejected with an exception: what a corrupt file must give
  }
  if (auto m = std::dynamic_pointer_cast<rtog::CRTreeOccupancyGridMap>(obj)) {
    exercise(*m);
  } else if (auto g = std::dynamic_pointer_cast<rtog::CRTreeBackedGridMap2D>(obj)) {
    exercise(g->rtreeMap());
    (void)g->asString();
  }
  return 0;
}
