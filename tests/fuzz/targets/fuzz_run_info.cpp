// run.yaml reader (acquisition/runformat): parse_run_info on arbitrary text.
#include "fuzz_common.hpp"
#include "hil/format/error.hpp"
#include "hil/format/run.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)hil::format::parse_run_info(text, "fuzz.run.yaml");
  } catch (const hil::format::FormatError&) {
  } catch (const std::exception& e) {
    hil::fuzz::unexpected("fuzz_run_info", &e);
  } catch (...) {
    hil::fuzz::unexpected("fuzz_run_info", nullptr);
  }
  return 0;
}
