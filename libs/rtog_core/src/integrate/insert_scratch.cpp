#include "integrate/insert_scratch.hpp"

#include <mutex>

namespace rtog {
namespace {

// Idle insertion buffers: as many as maps insert at one time, up to kKeep sets and
// ScratchScope::kIdleBytes in all.
struct ScratchPool {
  static constexpr std::size_t kKeep = 4;
  std::mutex mutex;
  std::vector<std::pair<std::unique_ptr<InsertScratch>, std::size_t>> idle;  // with their bytes
  std::size_t idle_bytes = 0;
  static ScratchPool& instance() {
    static ScratchPool pool;
    return pool;
  }
};

}  // namespace

std::size_t InsertScratch::memoryBytes() const {
  std::size_t bytes = sizeof(*this) + planar_beams.capacity() * sizeof(PlanarBeam) +
                      assigned.capacity() * sizeof(AssignedPiece) + shared_ends.memoryBytes();
  for (const auto& m : moved_points) bytes += m.capacity() * sizeof(Eigen::Vector3f);
  for (const GradedScan& g : graded) bytes += sizeof(g) + g.memoryBytes();
  for (const UpdateBatch& b : batches) bytes += sizeof(b) + b.memoryBytes();
  for (const ApplyContext& c : apply_ctx) bytes += c.memoryBytes();
  for (const PlanarBatch& b : planar_batches) bytes += sizeof(b) + b.memoryBytes();
  return bytes;
}

void InsertScratch::shrink() {
  for (UpdateBatch& b : batches) b = UpdateBatch();
  for (ApplyContext& c : apply_ctx) c = ApplyContext();
  for (PlanarBatch& b : planar_batches) b = PlanarBatch();
  std::vector<PlanarBeam>().swap(planar_beams);
  for (GradedScan& g : graded) g = GradedScan();
  shared_ends = SharedEnds();
  std::vector<AssignedPiece>().swap(assigned);
  std::vector<std::vector<Eigen::Vector3f>>().swap(moved_points);
}

ScratchScope::ScratchScope(std::unique_ptr<InsertScratch>& slot) : slot_(slot), owner_(slot == nullptr) {
  if (!owner_) return;
  ScratchPool& pool = ScratchPool::instance();
  {
    const std::lock_guard<std::mutex> lock(pool.mutex);
    if (!pool.idle.empty()) {
      slot_ = std::move(pool.idle.back().first);
      pool.idle_bytes -= pool.idle.back().second;
      pool.idle.pop_back();
    }
  }
  if (!slot_) slot_ = std::make_unique<InsertScratch>();
}

ScratchScope::~ScratchScope() {
  if (!owner_) return;
  ScratchPool& pool = ScratchPool::instance();
  std::unique_ptr<InsertScratch> scratch = std::move(slot_);
  std::size_t bytes = scratch->memoryBytes();
  const std::lock_guard<std::mutex> lock(pool.mutex);
  if (pool.idle.size() >= ScratchPool::kKeep) return;  // freed here
  if (bytes > keep_at_most_ || pool.idle_bytes + bytes > kIdleBytes) {
    scratch->shrink();
    bytes = scratch->memoryBytes();
  }
  pool.idle_bytes += bytes;
  pool.idle.emplace_back(std::move(scratch), bytes);
}

void releaseInsertBuffers() {
  std::vector<std::pair<std::unique_ptr<InsertScratch>, std::size_t>> idle;
  {
    ScratchPool& pool = ScratchPool::instance();
    const std::lock_guard<std::mutex> lock(pool.mutex);
    idle.swap(pool.idle);
    pool.idle_bytes = 0;
  }
}  // freed here, outside the lock

}  // namespace rtog
