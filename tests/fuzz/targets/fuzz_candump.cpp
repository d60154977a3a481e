// candump -L log lines and cansend frame text (drivers/src/candump.cpp). Functions that report
// errors as strings must never throw; a line that parses must format back to the same frame.
#include <string_view>
#include "fuzz_common.hpp"
#include <hil/drivers/candump.hpp>

using namespace hil::drivers;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view all(reinterpret_cast<const char*>(data), size);
  try {
    std::size_t pos = 0;
    while (pos <= all.size()) {
      std::size_t nl = all.find('\n', pos);
      if (nl == std::string_view::npos) nl = all.size();
      const std::string_view line = all.substr(pos, nl - pos);
      pos = nl + 1;

      CanFrame f;
      std::string iface;
      if (parse_candump_line(line, f, iface).empty()) {
        CanFrame g;
        std::string iface2;
        const std::string again = format_candump_line(f, iface);
        if (!parse_candump_line(again, g, iface2).empty()) hil::fuzz::violated("fuzz_candump", "formatted line does not parse");
        if (!same_frame(f, g) || iface != iface2 || f.t_ns / 1000 != g.t_ns / 1000)
          hil::fuzz::violated("fuzz_candump", "line does not round-trip");
      }
      CanFrame h;
      if (parse_frame_text(line, h).empty()) {
        char buf[kMaxFrameText];
        const std::size_t n = format_frame_text(h, buf);
        CanFrame k;
        if (!parse_frame_text(std::string_view(buf, n), k).empty() || !same_frame(h, k))
          hil::fuzz::violated("fuzz_candump", "frame text does not round-trip");
      }
    }
  } catch (const std::exception& e) {
    hil::fuzz::unexpected("fuzz_candump", &e);
  }
  return 0;
}
