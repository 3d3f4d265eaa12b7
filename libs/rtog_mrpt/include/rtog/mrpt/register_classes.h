// Registration of the plugin's classes with MRPT's class registry.
#pragma once

namespace rtog {

/// Registers CRTreeOccupancyGridMap and CRTreeBackedGridMap2D in MRPT's class registry, where
/// CArchive::ReadObject finds classes by name. Loading librtog_mrpt.so does it, and so does
/// constructing a map; call it before reading a map in code that may run earlier (other static
/// initializers). Thread-safe; calls after the first do nothing.
void registerMrptClasses();

}  // namespace rtog
