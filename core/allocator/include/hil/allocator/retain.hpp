#pragma once

#include <cstddef>

namespace hil::allocator {

/// Blocks up to this size come from the heap rather than from a fresh mmap each (glibc's default
/// starts at 128 KiB and adapts only up to the largest block freed so far).
inline constexpr std::size_t kMmapThresholdBytes = std::size_t{32} << 20;
/// Free memory at the heap's top is returned to the kernel only beyond this (glibc: twice the
/// mmap threshold, a few MB): a diagnosis frees and re-allocates designs of MBs at every fit.
inline constexpr std::size_t kTrimThresholdBytes = std::size_t{256} << 20;

/// What retain_freed_memory() did.
enum class HeapPolicy {
  retained,     ///< both thresholds set
  user_set,     ///< the environment sets glibc's malloc tunables: left as the user chose
  unavailable,  ///< not glibc's allocator (another libc, or a sanitizer's allocator)
};

/// Keeps freed heap memory in the process instead of returning it to the kernel at every free:
/// the diagnosis engine allocates and frees matrices of MBs thousands of times per run, and
/// glibc's defaults unmap them each time, so every new one page-faults in afresh (on the TIAGo
/// diagnosis that was more than half the run's time). Process-wide; call it before the threads
/// start. The numbers computed do not change, only where their memory comes from.
HeapPolicy retain_freed_memory();

}  // namespace hil::allocator
