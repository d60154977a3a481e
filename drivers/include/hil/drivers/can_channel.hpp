#pragma once
/// \file One small interface for a CAN bus endpoint, and its three implementations:
/// SocketCanChannel (the kernel, socketcan.hpp), CanLogChannel (`candump -L` files) and the
/// in-process CanLoopbackBus (for tests and the fake rig without a kernel bus).
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <hil/drivers/can_frame.hpp>

namespace hil::drivers {

/// Result of one channel operation; channels never throw once open.
enum class IoStatus : std::uint8_t {
  ok,
  timeout,  ///< nothing within the timeout (receive), or the queue stayed full (send)
  closed,   ///< end of log file, or the channel/bus was closed
  error     ///< see last_error()
};
const char* to_string(IoStatus s) noexcept;

struct CanChannelStats {
  std::uint64_t rx_frames = 0;  ///< frames returned by receive (error frames included)
  std::uint64_t tx_frames = 0;
  std::uint64_t rx_dropped = 0;    ///< frames lost before we read them (kernel SO_RXQ_OVFL, full queue)
  std::uint64_t tx_failed = 0;     ///< sends that failed or timed out
  std::uint64_t error_frames = 0;  ///< error frames received
};

/// What an endpoint listens to. Same meaning for every implementation.
struct CanChannelOptions {
  std::vector<CanFilter> filters;          ///< empty = every data frame (CAN_RAW_FILTER)
  std::uint32_t error_mask = kCanErrMask;  ///< error classes delivered (CAN_RAW_ERR_FILTER); 0 = none
  bool fd = true;                          ///< accept and send CAN FD frames (CAN_RAW_FD_FRAMES)
  bool receive_own = false;                ///< see our own sends (CAN_RAW_RECV_OWN_MSGS)
  std::size_t rx_queue = 8192;             ///< loopback: queue length before frames are dropped
};

/// A CAN endpoint. One thread sends and one receives at a time (the two may differ).
class CanChannel {
 public:
  virtual ~CanChannel() = default;
  CanChannel() = default;
  CanChannel(const CanChannel&) = delete;
  CanChannel& operator=(const CanChannel&) = delete;

  /// Sends one frame, waiting up to `timeout` while the transmit queue is full.
  virtual IoStatus send(const CanFrame& frame, std::chrono::nanoseconds timeout) noexcept = 0;
  /// Receives the next frame (with its receive timestamp), waiting up to `timeout`.
  virtual IoStatus receive(CanFrame& frame, std::chrono::nanoseconds timeout) noexcept = 0;
  virtual CanChannelStats stats() const noexcept = 0;
  /// Interface or file name, for messages.
  virtual std::string name() const = 0;
  /// Text of the last `error` status (empty if none). Not real-time safe.
  virtual std::string last_error() const = 0;
};

/// An in-process bus: frames sent on one endpoint reach every other endpoint (and the sender
/// with receive_own), after that endpoint's filters, stamped with the send time (software).
/// Thread-safe. Endpoints keep the bus alive.
class CanLoopbackBus : public std::enable_shared_from_this<CanLoopbackBus> {
 public:
  static std::shared_ptr<CanLoopbackBus> create(std::string name = "loop0");
  ~CanLoopbackBus();
  /// A new endpoint on this bus.
  std::unique_ptr<CanChannel> open(CanChannelOptions options = {});
  const std::string& name() const noexcept { return name_; }
  /// Wakes every endpoint; further receives return `closed`.
  void close();

  struct Impl;

 private:
  explicit CanLoopbackBus(std::string name);
  std::string name_;
  std::unique_ptr<Impl> impl_;
};

/// A `candump -L` log file as a channel. Read mode returns the logged frames in order with their
/// logged timestamps (optionally paced in real time); write mode appends one line per sent frame.
struct CanLogOptions {
  std::string interface;      ///< read: only lines of this interface (empty = all); write: name to log
  bool realtime = false;      ///< read: wait so frames come out at their logged spacing
  double speed = 1.0;         ///< read with realtime: playback speed factor
  CanChannelOptions channel;  ///< read: filters and error mask applied to logged frames
};

class CanLogChannel final : public CanChannel {
 public:
  /// \throws DeviceError if the file cannot be opened.
  static std::unique_ptr<CanLogChannel> open_read(const std::string& path, CanLogOptions options = {});
  /// Creates (truncates) the file. \throws DeviceError.
  static std::unique_ptr<CanLogChannel> open_write(const std::string& path, CanLogOptions options = {});
  ~CanLogChannel() override;

  /// Write mode: appends the frame (its t_ns, or now if 0). Read mode: `error`.
  IoStatus send(const CanFrame& frame, std::chrono::nanoseconds timeout) noexcept override;
  /// Read mode: next frame; `closed` at end of file; `error` for a malformed line (last_error()
  /// names file and line; the next call continues after it). Write mode: `closed`.
  IoStatus receive(CanFrame& frame, std::chrono::nanoseconds timeout) noexcept override;
  CanChannelStats stats() const noexcept override { return stats_; }
  std::string name() const override { return path_; }
  std::string last_error() const override { return last_error_; }
  /// Write mode: pushes buffered lines to the kernel.
  void flush() noexcept;
  /// The interface of the last frame read.
  const std::string& last_interface() const noexcept { return last_iface_; }

 private:
  CanLogChannel() = default;
  std::FILE* f_ = nullptr;
  bool write_ = false;
  std::string path_;
  CanLogOptions opt_;
  CanChannelStats stats_;
  std::string last_error_;
  std::string last_iface_;
  std::size_t line_no_ = 0;
  std::string line_;
  std::int64_t first_log_ns_ = -1;
  std::chrono::steady_clock::time_point first_wall_;
};

/// A channel that records its traffic: every frame received from and sent through `inner` is
/// also written to `log` (a CanLogChannel in write mode), received frames with their receive
/// stamps, sent frames with the send time. For the run's raw/ folder. Log write failures are
/// counted (log_failures()), never returned to the caller.
class CanRecordingChannel final : public CanChannel {
 public:
  CanRecordingChannel(std::unique_ptr<CanChannel> inner, std::unique_ptr<CanLogChannel> log, bool record_sent = true);
  IoStatus send(const CanFrame& frame, std::chrono::nanoseconds timeout) noexcept override;
  IoStatus receive(CanFrame& frame, std::chrono::nanoseconds timeout) noexcept override;
  CanChannelStats stats() const noexcept override { return inner_->stats(); }
  std::string name() const override { return inner_->name(); }
  std::string last_error() const override { return inner_->last_error(); }
  std::uint64_t log_failures() const noexcept { return log_failures_; }
  CanLogChannel& log() noexcept { return *log_; }

 private:
  std::unique_ptr<CanChannel> inner_;
  std::unique_ptr<CanLogChannel> log_;
  bool record_sent_;
  std::uint64_t log_failures_ = 0;
};

/// Current CLOCK_REALTIME in ns since the epoch (the clock kernel CAN stamps use).
std::int64_t realtime_ns() noexcept;

}  // namespace hil::drivers
