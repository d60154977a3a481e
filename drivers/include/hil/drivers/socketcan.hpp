#pragma once
/// \file The kernel's SocketCAN (PF_CAN, CAN_RAW) as a CanChannel.
#include <atomic>
#include <memory>
#include <string>

#include <hil/drivers/can_channel.hpp>

namespace hil::drivers {

struct SocketCanOptions {
  std::string interface = "vcan0";
  CanChannelOptions channel;
  /// Ask for SO_TIMESTAMPING (hardware stamp when the interface gives one, else software).
  bool timestamps = true;
};

/// A CAN_RAW socket bound to one interface: filters (CAN_RAW_FILTER), error frames
/// (CAN_RAW_ERR_FILTER), CAN FD (CAN_RAW_FD_FRAMES), kernel receive timestamps (SO_TIMESTAMPING,
/// hardware if given, else software; SO_TIMESTAMPNS as fallback) and the kernel drop counter
/// (SO_RXQ_OVFL). ENOBUFS on send is waited out with poll() up to the send timeout.
class SocketCanChannel final : public CanChannel {
 public:
  /// \throws DeviceError naming the interface and the failing call (e.g. no PF_CAN in the kernel).
  static std::unique_ptr<SocketCanChannel> open(const SocketCanOptions& options);
  /// True if this kernel can create PF_CAN sockets.
  static bool kernel_supports_can() noexcept;
  ~SocketCanChannel() override;

  IoStatus send(const CanFrame& frame, std::chrono::nanoseconds timeout) noexcept override;
  IoStatus receive(CanFrame& frame, std::chrono::nanoseconds timeout) noexcept override;
  CanChannelStats stats() const noexcept override;
  std::string name() const override { return iface_; }
  std::string last_error() const override { return last_error_; }
  int fd() const noexcept { return fd_; }

 private:
  SocketCanChannel() = default;
  int fd_ = -1;
  std::string iface_;
  bool fd_frames_ = false;
  std::uint32_t last_ovfl_ = 0;
  bool have_ovfl_ = false;
  std::atomic<std::uint64_t> rx_{0}, tx_{0}, dropped_{0}, tx_failed_{0}, err_{0};
  std::string last_error_;
};

}  // namespace hil::drivers
