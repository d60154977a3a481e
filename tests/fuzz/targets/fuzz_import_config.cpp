// The `hil import` mapping config (tools/hil/import/src/config.cpp) on arbitrary YAML text.
#include "fuzz_common.hpp"
#include "hil/format/error.hpp"
#include "hil/import/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto cfg = hil::import::parse_import_config(text, "fuzz.import.yaml");
    (void)hil::import::expand_columns(cfg.columns);
  } catch (const hil::format::FormatError&) {
  } catch (const std::exception& e) {
    hil::fuzz::unexpected("fuzz_import_config", &e);
  } catch (...) {
    hil::fuzz::unexpected("fuzz_import_config", nullptr);
  }
  return 0;
}
