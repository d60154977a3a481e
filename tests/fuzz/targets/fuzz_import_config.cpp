// The `hil import` mapping config (tools/hil/import/src/config.cpp) on arbitrary YAML text.
#include "fuzz_common.hpp"
#include <hil/error/error.hpp>
#include <hil/import/config.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  hil::fuzz::answers_or<hil::error::FormatError>("fuzz_import_config", [&] {
    const auto cfg = hil::import::parse_import_config(text, "fuzz.import.yaml");
    (void)hil::import::expand_columns(cfg.columns);
  });
  return 0;
}
