#include <hil/acquisition/monitor.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace hil::acquisition {

const char* to_string(DeviceState s) {
  switch (s) {
    case DeviceState::ok: return "ok";
    case DeviceState::degraded: return "degraded";
    case DeviceState::fault: return "fault";
    case DeviceState::disconnected: return "disconnected";
  }
  return "?";
}

DeviceMonitor::DeviceMonitor(std::string device, double nominal_rate_hz, double silence_periods, double lost_per_s_tolerated)
    : device_(std::move(device)), period_s_(1.0 / nominal_rate_hz), silence_periods_(silence_periods),
      drops_tolerated_(lost_per_s_tolerated >= 0 ? lost_per_s_tolerated : std::max(1.0, 0.05 * nominal_rate_hz)) {}

void DeviceMonitor::sample(std::int64_t t_ns) {
  ++samples_;
  last_sample_ns_ = t_ns;
  connected_ = true;
  recent_.push_back(t_ns);
  while (!recent_.empty() && recent_.front() < t_ns - 1'000'000'000) recent_.pop_front();
}

void DeviceMonitor::dropped(std::uint64_t n, std::int64_t t_ns) {
  if (n == 0) return;
  dropped_ += n;
  last_drop_ns_ = t_ns;
  for (std::uint64_t i = 0; i < n && i < 100000; ++i) recent_drops_.push_back(t_ns);
}

void DeviceMonitor::error(const std::string& what, std::int64_t t_ns) {
  ++errors_;
  last_error_ = what;
  last_error_ns_ = t_ns;
}

void DeviceMonitor::link(bool connected, std::int64_t t_ns) {
  connected_ = connected;
  if (!connected) last_error_ns_ = std::max(last_error_ns_, t_ns);
}

bool DeviceMonitor::update(std::int64_t now_ns) {
  while (!recent_drops_.empty() && recent_drops_.front() < now_ns - 1'000'000'000) recent_drops_.pop_front();
  DeviceState s;
  std::string why;
  int cause = 0;
  const double silence_s = (now_ns - last_sample_ns_) * 1e-9;
  const double limit_s = silence_periods_ * period_s_;
  if (!connected_) {
    s = DeviceState::disconnected;
    why = last_error_.empty() ? "not connected" : "link lost: " + last_error_;
    cause = 1;
  } else if (last_error_ns_ != 0 && last_error_ns_ >= last_sample_ns_ - static_cast<std::int64_t>(period_s_ * 1e9)) {
    // A fault holds until good samples flow again for more than a period after it.
    s = DeviceState::fault;
    why = last_error_;
    cause = 2;
  } else if (samples_ > 0 && silence_s > limit_s) {
    s = DeviceState::degraded;
    why = fmt::format("silent for {:.1f} ms", silence_s * 1e3);
    cause = 3;
  } else if (static_cast<double>(recent_drops_.size()) > drops_tolerated_) {
    s = DeviceState::degraded;
    why = fmt::format("{} readings lost in the last second ({} in all)", recent_drops_.size(), dropped_);
    cause = 4;
  } else {
    s = DeviceState::ok;
  }
  const bool changed = s != state_ || cause != cause_ || (cause == 2 && why != reason_);
  state_ = s;
  cause_ = cause;
  reason_ = why;
  return changed;
}

DeviceHealth DeviceMonitor::health(std::int64_t now_ns) const {
  DeviceHealth h;
  h.device = device_;
  h.state = state_;
  h.connected = connected_;
  std::size_t n = 0;
  for (auto t : recent_) n += t >= now_ns - 1'000'000'000;
  h.rate_hz = static_cast<double>(n);
  h.last_sample_age_s = samples_ ? (now_ns - last_sample_ns_) * 1e-9 : INFINITY;
  h.samples = samples_;
  h.frames_dropped = dropped_;
  h.errors = errors_;
  h.last_error = last_error_;
  h.reason = reason_;
  return h;
}

bool StateLog::change(DeviceState s, std::int64_t t_ns, int& held_back, const std::string& reason) {
  const bool serious = s == DeviceState::fault || s == DeviceState::disconnected;
  const bool in_window = logged_ && t_ns - last_ns_ < quiet_ns_;
  const bool repeated = s == last_state_ && reason == last_reason_;
  if (in_window && (!serious || repeated)) {
    ++held_;
    return false;
  }
  held_back = held_;
  held_ = 0;
  last_ns_ = t_ns;
  logged_ = true;
  last_state_ = s;
  last_reason_ = reason;
  return true;
}

bool StateLog::flush(std::int64_t t_ns, int& held_back, DeviceState s, const std::string& reason) {
  if (held_ == 0 || t_ns - last_ns_ < quiet_ns_) return false;
  held_back = held_;
  held_ = 0;
  last_ns_ = t_ns;
  last_state_ = s;
  last_reason_ = reason;
  return true;
}

}  // namespace hil::acquisition
