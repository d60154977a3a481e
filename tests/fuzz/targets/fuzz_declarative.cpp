// The declarative CAN force-plate decoder (drivers/src/declarative.cpp, force_plate.cpp).
// The first bytes make the configuration (signal count, then per signal: component, frame id,
// start bit, length, flags, scale); a bad one must be refused with ConfigError. The rest is a
// stream of frames fed to DeclarativeForcePlate::feed, which must never crash or read outside
// the payload (extract_raw runs on every frame whose length covers its signals).
#include <memory>
#include "fuzz_common.hpp"
#include <hil/drivers/can_channel.hpp>
#include <hil/drivers/error.hpp>
#include <hil/drivers/force_plate.hpp>

using namespace hil::drivers;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hil::fuzz::Bytes in(data, size);
  ForcePlateConfig cfg;
  cfg.protocol = ForcePlateProtocol::declarative;
  const unsigned n = in.u8() % 9;
  for (unsigned i = 0; i < n; ++i) {
    CanSignal s;
    s.component = static_cast<WrenchComponent>(in.u8() % 8);  // 7 = out of range on purpose
    const std::uint8_t flags = in.u8();
    s.extended_id = flags & 1;
    s.is_signed = flags & 2;
    s.big_endian = flags & 4;
    // Few distinct ids most of the time, so that frames below hit the configured ones.
    s.frame_id = (flags & 8) ? in.u32() : (0x100u + (in.u8() & 3));
    s.start_bit = in.u16() % 530;
    s.length_bits = in.u8() % 70;
    s.scale = (flags & 16) ? 0.0 : 1.0 / (1 + in.u8());
    s.offset = (flags & 32) ? -1.5 : 0.0;
    cfg.signals.push_back(s);
  }
  static const auto bus = CanLoopbackBus::create("fuzz0");
  std::unique_ptr<DeclarativeForcePlate> plate;
  try {
    plate = std::make_unique<DeclarativeForcePlate>(cfg, bus->open());
  } catch (const ConfigError&) {
    return 0;
  } catch (const std::exception& e) {
    hil::fuzz::unexpected("fuzz_declarative", &e);
  }
  for (const auto& s : cfg.signals)
    if (bytes_needed(s) > 64) hil::fuzz::violated("fuzz_declarative", "accepted a signal beyond 64 bytes");

  if (n > 0 && (in.u8() & 1)) plate->tare(2);
  while (in.left() > 0) {
    CanFrame f;
    const std::uint8_t head = in.u8();
    f.extended = head & 1;
    f.rtr = head & 2;
    f.error = (head & 0x0C) == 0x0C;
    f.len = static_cast<std::uint8_t>(in.u8() % 65);
    f.fd = f.len > 8;
    f.id = (head & 0x10) ? in.u32() & kCanEffMask : 0x100u + (in.u8() & 3);
    for (unsigned i = 0; i < f.len; ++i) f.data[i] = in.u8();
    WrenchSample out;
    if (plate->feed(f, out) && !out.w_sensor.allFinite())
      hil::fuzz::violated("fuzz_declarative", "non-finite wrench from integer signals with finite scale and offset");
  }
  return 0;
}
