// The Net F/T box's CAN mode, short data: request on the base address, answers on base+5 and
// base+6. The answers of one request are taken together only: a second answer that comes before
// this poll's first belongs to an earlier, abandoned request (late), as on the NETCANOEM.
#include <spdlog/spdlog.h>

#include <cstdio>

#include <hil/drivers/error.hpp>
#include <hil/drivers/netft_driver.hpp>

namespace hil::drivers {
namespace {
using Clock = std::chrono::steady_clock;
std::chrono::nanoseconds seconds(double s) { return std::chrono::nanoseconds(static_cast<std::int64_t>(s * 1e9)); }
bool is_plain(const CanFrame& f) noexcept { return !f.error && !f.extended && !f.rtr && !f.fd; }
}  // namespace

NetFtCanDriver::NetFtCanDriver(const ForcePlateConfig& cfg, std::unique_ptr<CanChannel> channel) : CanForcePlate(cfg, std::move(channel)) {
  if (cfg_.protocol != ForcePlateProtocol::ati_netft_can) throw ConfigError("protocol", "NetFtCanDriver needs protocol ati_netft_can");
  n_per_count_ = cfg_.netft_calibration.newtons_per_count();
  nm_per_count_ = cfg_.netft_calibration.newton_metres_per_count();
}

void NetFtCanDriver::drain() noexcept {
  CanFrame f;
  while (channel_->receive(f, std::chrono::nanoseconds(0)) == IoStatus::ok) {
    if (f.error) book_error_frame(f);
    else if (is_plain(f) && (f.id == cfg_.base_id + netft_can::kShortFirst || f.id == cfg_.base_id + netft_can::kShortSecond))
      ++counters_.late_frames;
  }
}

bool NetFtCanDriver::bias_on_device() noexcept {
  return channel_->send(netft_can::request(cfg_.base_id, netft_can::kRequestBias), seconds(cfg_.response_timeout())) == IoStatus::ok;
}

ForcePlateInfo NetFtCanDriver::start() {
  char where[96];
  std::snprintf(where, sizeof where, "ATI Net F/T (CAN) at base address 0x%03X on %s", cfg_.base_id, channel_->name().c_str());
  // A reading proves the box answers; start() waits up to startup_timeout_s per try.
  const double saved = cfg_.response_timeout_s;
  cfg_.response_timeout_s = cfg_.startup_timeout_s;
  started_ = true;
  WrenchSample s;
  PollStatus st = PollStatus::timeout;
  for (int attempt = 0; attempt < cfg_.startup_tries && st != PollStatus::ok; ++attempt) {
    if (attempt > 0) ++counters_.retries;
    st = poll(s);
    if (st == PollStatus::closed) break;
  }
  cfg_.response_timeout_s = saved;
  if (st != PollStatus::ok) {
    started_ = false;
    throw DeviceError(std::string(where) + ": no short-data answer (ids base+5, base+6) to " + std::to_string(cfg_.startup_tries) +
                      " requests (" + last_problem_ +
                      "; is CAN Bus selected on the box's Communications page, and the DIP switches' "
                      "base address and bit rate the rig's?)");
  }
  counters_.connected = true;
  ForcePlateInfo info;
  info.protocol = "ati_netft_can";
  info.units = cfg_.netft_calibration.force_unit + ", " + cfg_.netft_calibration.torque_unit;
  info.counts_per_force = static_cast<std::int32_t>(cfg_.netft_calibration.counts_per_force);
  info.counts_per_torque = static_cast<std::int32_t>(cfg_.netft_calibration.counts_per_torque);
  info.calibration = Matrix6d::Identity();  // the box sends F/T values
  spdlog::info("{}: answering, units {}, counts {}/{} (short data)", where, info.units, cfg_.netft_calibration.counts_per_force,
               cfg_.netft_calibration.counts_per_torque);
  return info;
}

PollStatus NetFtCanDriver::poll(WrenchSample& out) noexcept {
  ++counters_.polls;
  if (!started_) {
    problem("poll() before start()");
    return PollStatus::disconnected;
  }
  drain();
  out.error_frames = 0;
  out.gauges = {};
  const std::uint32_t id_a = cfg_.base_id + netft_can::kShortFirst, id_b = cfg_.base_id + netft_can::kShortSecond;
  const auto timeout = seconds(cfg_.response_timeout());
  const auto deadline = Clock::now() + timeout;
  if (const auto sst = send_request(netft_can::request(cfg_.base_id, netft_can::kRequestShortData), timeout, "short-data");
      sst != PollStatus::ok)
    return sst;
  netft_can::ShortData d;
  bool have_a = false, have_b = false;
  CanFrame f;
  char msg[128];
  for (;;) {
    const auto st = next_data_frame(deadline, f, out, "short data");
    if (st == PollStatus::timeout) break;
    if (st != PollStatus::ok) return st;
    if (!is_plain(f) || (f.id != id_a && f.id != id_b)) continue;
    if (f.id == id_a) {
      if (have_a) ++counters_.late_frames;  // the box answers in order: the newest is ours
      if (!netft_can::decode_short_first(f, d)) {
        ++counters_.bad_frames;
        ++counters_.consecutive_failures;
        std::snprintf(msg, sizeof msg, "short-data answer 1 (id 0x%03X) has length %u, expected 8", id_a, f.len);
        problem(msg);
        return PollStatus::bad_frame;
      }
      have_a = true;
      out.t_ns = f.t_ns;
      out.stamp = f.stamp;
      continue;
    }
    if (!have_a) {
      ++counters_.late_frames;  // an abandoned request's second answer: taking it would tear the reading
      continue;
    }
    if (!netft_can::decode_short_second(f, d)) {
      ++counters_.bad_frames;
      ++counters_.consecutive_failures;
      std::snprintf(msg, sizeof msg, "short-data answer 2 (id 0x%03X) has length %u, expected 8", id_b, f.len);
      problem(msg);
      return PollStatus::bad_frame;
    }
    have_b = true;
    break;
  }
  if (!(have_a && have_b)) return answer_missing(out, have_a ? "short-data answer 2 missing" : "no short-data answer");
  last_sample_ = d.sample;
  bool sat = false;
  for (std::size_t i = 0; i < 6; ++i) {
    sat = sat || d.counts[i] == INT16_MAX || d.counts[i] == INT16_MIN;
    out.w_sensor[static_cast<int>(i)] = d.counts[i] * (i < 3 ? n_per_count_ : nm_per_count_);
  }
  out.gauge_saturated = sat;
  out.status_word = d.status;
  out.device_fault = d.status != 0;  // any bit, as for every device here
  if (out.device_fault) ++counters_.device_faults;
  finish(out);
  counters_.dropped_frames = channel_->stats().rx_dropped;
  return PollStatus::ok;
}

std::string NetFtCanDriver::describe_status(const WrenchSample& s) const {
  char buf[96];
  std::snprintf(buf, sizeof buf, "Net F/T CAN status 0x%04X", s.status_word);
  std::string out = buf;
  std::string bits;
  for (int b = 15; b >= 0; --b)
    if ((s.status_word >> b) & 1U) bits += (bits.empty() ? "" : ", ") + std::string("bit ") + std::to_string(b);
  return out + (bits.empty() ? "" : " (" + bits + ")");
}

}  // namespace hil::drivers
