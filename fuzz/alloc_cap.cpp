// Linked into the fuzz target that reads lengths from its input (rtog_fuzz_mrpt_archive):
// operator new refuses (throws std::bad_alloc) a single allocation above RTOG_FUZZ_ALLOC_CAP_MB
// (default 32; libFuzzer's own largest is smaller), as it would in a process under a memory
// limit. A loader must then fail with an exception, which the target accepts as a rejection.
// Without the cap, a length field claiming terabytes makes libFuzzer stop at its first such
// input with "out-of-memory (malloc(...))": a known finding (issue #15, "bounded loads": lengths
// are to be checked against the bytes that remain), which would keep the target from looking
// further. RTOG_FUZZ_ALLOC_CAP_MB=0 lifts the cap, to see those inputs fail again.
#include <cstdlib>
#include <cstddef>
#include <new>

namespace {

std::size_t capBytes() {
  static const std::size_t cap = [] {
    const char* s = std::getenv("RTOG_FUZZ_ALLOC_CAP_MB");
    const long mb = s ? std::atol(s) : 32;  // each refused claim first costs a zero-fill up to it
    return mb > 0 ? static_cast<std::size_t>(mb) << 20 : ~std::size_t{0};
  }();
  return cap;
}

void* allocate(std::size_t n, std::size_t align = 0) {
  if (n > capBytes()) throw std::bad_alloc();
  void* p = align > alignof(std::max_align_t) ? std::aligned_alloc(align, (n + align - 1) / align * align)
                                              : std::malloc(n ? n : 1);
  if (!p) throw std::bad_alloc();
  return p;
}

}  // namespace

void* operator new(std::size_t n) { return allocate(n); }
void* operator new[](std::size_t n) { return allocate(n); }
void* operator new(std::size_t n, std::align_val_t a) { return allocate(n, static_cast<std::size_t>(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return allocate(n, static_cast<std::size_t>(a)); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return allocate(n);
  } catch (const std::bad_alloc&) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
