// Checks of .ini sections shared by the map types' option loaders.
#pragma once

#include <initializer_list>
#include <stdexcept>
#include <string>

#include <mrpt/config/CConfigFileBase.h>

namespace rtog {

/// Warns once per process (stderr) about each key of `section` that is not in `known`: a key
/// pasted from another map's section, or misspelt, would otherwise be dropped without a word.
void reportUnknownKeys(const mrpt::config::CConfigFileBase& source, const std::string& section,
                       std::initializer_list<const char*> known);

/// Throws std::invalid_argument naming `section` unless min_x < max_x and min_y < max_y, all
/// finite: the check of an .ini's extent and of a loaded map's grid frame.
void checkGridExtent(const std::string& section, float min_x, float max_x, float min_y, float max_y);

/// Reads COccupancyGridMap2D's creation extent (min_x, max_x, min_y, max_y) from `section`;
/// throws std::invalid_argument naming the key when it is not a finite, ordered extent.
void readGridExtent(const mrpt::config::CConfigFileBase& source, const std::string& section, float& min_x,
                    float& max_x, float& min_y, float& max_y);

/// Runs `validate` (an options struct's validate()), adding `section` to the message of the
/// std::invalid_argument it throws: the error names where in the .ini the value came from.
template <class Validate>
void validateInSection(const std::string& section, Validate&& validate) {
  try {
    validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(e.what()) + " (section [" + section + "])");
  }
}

}  // namespace rtog
