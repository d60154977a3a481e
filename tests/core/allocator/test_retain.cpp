// The heap policy (hil::allocator::retain_freed_memory): large blocks freed and allocated again,
// as a diagnosis does with its designs, fault no new pages in; with glibc's starting thresholds
// they do (the measurement can tell the two apart).
#include <gtest/gtest.h>
#include <hil/allocator/retain.hpp>

#include <sys/resource.h>

#include <cstdlib>
#include <cstring>
#include <vector>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace {

using hil::allocator::HeapPolicy;
using hil::allocator::retain_freed_memory;

constexpr std::size_t kBlockBytes = std::size_t{8} << 20;  // a 10,000-sample design is ~10 MB
constexpr int kBlocks = 4;
constexpr int kRounds = 6;

long minor_faults() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_minflt;
}

/// Minor page faults per page written, over rounds 2..kRounds of: allocate kBlocks blocks, write
/// every byte, free them all (the first round may fault: nothing was freed before it).
double faults_per_page() {
  const auto round = [] {
    std::vector<void*> blocks;
    for (int b = 0; b < kBlocks; ++b) {
      void* p = std::malloc(kBlockBytes);
      if (!p) std::abort();
      std::memset(p, b + 1, kBlockBytes);
      blocks.push_back(p);
    }
    for (void* p : blocks) std::free(p);
  };
  round();
  const long before = minor_faults();
  for (int r = 1; r < kRounds; ++r) round();
  const double pages = static_cast<double>(kRounds - 1) * kBlocks * static_cast<double>(kBlockBytes) / 4096.0;
  return static_cast<double>(minor_faults() - before) / pages;
}

TEST(RetainFreedMemory, ReallocatedLargeBlocksFaultNoNewPages) {
  const HeapPolicy policy = retain_freed_memory();
  if (policy == HeapPolicy::unavailable) GTEST_SKIP() << "not glibc's allocator (a sanitizer build?)";
  if (policy == HeapPolicy::user_set) GTEST_SKIP() << "GLIBC_TUNABLES or MALLOC_*_ set: the user's policy stands";
  ASSERT_EQ(policy, HeapPolicy::retained);
  // Thresholds written before the measurement: retained, under 5 % of the pages fault again.
  EXPECT_LT(faults_per_page(), 0.05);

#if defined(__GLIBC__)
  // glibc's starting thresholds (128 KiB each), as a process that never called it: every round
  // maps its blocks afresh and faults in (nearly) every page.
  ASSERT_EQ(mallopt(M_MMAP_THRESHOLD, 128 * 1024), 1);
  ASSERT_EQ(mallopt(M_TRIM_THRESHOLD, 128 * 1024), 1);
  EXPECT_GT(faults_per_page(), 0.5);
  EXPECT_EQ(retain_freed_memory(), HeapPolicy::retained);
  EXPECT_LT(faults_per_page(), 0.05);
#endif
}

}  // namespace
