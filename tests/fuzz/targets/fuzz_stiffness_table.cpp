// The stiffness-experiment table (formats/models/src/stiffness.cpp). The
// first byte picks the robot's joint count (1..8) and whether dx dy dz are required; the rest is
// the CSV text. A table that parses must have one line number per row and rows of that width.
#include "fuzz_common.hpp"
#include <hil/error/error.hpp>
#include <hil/models/stiffness.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hil::fuzz::Bytes in(data, size);
  const std::uint8_t head = in.u8();
  const int dof = 1 + head % 8;
  const bool require_measured = head & 0x10;
  const std::string text = in.rest();
  hil::fuzz::answers_or<hil::error::FormatError>("fuzz_stiffness_table", [&] {
    const auto t = hil::models::parse_stiffness_table(text, "fuzz.table.csv", dof, require_measured);
    if (t.lines.size() != t.rows.size()) hil::fuzz::violated("fuzz_stiffness_table", "one line per row");
    if (require_measured && !t.rows.empty() && !t.has_measured)
      hil::fuzz::violated("fuzz_stiffness_table", "measured columns required but absent");
  });
  return 0;
}
