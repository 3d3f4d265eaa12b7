// Preloaded into the MRPT apps by the app tests, next to the plugin. pf-localization seeds MRPT's
// global generator from the clock (CRandomGenerator::randomize()), so two runs never agree and
// runs started within the same second share a seed. Interposing that one symbol pins the seed to
// RTOG_TEST_SEED, which makes every run reproducible and lets both maps face the same particles.
#include <cstdint>
#include <cstdlib>

#include <mrpt/random/RandomGenerators.h>

void mrpt::random::CRandomGenerator::randomize() {
  const char* seed = std::getenv("RTOG_TEST_SEED");
  randomize(seed ? static_cast<std::uint32_t>(std::strtoul(seed, nullptr, 10)) : 1u);
}
