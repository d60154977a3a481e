// rig.yaml reader (formats/format): parse_rig on arbitrary text.
#include "fuzz_common.hpp"
#include <hil/error/error.hpp>
#include <hil/format/rig.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  hil::fuzz::answers_or<hil::error::FormatError>("fuzz_rig", [&] {
    const auto rig = hil::format::parse_rig(text, "fuzz.rig.yaml");
    (void)hil::format::total_polyhedra(rig);
    (void)hil::format::total_features(rig);
  });
  return 0;
}
