#pragma once
/// \file Health of one device, from what its driver reports: samples, drops, errors, link state.
/// Pure: the caller passes the time. A silence longer than `silence_periods` nominal periods,
/// a fault, a drop or a lost link changes the state at the next update(), so a fault is visible
/// within three sample periods when update() runs at the sample rate (silence is declared after
/// two, leaving a period for the poll in flight).
#include <cstdint>
#include <deque>
#include <string>

namespace hil::acquisition {

enum class DeviceState : std::uint8_t { ok = 0, degraded = 1, fault = 2, disconnected = 3 };
const char* to_string(DeviceState s);

struct DeviceHealth {
  std::string device;
  DeviceState state = DeviceState::disconnected;
  bool connected = false;
  double rate_hz = 0.0;            ///< samples over the last second
  double last_sample_age_s = 0.0;  ///< +inf before the first sample
  std::uint64_t samples = 0;
  std::uint64_t frames_dropped = 0;
  std::uint64_t errors = 0;
  std::uint64_t device_faults = 0;  ///< readings the device flagged bad (from the driver's counters)
  std::string last_error;
  std::string reason;  ///< why the state is what it is, e.g. "silent for 4.0 ms"
};

class DeviceMonitor {
 public:
  /// \param lost_per_s_tolerated  readings lost per second before the device counts as degraded
  ///        (default: 5 % of the nominal rate, at least 1): late answers on a busy machine are
  ///        counted (and bridged, with GAP_BEFORE) but do not flap the state.
  DeviceMonitor(std::string device, double nominal_rate_hz, double silence_periods = 2.0, double lost_per_s_tolerated = -1.0);

  void sample(std::int64_t t_ns);
  void dropped(std::uint64_t n, std::int64_t t_ns);
  /// A fault reported by the device or its driver (bus-off, exception response, status bit...).
  void error(const std::string& what, std::int64_t t_ns);
  void link(bool connected, std::int64_t t_ns);

  /// Re-evaluates the state at `now_ns`. \returns true when the state or its cause changed
  /// (publish then).
  bool update(std::int64_t now_ns);
  DeviceHealth health(std::int64_t now_ns) const;
  DeviceState state() const { return state_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string device_;
  double period_s_;
  double silence_periods_;
  bool connected_ = false;
  std::int64_t last_sample_ns_ = 0;
  std::int64_t last_error_ns_ = 0;
  std::int64_t last_drop_ns_ = 0;
  std::uint64_t samples_ = 0, dropped_ = 0, errors_ = 0;
  std::string last_error_;
  std::deque<std::int64_t> recent_;        ///< sample times within the last second
  std::deque<std::int64_t> recent_drops_;  ///< times of lost readings within the last second
  double drops_tolerated_;
  DeviceState state_ = DeviceState::disconnected;
  std::string reason_ = "not connected yet";
  int cause_ = -1;  ///< what made the state: link, error, silence, losses, none
};

/// Which of a device's state changes to write to the log. Every change into fault or disconnected
/// is logged, unless the same fault for the same reason was logged within `quiet_s` (a plate whose
/// every fifth answer is corrupt would otherwise write hundreds of identical lines a second), and
/// the first change in any `quiet_s` window; the others (a device flapping between
/// degraded and ok on a busy machine, several times a second) are counted, and the next logged line
/// says how many were held back. flush() logs the current state once the window has passed with
/// changes held back, so the log always ends on the state the device is in. The status topic
/// carries every change regardless. Pure: the caller passes the time.
class StateLog {
 public:
  explicit StateLog(double quiet_s = 1.0) : quiet_ns_(static_cast<std::int64_t>(quiet_s * 1e9)) {}
  /// A change into `s` at t_ns: true when it is to be logged now, with `held_back` the changes
  /// not logged since the last line.
  bool change(DeviceState s, std::int64_t t_ns, int& held_back, const std::string& reason = {});
  /// Called periodically: true when changes were held back and the window has passed.
  /// `s`, `reason`: the state that line will log.
  bool flush(std::int64_t t_ns, int& held_back, DeviceState s = DeviceState::ok, const std::string& reason = {});

 private:
  std::int64_t quiet_ns_;
  std::int64_t last_ns_ = 0;
  bool logged_ = false;
  int held_ = 0;
  DeviceState last_state_ = DeviceState::ok;  ///< the state and reason of the last line logged
  std::string last_reason_;
};

}  // namespace hil::acquisition
