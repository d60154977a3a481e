// Finding a NETCANOEM board whose base id is not known: every base id 0..0x7F is asked for its
// serial number (opcode 0x5, the request every independent driver opens with); a board answers on
// its own base id. The requests go out at once and the answers are gathered over one window, so a
// scan takes that window, not 128 timeouts.
#include <chrono>
#include <map>

#include <hil/drivers/force_plate.hpp>

namespace hil::drivers {

std::vector<NetCanOemBoard> scan_netcanoem(CanChannel& channel, double answer_window_s) {
  using Clock = std::chrono::steady_clock;
  const auto window = std::chrono::nanoseconds(static_cast<std::int64_t>(answer_window_s * 1e9));
  CanFrame f;
  while (channel.receive(f, std::chrono::nanoseconds(0)) == IoStatus::ok) {
  }
  std::map<std::uint32_t, std::string> found;
  const auto collect = [&](Clock::time_point until) {
    for (;;) {
      const auto now = Clock::now();
      if (now >= until) return;
      const IoStatus st = channel.receive(f, until - now);
      if (st == IoStatus::closed) return;
      if (st != IoStatus::ok) continue;
      if (f.error || f.extended || f.rtr || f.fd || ati::opcode_of(f.id) != ati::kOpSerial || f.len != 8) continue;
      found.try_emplace(ati::base_of(f.id), ati::decode_serial(f));
    }
  };
  for (std::uint32_t base = 0; base <= ati::kMaxBase; ++base) {
    // A full transmit queue (a real bus without a listener acknowledging) is waited out briefly;
    // answers arriving meanwhile are kept.
    if (channel.send(ati::request(base, ati::kOpSerial), std::chrono::milliseconds(20)) == IoStatus::closed) break;
    collect(Clock::now());
  }
  collect(Clock::now() + window);
  std::vector<NetCanOemBoard> out;
  for (auto& [base, serial] : found) out.push_back({base, std::move(serial)});
  return out;
}

}  // namespace hil::drivers
