// Ranks without MPI: this process alone.
#include "ranks.hpp"

namespace rtog::cli {

Ranks::Ranks() = default;
Ranks::~Ranks() = default;
std::vector<std::string> Ranks::gather(const std::string& mine) const { return {mine}; }
void Ranks::barrier() const {}
bool Ranks::all(bool ok) const { return ok; }

}  // namespace rtog::cli
