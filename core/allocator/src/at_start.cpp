// Linked as an object (hil_allocator_at_start) into programs whose main() is a library's: the
// heap policy hil's own main() sets, set before main.
#include <hil/allocator/retain.hpp>

namespace {
[[maybe_unused]] const hil::allocator::HeapPolicy kAtStart = hil::allocator::retain_freed_memory();
}  // namespace
