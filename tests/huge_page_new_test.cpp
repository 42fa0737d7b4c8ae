// The programs' operator new (tools/huge_page_new.cpp, linked into this binary as into `qsil`):
// large blocks aligned to 2 MiB and marked for transparent huge pages, the rest of the contract of
// the replaceable allocation functions kept.

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <memory>
#include <new>
#include <sstream>
#include <string>
#include <vector>

namespace {

constexpr std::size_t kHuge = std::size_t(2) << 20;

/// The VmFlags line of /proc/self/smaps for the mapping that holds address a ("" if none).
std::string vm_flags_of(std::uintptr_t a) {
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-') {
      inside = lo <= a && a < hi;
      continue;
    }
    if (inside && line.rfind("VmFlags:", 0) == 0) return line;
  }
  return "";
}

bool kernel_has_transparent_huge_pages() {
  std::ifstream f("/sys/kernel/mm/transparent_hugepage/enabled");
  return f.good();
}

TEST(HugePageNew, LargeBlocksAreAlignedToHugePages) {
  for (std::size_t bytes : {kHuge, kHuge + 1, 3 * kHuge + 12345}) {
    std::unique_ptr<char[]> p(new char[bytes]);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p.get()) % kHuge, 0u) << bytes << " bytes";
    p[bytes - 1] = 1;  // the whole block is writable
  }
  std::vector<double> v(kHuge / sizeof(double) + 7, 1.0);  // std::allocator goes through operator new
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(v.data()) % kHuge, 0u);
}

TEST(HugePageNew, LargeBlocksAreMarkedForTransparentHugePages) {
  if (!kernel_has_transparent_huge_pages()) GTEST_SKIP() << "this kernel has no transparent huge pages";
  std::unique_ptr<char[]> p(new char[4 * kHuge]);
  p[0] = 1;
  const std::string flags = vm_flags_of(reinterpret_cast<std::uintptr_t>(p.get()));
  ASSERT_FALSE(flags.empty()) << "no mapping in /proc/self/smaps holds the block";
  EXPECT_NE(flags.find(" hg"), std::string::npos) << "madvise(MADV_HUGEPAGE) not applied: " << flags;
}

// Over-aligned types (alignas beyond malloc's 16 bytes) go through the aligned forms.
TEST(HugePageNew, AlignedFormsKeepTheirAlignmentAndLargeBlocksGetHugePages) {
  struct alignas(64) Record {
    double x[8];
  };
  std::vector<Record> records(kHuge / sizeof(Record) + 3);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(records.data()) % kHuge, 0u);
  if (kernel_has_transparent_huge_pages()) {
    records[0].x[0] = 1;
    const std::string flags = vm_flags_of(reinterpret_cast<std::uintptr_t>(records.data()));
    EXPECT_NE(flags.find(" hg"), std::string::npos) << "madvise(MADV_HUGEPAGE) not applied: " << flags;
  }
  for (std::size_t alignment : {std::size_t(32), std::size_t(4096), 2 * kHuge})
    for (std::size_t bytes : {std::size_t(0), std::size_t(100), kHuge + 5}) {
      void* p = ::operator new(bytes, std::align_val_t(alignment));
      EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % alignment, 0u) << bytes << " bytes at " << alignment;
      ::operator delete(p, std::align_val_t(alignment));
      void* q = ::operator new[](bytes, std::align_val_t(alignment), std::nothrow);
      ASSERT_NE(q, nullptr);
      EXPECT_EQ(reinterpret_cast<std::uintptr_t>(q) % alignment, 0u) << bytes << " bytes at " << alignment;
      ::operator delete[](q, std::align_val_t(alignment), std::nothrow);
    }
  const std::size_t impossible = std::size_t(1) << 62;
  EXPECT_THROW(::operator delete(::operator new(impossible, std::align_val_t(64)), std::align_val_t(64)),
               std::bad_alloc);
  EXPECT_EQ(::operator new(impossible, std::align_val_t(64), std::nothrow), nullptr);
  EXPECT_EQ(::operator new[](impossible, std::align_val_t(4 * kHuge), std::nothrow), nullptr);
}

TEST(HugePageNew, ExhaustionThrowsOrReturnsNull) {
  const std::size_t impossible = std::size_t(1) << 62;
  // The functions themselves: a new-expression's allocation may be elided (and is, under LTO).
  EXPECT_THROW(::operator delete(::operator new(impossible)), std::bad_alloc);
  EXPECT_THROW(::operator delete[](::operator new[](impossible)), std::bad_alloc);
  EXPECT_EQ(::operator new(impossible, std::nothrow), nullptr);
  EXPECT_EQ(::operator new[](impossible, std::nothrow), nullptr);
}

TEST(HugePageNew, TheNewHandlerIsCalledBeforeGivingUp) {
  static int calls = 0;
  calls = 0;
  std::new_handler old = std::set_new_handler([] {
    if (++calls == 2) std::set_new_handler(nullptr);  // then operator new throws
  });
  EXPECT_THROW((void)::operator new(std::size_t(1) << 62), std::bad_alloc);
  std::set_new_handler(old);
  EXPECT_EQ(calls, 2);
}

TEST(HugePageNew, SmallBlocksAndZeroBytesAreOrdinary) {
  void* zero = ::operator new(0);
  ASSERT_NE(zero, nullptr);
  void* other = ::operator new(0);
  EXPECT_NE(zero, other);  // distinct non-null pointers
  ::operator delete(zero);
  ::operator delete(other);
  auto small = std::make_unique<int[]>(1000);
  small[999] = 3;
  EXPECT_EQ(small[999], 3);
}

}  // namespace
