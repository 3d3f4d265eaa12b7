// Checks of a CMultiMetricMap .ini section that MRPT's own loader does not make.
#pragma once

#include <string>

#include <mrpt/config/CConfigFileBase.h>

namespace rtog {

/// The most maps of one type a section may ask for.
constexpr long long kMaxMapCount = 1000;

/// Throws std::invalid_argument naming section and key unless every "<map>_count" key of the
/// section holds a number in [0, kMaxMapCount]. MRPT's TSetOfMetricMapInitializers reads the
/// counts unsigned, so "-1" asks it for four billion map definitions (found by rtog_fuzz_ini).
/// Call it before TSetOfMetricMapInitializers::loadFromConfigFile.
void checkMapCounts(const mrpt::config::CConfigFileBase& cfg, const std::string& section);

}  // namespace rtog
