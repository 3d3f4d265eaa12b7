// Checks of .ini sections shared by the map types' option loaders.
#pragma once

#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <utility>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/maps/metric_map_types.h>

namespace rtog {

/// Warns once per process (stderr) about each key of `section` that is not in `known`: a key
/// pasted from another map's section, or misspelt, would otherwise be dropped without a word.
void reportUnknownKeys(const mrpt::config::CConfigFileBase& source, const std::string& section,
                       std::initializer_list<const char*> known);

/// Warns once per process (stderr, one line) that `key` of `section`, a key this project knows,
/// has no effect under the other options of the section (`why`): a rangeNoise sigma under
/// another sensorModel, a prior's geometry without a prior. Shares the unknown keys' memory.
void reportInertKey(const std::string& section, const std::string& key, const std::string& why);

/// Typed values of an .ini key, read strictly: MRPT's read_bool takes any word ("on" is false)
/// and read_float / read_int the leading number of any text ("0.1abc" is 0.1). These take the
/// whole value (after MRPT's trimming and its " //" comment) or throw std::invalid_argument
/// "rtog: invalid option [SECTION] KEY: ...", naming the rule; an absent key gives `def`.
/// Booleans: true/false, yes/no, on/off, 1/0, in any case.
bool readBool(const mrpt::config::CConfigFileBase& source, const std::string& section, const std::string& key,
              bool def, const std::string& who = "rtog");
/// A number, all of it: "nan" and "inf" are read (the options' checks refuse them where they
/// must be finite); a value beyond the type's range is refused.
double readDouble(const mrpt::config::CConfigFileBase& source, const std::string& section, const std::string& key,
                  double def);
float readFloat(const mrpt::config::CConfigFileBase& source, const std::string& section, const std::string& key,
                float def);
/// A whole number in int's range.
int readInt(const mrpt::config::CConfigFileBase& source, const std::string& section, const std::string& key, int def);

/// The kinds of value a section read by MRPT's own loader holds, checked before MRPT reads it.
/// Count: a whole number >= 1 (a step MRPT keeps unsigned, where -1 would wrap to 4294967295).
enum class IniValue { Bool, Int, Count, Real };
/// Throws as the readers above (the message starting with `who`) for the first key of `keys`
/// present in `section` whose value is not of its kind: for sections MRPT's own loader reads,
/// such as COccupancyGridMap2D's likelihood options.
void checkIniValues(const mrpt::config::CConfigFileBase& source, const std::string& section, const std::string& who,
                    std::initializer_list<std::pair<const char*, IniValue>> keys);

/// The booleans MRPT's TMapGenericParams reads from every map's _creationOpts with its
/// read_bool (which takes "on" for false), read again as readBool reads them.
inline void readGenericMapParams(const mrpt::config::CConfigFileBase& source, const std::string& section,
                                 const std::string& who, mrpt::maps::TMapGenericParams& p) {
  p.enableSaveAs3DObject = readBool(source, section, "enableSaveAs3DObject", p.enableSaveAs3DObject, who);
  p.enableObservationLikelihood =
      readBool(source, section, "enableObservationLikelihood", p.enableObservationLikelihood, who);
  p.enableObservationInsertion = readBool(source, section, "enableObservationInsertion", p.enableObservationInsertion, who);
  readBool(source, section, "disableSaveAs3DObject", false, who);  // older MRPT's key: its syntax only
}

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

/// Throws std::invalid_argument ("WHO: invalid option [SECTION] KEY: why") unless likelihood
/// options hold usable values: positive widths and ranges, hit and random weights non-negative
/// and not both zero, and each decimation or skip at least 1 (COccupancyGridMap2D's likelihood
/// methods step through the beams by them: with 0, its likelihood field loops forever). For
/// rtog's options and for COccupancyGridMap2D's (the backed grid's) alike: the members have the
/// same names.
template <class LikelihoodOptions>
void checkLikelihoodValues(const LikelihoodOptions& o, const std::string& who, const std::string& section) {
  const auto bad = [&](const char* key, const std::string& why) {
    throw std::invalid_argument(who + ": invalid option [" + section + "] " + key + ": " + why);
  };
  const auto positive = [&](float v, const char* key) {
    if (!(std::isfinite(v) && v > 0.0f)) bad(key, "must be a positive number, got " + std::to_string(v));
  };
  positive(o.LF_stdHit, "LF_stdHit");
  positive(o.LF_maxRange, "LF_maxRange");
  positive(o.LF_maxCorrsDistance, "LF_maxCorrsDistance");
  positive(o.rayTracing_stdHit, "rayTracing_stdHit");
  if (!(o.LF_zHit >= 0.0f && o.LF_zRandom >= 0.0f && o.LF_zHit + o.LF_zRandom > 0.0f))
    bad("LF_zHit/LF_zRandom", "must be non-negative and not both zero");
  const auto atLeastOne = [&](long long v, const char* key) {
    if (v < 1) bad(key, "must be >= 1, got " + std::to_string(v));
  };
  atLeastOne(o.LF_decimation, "LF_decimation");
  atLeastOne(o.rayTracing_decimation, "rayTracing_decimation");
  atLeastOne(o.MI_skip_rays, "MI_skip_rays");
  atLeastOne(o.consensus_takeEachRange, "consensus_takeEachRange");
}

}  // namespace rtog
