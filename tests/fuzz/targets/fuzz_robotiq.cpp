// The Robotiq FT 300 readers (drivers/src/robotiq_ft300.cpp): a serial byte stream cut into pushes
// of any size through the framer, and identity registers of any value.
// Input: first byte selects: even = line bytes (the rest, pushed in chunks of 1..32 bytes chosen
// by the stream itself); odd = seven registers (firmware, serial) then nothing.
#include "fuzz_common.hpp"
#include <hil/drivers/robotiq_ft300.hpp>

#include <cmath>
#include <vector>

using namespace hil::drivers;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hil::fuzz::Bytes in(data, size);
  const std::uint8_t mode = in.u8();
  try {
    if (mode % 2 == 0) {
      robotiq::StreamFramer framer;
      std::uint64_t pushed = 0, framed = 0;
      robotiq::Reading r;
      while (in.left() > 0) {
        const std::size_t chunk = 1 + in.u8() % 32;
        std::vector<std::uint8_t> bytes;
        while (bytes.size() < chunk && in.left() > 0) bytes.push_back(in.u8());
        const std::size_t taken = framer.push(bytes);
        if (taken != bytes.size()) hil::fuzz::violated("fuzz_robotiq", "a drained framer takes every chunk");
        pushed += taken;
        while (framer.next(r)) {
          ++framed;
          std::uint8_t back[robotiq::kFrameBytes];
          robotiq::encode_frame(r, back);
          robotiq::Reading again;
          if (!robotiq::decode_frame(back, again) || again.counts != r.counts)
            hil::fuzz::violated("fuzz_robotiq", "a framed reading encodes to a frame that decodes to it");
          for (double v : r.si())
            if (!std::isfinite(v) || std::fabs(v) > 32768.0 / robotiq::kCountsPerNewton)
              hil::fuzz::violated("fuzz_robotiq", "readings in range");
        }
        if (framer.buffered() >= robotiq::kFrameBytes) hil::fuzz::violated("fuzz_robotiq", "next() leaves less than a frame");
      }
      if (framed * robotiq::kFrameBytes + framer.skipped_bytes() + framer.buffered() != pushed)
        hil::fuzz::violated("fuzz_robotiq", "every byte is framed, skipped or buffered");
    } else {
      std::array<std::uint16_t, 3> fw{in.u16(), in.u16(), in.u16()};
      std::array<std::uint16_t, 4> sn{in.u16(), in.u16(), in.u16(), in.u16()};
      const std::string f = robotiq::decode_firmware(fw);
      if (!f.empty() && f[0] != 'F') hil::fuzz::violated("fuzz_robotiq", "a firmware version starts with F");
      if (robotiq::decode_serial(sn).empty()) hil::fuzz::violated("fuzz_robotiq", "every serial decodes to text");
    }
  } catch (const std::exception& e) {
    hil::fuzz::unexpected("fuzz_robotiq", &e);
  }
  return 0;
}
