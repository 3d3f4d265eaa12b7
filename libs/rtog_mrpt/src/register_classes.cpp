// rtog::registerMrptClasses(): the plugin's classes in MRPT's class registry.
//
// Why not MRPT_INITIALIZER: on Linux that is __attribute__((constructor)), whose order against
// the dynamic initializers of its file is the compiler's choice. runtimeClassId holds a
// std::function, so it is initialized dynamically; clang runs the constructor first, MRPT's
// registerClass then sees a null class name, warns and drops the class, and every CArchive read
// of a map fails with "not registered" (GCC happens to run it last). So each class is registered
// by a variable defined after its IMPLEMENTS_SERIALIZABLE (CRTreeOccupancyGridMap.cpp,
// CRTreeBackedGridMap2D.cpp), which every compiler initializes after runtimeClassId (ordered
// initialization within one translation unit), and again here on first use, for code that runs
// before the library's initializers are done.
#include "rtog/mrpt/register_classes.h"

#include <atomic>
#include <mutex>

#include <mrpt/rtti/CObject.h>

#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

void registerMrptClasses() {
  static std::atomic<bool> done{false};
  if (done.load(std::memory_order_acquire)) return;
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  const mrpt::rtti::TRuntimeClassId* ids[] = {CLASS_ID(CRTreeOccupancyGridMap), CLASS_ID(CRTreeBackedGridMap2D)};
  // Called from another file's static initializer, an id may not be initialized yet: leave it
  // to its own file's registration (and to a later call) instead of handing MRPT a null name.
  bool all = true;
  for (const auto* id : ids) {
    if (id->className)
      mrpt::rtti::registerClass(id);
    else
      all = false;
  }
  done.store(all, std::memory_order_release);
}

}  // namespace rtog
