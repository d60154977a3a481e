// run.yaml reader (formats/format): parse_run_info on arbitrary text.
#include "fuzz_common.hpp"
#include <hil/error/error.hpp>
#include <hil/format/run.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  hil::fuzz::answers_or<hil::error::FormatError>("fuzz_run_info", [&] { (void)hil::format::parse_run_info(text, "fuzz.run.yaml"); });
  return 0;
}
