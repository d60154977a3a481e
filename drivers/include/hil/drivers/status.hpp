#pragma once
/// \file What a polling call returns, and the per-device counters the acquisition layer publishes
/// as DeviceStatus.
#include <chrono>
#include <cstdint>
#include <thread>

namespace hil::drivers {

/// Result of one poll. Polls never throw.
enum class PollStatus : std::uint8_t {
  ok,            ///< a sample was produced
  timeout,       ///< the device did not answer in time (or was silent)
  bad_frame,     ///< a malformed/corrupt frame or response arrived (counted, no sample)
  bus_error,     ///< error frames / bus-off seen and no sample
  exception,     ///< Modbus exception response (device answered, refused)
  disconnected,  ///< link down; reconnection is attempted with back-off by later polls
  closed         ///< the channel ended (end of a log, bus closed)
};
const char* to_string(PollStatus s) noexcept;

struct DeviceCounters {
  std::uint64_t polls = 0;
  std::uint64_t samples = 0;
  std::uint64_t timeouts = 0;
  std::uint64_t bad_frames = 0;
  std::uint64_t late_frames = 0;   ///< answers that came after their poll had given up
  std::uint64_t error_frames = 0;  ///< CAN error frames seen
  std::uint64_t bus_off_events = 0;
  std::uint64_t exceptions = 0;  ///< Modbus exception responses
  std::uint64_t retries = 0;
  std::uint64_t reconnects = 0;      ///< successful reconnections after a lost link
  std::uint64_t dropped_frames = 0;  ///< frames the channel lost (kernel overflow)
  /// Robot: polls where a joint angle wrapped between its angle and turn-counter requests, so
  /// both were read again (the decoded joint would have been a full turn off).
  std::uint64_t torn_reads = 0;
  /// Samples the device itself flagged as bad (ATI status word non-zero, RDT status, sensor fault):
  /// delivered with the device-fault quality flag, never as good samples.
  std::uint64_t device_faults = 0;
  std::uint32_t consecutive_failures = 0;
  bool connected = false;
  bool bus_off = false;  ///< last error frame said bus-off and nothing valid came since
};

/// The steady clock in nanoseconds: deadlines and silences (never jumps).
inline std::int64_t steady_ns() noexcept {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Paces a polling loop at a fixed rate on absolute deadlines (no drift); counts overruns.
class RatePacer {
 public:
  explicit RatePacer(double rate_hz)
      : period_(std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / rate_hz))), next_(std::chrono::steady_clock::now()) {}
  /// Sleeps until the next period starts. When more than one period late, skips ahead.
  void wait() {
    next_ += period_;
    const auto now = std::chrono::steady_clock::now();
    if (next_ < now - period_) {
      ++overruns_;
      next_ = now;
      return;
    }
    std::this_thread::sleep_until(next_);
  }
  std::chrono::nanoseconds period() const noexcept { return period_; }
  std::uint64_t overruns() const noexcept { return overruns_; }

 private:
  std::chrono::nanoseconds period_;
  std::chrono::steady_clock::time_point next_;
  std::uint64_t overruns_ = 0;
};

}  // namespace hil::drivers
