// ros2 bag metadata.yaml (acquisition, `hil import BAG`): parse_bag_metadata on arbitrary text.
// The answer is the bag's relative file names (never empty, none absolute) or a FormatError.
#include "fuzz_common.hpp"
#include <hil/acquisition/bag_metadata.hpp>
#include <hil/error/error.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  hil::fuzz::answers_or<hil::error::FormatError>("fuzz_bag_metadata", [&] {
    const auto files = hil::acquisition::parse_bag_metadata(text, "fuzz/metadata.yaml");
    if (files.empty()) hil::fuzz::violated("fuzz_bag_metadata", "a bag without files accepted");
    for (const auto& f : files)
      if (f.empty() || f.front() == '/') hil::fuzz::violated("fuzz_bag_metadata", "an empty or absolute file name accepted");
  });
  return 0;
}
