#include <cstdio>

#include <hil/drivers/error.hpp>
#include <hil/drivers/force_plate.hpp>

namespace hil::drivers {

DeclarativeForcePlate::DeclarativeForcePlate(const ForcePlateConfig& cfg, std::unique_ptr<CanChannel> channel)
    : CanForcePlate(cfg, std::move(channel)) {
  if (cfg_.protocol != ForcePlateProtocol::declarative) throw ConfigError("protocol", "DeclarativeForcePlate needs protocol declarative");
  for (unsigned i = 0; i < cfg_.signals.size(); ++i) {
    const auto& s = cfg_.signals[i];
    FrameSlot* slot = nullptr;
    for (auto& sl : slots_)
      if (sl.id == s.frame_id && sl.extended == s.extended_id) slot = &sl;
    if (slot == nullptr) {
      slots_.push_back(FrameSlot{s.frame_id, s.extended_id, 0, {}});
      slot = &slots_.back();
    }
    slot->min_len = std::max(slot->min_len, bytes_needed(s));
    slot->signals.push_back(i);
  }
  full_mask_ = slots_.size() == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << slots_.size()) - 1;
}

ForcePlateInfo DeclarativeForcePlate::start() {
  ForcePlateInfo info;
  info.protocol = "declarative";
  info.units = "N, N-m";
  counters_.connected = true;
  return info;
}

bool DeclarativeForcePlate::feed(const CanFrame& f, WrenchSample& out) noexcept {
  if (f.error || f.rtr) return false;
  for (std::size_t k = 0; k < slots_.size(); ++k) {
    const FrameSlot& sl = slots_[k];
    if (sl.id != f.id || sl.extended != f.extended) continue;
    if (f.len < sl.min_len) {
      bad_ = true;
      return false;
    }
    if (seen_mask_ == 0) {
      first_t_ns_ = f.t_ns;
      first_stamp_ = f.stamp;
    }
    for (const unsigned i : sl.signals) {
      const CanSignal& s = cfg_.signals[i];
      const std::int64_t raw = extract_raw(s, f.data.data());
      if (s.component == WrenchComponent::status) {
        pending_status_ = static_cast<std::uint16_t>(raw);
      } else {
        const double raw_d = s.is_signed ? static_cast<double>(raw) : static_cast<double>(static_cast<std::uint64_t>(raw));
        pending_[static_cast<int>(s.component)] = raw_d * s.scale + s.offset;
      }
    }
    seen_mask_ |= std::uint64_t{1} << k;
    if (seen_mask_ != full_mask_) return false;
    seen_mask_ = 0;
    out.t_ns = first_t_ns_;
    out.stamp = first_stamp_;
    out.w_sensor = pending_;
    out.status_word = pending_status_;
    out.gauges = {};
    out.gauge_saturated = false;
    out.device_fault = false;  // what a declarative status means is the user's: recorded, not judged
    return true;
  }
  return false;
}

PollStatus DeclarativeForcePlate::poll(WrenchSample& out) noexcept {
  ++counters_.polls;
  out.error_frames = 0;
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::nanoseconds(static_cast<std::int64_t>(cfg_.response_timeout() * 1e9));
  CanFrame f;
  for (;;) {
    const auto st = next_data_frame(deadline, f, out, "the signal frames");
    if (st == PollStatus::timeout) break;
    if (st != PollStatus::ok) return st;
    bad_ = false;
    if (feed(f, out)) {
      finish(out);
      counters_.dropped_frames = channel_->stats().rx_dropped;
      return PollStatus::ok;
    }
    if (bad_) {
      ++counters_.bad_frames;
      ++counters_.consecutive_failures;
      char msg[96];
      std::snprintf(msg, sizeof msg, "frame 0x%X has %u bytes, the signals need more", f.id, f.len);
      problem(msg);
      return PollStatus::bad_frame;
    }
  }
  ++counters_.timeouts;
  ++counters_.consecutive_failures;
  problem(counters_.bus_off ? "no frames: bus-off" : "no complete frame set in time");
  return counters_.bus_off || out.error_frames != 0 ? PollStatus::bus_error : PollStatus::timeout;
}

}  // namespace hil::drivers
