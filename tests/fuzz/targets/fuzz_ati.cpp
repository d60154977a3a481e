// ATI NETCANOEM decoders (drivers/src/ati_protocol.cpp) on frames of any id and length.
// Input: per frame one header byte (length 0..64), a 16-bit id, then the payload.
#include "fuzz_common.hpp"
#include <hil/drivers/ati_protocol.hpp>

using namespace hil::drivers;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hil::fuzz::Bytes in(data, size);
  try {
    while (in.left() > 0) {
      CanFrame f;
      f.len = static_cast<std::uint8_t>(in.u8() % 65);
      f.id = in.u16() & kCanSffMask;
      f.fd = f.len > 8;
      for (unsigned i = 0; i < f.len; ++i) f.data[i] = in.u8();

      std::uint16_t status = 0;
      ati::Gauges g{};
      ati::MatrixRow row{};
      std::int32_t cpf = 0, cpt = 0;
      std::uint8_t fu = 0, tu = 0;
      ati::Firmware fw;
      if (ati::decode_gauges_first(f, status, g) != (f.len == 8)) hil::fuzz::violated("fuzz_ati", "gauges (first) accepted iff 8 bytes");
      if (ati::decode_gauges_second(f, g) != (f.len == 6)) hil::fuzz::violated("fuzz_ati", "gauges (second) accepted iff 6 bytes");
      for (unsigned part = 0; part < 4; ++part) (void)ati::decode_matrix_part(f, part, row);
      const std::string serial = ati::decode_serial(f);
      if (serial.size() > 8) hil::fuzz::violated("fuzz_ati", "serial longer than 8 characters");
      (void)ati::decode_counts(f, cpf, cpt);
      if (ati::decode_units(f, fu, tu)) {
        (void)ati::force_unit_name(fu);
        (void)ati::torque_unit_name(tu);
        (void)ati::force_unit_to_si(fu);
        (void)ati::torque_unit_to_si(tu);
      }
      (void)ati::decode_firmware(f, fw);
    }
  } catch (const std::exception& e) {
    hil::fuzz::unexpected("fuzz_ati", &e);
  }
  return 0;
}
