// The Net F/T readers (drivers/src/netft_rdt.cpp, netft_can.cpp): RDT datagrams and requests of any
// size, the box's calibration page (netftapi2.xml) as any text, and its CAN short-data answers.
// Input: first byte selects: 0 mod 3 = datagram bytes (the rest); 1 = calibration page (the rest);
// 2 = two CAN answers (a length byte and 8 data bytes each).
#include "fuzz_common.hpp"
#include <hil/drivers/error.hpp>
#include <hil/drivers/netft_can.hpp>
#include <hil/drivers/netft_rdt.hpp>

#include <array>
#include <cmath>
#include <vector>

using namespace hil::drivers;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hil::fuzz::Bytes in(data, size);
  const std::uint8_t mode = in.u8();
  try {
    if (mode % 3 == 2) {
      std::array<CanFrame, 2> f;
      for (auto& x : f) {
        x.len = static_cast<std::uint8_t>(in.u8() % 65);
        for (std::size_t i = 0; i < 8; ++i) x.data[i] = in.u8();
      }
      netft_can::ShortData d;
      const bool a = netft_can::decode_short_first(f[0], d), b = netft_can::decode_short_second(f[1], d);
      if (a != (f[0].len == 8) || b != (f[1].len == 8)) hil::fuzz::violated("fuzz_netft", "a CAN answer decodes iff it has 8 bytes");
      if (a && b) {
        const auto again = netft_can::encode_short(0x100, d);
        for (std::size_t k = 0; k < 2; ++k)
          for (std::size_t i = 0; i < 8; ++i)
            if (again[k].data[i] != f[k].data[i]) hil::fuzz::violated("fuzz_netft", "CAN answers encode back to their bytes");
      }
    } else if (mode % 3 == 0) {
      std::vector<std::uint8_t> d;
      while (in.left() > 0) d.push_back(in.u8());
      const std::size_t n = netft::records_in(d.size());
      if (n * netft::kRecordBytes != (n == 0 ? 0 : d.size())) hil::fuzz::violated("fuzz_netft", "records_in counts whole records only");
      std::uint8_t back[netft::kRecordBytes];
      for (std::size_t k = 0; k < n; ++k) {
        netft::RdtRecord r;
        netft::decode_record(d.data() + k * netft::kRecordBytes, r);
        netft::encode_record(r, back);
        for (std::size_t i = 0; i < netft::kRecordBytes; ++i)
          if (back[i] != d[k * netft::kRecordBytes + i]) hil::fuzz::violated("fuzz_netft", "a record encodes back to its bytes");
        if (netft::describe_status(r.status).empty()) hil::fuzz::violated("fuzz_netft", "every status is described");
      }
      netft::RdtRequest q;
      if (netft::decode_request(d, q)) {
        const auto again = netft::encode_request(static_cast<netft::RdtCommand>(q.command), q.sample_count);
        for (std::size_t i = 0; i < again.size(); ++i)
          if (again[i] != d[i]) hil::fuzz::violated("fuzz_netft", "a request encodes back to its bytes");
      }
    } else {
      const std::string text = in.rest();
      try {
        const netft::Calibration c = netft::parse_calibration_xml(text, "fuzz.xml");
        if (!(c.newtons_per_count() > 0.0) || !std::isfinite(c.newton_metres_per_count()))
          hil::fuzz::violated("fuzz_netft", "an accepted page gives finite positive scales");
      } catch (const ConfigError& e) {
        if (std::string(e.what()).find("fuzz.xml") == std::string::npos) hil::fuzz::violated("fuzz_netft", "errors name the page");
      }
    }
  } catch (const std::exception& e) {
    hil::fuzz::unexpected("fuzz_netft", &e);
  }
  return 0;
}
