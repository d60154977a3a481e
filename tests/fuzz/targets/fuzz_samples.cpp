// samples.csv reader (formats/format): parse_samples, then the summary `hil validate` prints.
#include "fuzz_common.hpp"
#include <hil/error/error.hpp>
#include <hil/format/run.hpp>
#include <hil/format/samples.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  hil::fuzz::answers_or<hil::error::FormatError>("fuzz_samples", [&] {
    const auto t = hil::format::parse_samples(text, "fuzz.samples.csv");
    if (t.line.size() != t.samples.size()) hil::fuzz::violated("fuzz_samples", "one source line per sample");
    (void)hil::format::summarize(t);
  });
  return 0;
}
