/// @file huge_page_new.cpp
/// The programs' global operator new (linked into `qsil`, `qsil-*`, the benchmarks and the test
/// binary, not into the libraries or the Python module): a block of kHugePageBytes or more is
/// aligned to 2 MiB and its whole 2 MiB pages are marked madvise(MADV_HUGEPAGE), so that where the
/// kernel's transparent huge pages are in `madvise` mode (Debian's default) they are backed by huge
/// pages; smaller blocks come from malloc as before.
///
/// Why: a set-up writes large arrays once (the mesh, the edge arrays, the forest's nodes and
/// bounds, their temporaries). With 4 KiB pages it spends much of its time in first-touch page
/// faults (23 % of `qsil forest`'s samples on a 1.31 M triangle mesh, in a virtual machine); with
/// huge pages that set-up is 1.8x faster (docs/experiments/2026-11-29-huge-pages.md). An
/// environment map's sampling tables are two large blocks for the same reason (Distribution2D;
/// docs/experiments/2026-11-29-envmap-setup.md). Rendering did not measurably change: its large
/// blocks are few. glibc's own switch for this
/// (GLIBC_TUNABLES=glibc.malloc.hugetlb=1) is read from the environment at start-up only, so a
/// program cannot turn it on for itself.
///
/// Contract: the replaceable allocation functions of [new.delete.single] and [new.delete.array],
/// the aligned forms (std::align_val_t, for over-aligned types such as the environment map's texel
/// records) included: every block comes from malloc or posix_memalign and is released with free,
/// so a block may be freed by any operator delete in the process. An aligned block of 2 MiB or
/// more whose alignment is at most 2 MiB is a large block as above (2 MiB alignment satisfies
/// it); a smaller one, or a larger alignment, comes from posix_memalign as libstdc++'s own would.
/// Where memory runs out the new_handler is called, then std::bad_alloc thrown (nothrow forms:
/// nullptr). madvise's failure (a kernel without THP) is ignored: the block is then an ordinary one.

#include <sys/mman.h>

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace {

/// The page size of x86-64's and AArch64's (4 KiB granule) transparent huge pages, and the size
/// from which a block gets them: smaller blocks would waste most of a huge page.
constexpr std::size_t kHugePageBytes = std::size_t(2) << 20;

/// A block of `bytes` aligned to `alignment` (a power of two; 0: malloc's own alignment).
void* allocate(std::size_t bytes, std::size_t alignment = 0) {
  if (bytes == 0) bytes = 1;
  for (;;) {
    if (alignment > kHugePageBytes || (alignment != 0 && bytes < kHugePageBytes)) {
      void* p = nullptr;
      if (posix_memalign(&p, std::max(alignment, sizeof(void*)), bytes) == 0) return p;
    } else if (bytes >= kHugePageBytes) {
      void* p = nullptr;
      if (posix_memalign(&p, kHugePageBytes, bytes) == 0) {
        // The whole huge pages of the block; its last partial page stays in 4 KiB pages, so that
        // no more than the block is ever resident.
        madvise(p, bytes & ~(kHugePageBytes - 1), MADV_HUGEPAGE);
        return p;
      }
    } else if (void* p = std::malloc(bytes)) {
      return p;
    }
    std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
}

void* allocate_nothrow(std::size_t bytes, std::size_t alignment = 0) noexcept {
  try {
    return allocate(bytes, alignment);
  } catch (...) { return nullptr; }
}

}  // namespace

void* operator new(std::size_t bytes) { return allocate(bytes); }
void* operator new[](std::size_t bytes) { return allocate(bytes); }
void* operator new(std::size_t bytes, const std::nothrow_t&) noexcept { return allocate_nothrow(bytes); }
void* operator new[](std::size_t bytes, const std::nothrow_t&) noexcept { return allocate_nothrow(bytes); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

void* operator new(std::size_t bytes, std::align_val_t a) { return allocate(bytes, std::size_t(a)); }
void* operator new[](std::size_t bytes, std::align_val_t a) { return allocate(bytes, std::size_t(a)); }
void* operator new(std::size_t bytes, std::align_val_t a, const std::nothrow_t&) noexcept {
  return allocate_nothrow(bytes, std::size_t(a));
}
void* operator new[](std::size_t bytes, std::align_val_t a, const std::nothrow_t&) noexcept {
  return allocate_nothrow(bytes, std::size_t(a));
}
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
