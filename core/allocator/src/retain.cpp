#include <hil/allocator/retain.hpp>

#include <cstdlib>
#include <cstring>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

// A sanitizer replaces glibc's allocator (its mallopt does nothing): say so instead of "retained".
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define HIL_OWN_ALLOCATOR 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define HIL_OWN_ALLOCATOR 1
#endif
#endif

namespace hil::allocator {

HeapPolicy retain_freed_memory() {
#if defined(__GLIBC__) && !defined(HIL_OWN_ALLOCATOR)
  // A user's own tuning (GLIBC_TUNABLES glibc.malloc.*, or the older MALLOC_*_ variables) wins.
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if ((tunables && std::strstr(tunables, "glibc.malloc.")) || std::getenv("MALLOC_MMAP_THRESHOLD_") ||
      std::getenv("MALLOC_TRIM_THRESHOLD_"))
    return HeapPolicy::user_set;
  // Setting the mmap threshold also stops glibc adapting it; both calls return 1 on success.
  if (mallopt(M_MMAP_THRESHOLD, static_cast<int>(kMmapThresholdBytes)) == 1 &&
      mallopt(M_TRIM_THRESHOLD, static_cast<int>(kTrimThresholdBytes)) == 1)
    return HeapPolicy::retained;
#endif
  return HeapPolicy::unavailable;
}

}  // namespace hil::allocator
