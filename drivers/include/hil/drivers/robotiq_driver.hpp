#pragma once
/// \file The Robotiq FT 300(-S) on a serial line (robotiq_ft300.hpp for the wire format). Modbus
/// RTU through libmodbus for its identity and, unless the rig allows the stream-start write, for
/// polling registers 180-185. With that write allowed, the sensor streams 100 Hz frames that
/// poll() hands out one by one, in order. The stream has no sequence numbers: frames lost on the
/// line are estimated from arrival gaps (DeviceCounters::dropped_frames), frames failing their CRC
/// are counted (bad_frames) and never delivered, and a silent sensor is asked to stream again.
#include <cstdint>
#include <memory>
#include <string>

#include <hil/drivers/force_plate.hpp>
#include <hil/drivers/robotiq_ft300.hpp>

namespace hil::drivers {

class RobotiqFt300Driver final : public ForcePlate {
 public:
  /// \throws ConfigError on a bad configuration (protocol robotiq_ft300, device, baud, slave).
  explicit RobotiqFt300Driver(const ForcePlateConfig& cfg);
  /// Stops the stream (the jam signal), so the sensor answers Modbus for the next user.
  ~RobotiqFt300Driver() override;

  /// Opens the port, stops a stream left running, reads firmware, serial number and production
  /// year, and starts the stream if allowed. \throws DeviceError naming the port and the step.
  ForcePlateInfo start() override;
  PollStatus poll(WrenchSample& out) noexcept override;
  std::string describe_status(const WrenchSample& s) const override;
  std::string link() const override { return cfg_.serial_device; }
  bool paced() const noexcept override { return !cfg_.robotiq_stream; }  ///< the stream pushes at 100 Hz

  /// The framer's counts (stream mode): bytes that belonged to no frame, frames failing the CRC.
  const robotiq::StreamFramer& framer() const noexcept { return framer_; }

 private:
  PollStatus poll_registers(WrenchSample& out) noexcept;
  PollStatus poll_stream(WrenchSample& out) noexcept;
  bool start_stream() noexcept;
  void jam() noexcept;
  void account_arrival(std::int64_t t_ns) noexcept;

  struct Modbus;
  std::unique_ptr<Modbus> mb_;
  robotiq::StreamFramer framer_;
  std::uint64_t counted_bad_crc_ = 0;
  std::int64_t last_frame_ns_ = 0;    ///< receive time of the last frame (steady clock)
  std::int64_t last_restart_ns_ = 0;  ///< steady clock
  std::int64_t read_t_ns_ = 0;        ///< CLOCK_REALTIME of the read that brought the buffered bytes
  std::int64_t read_steady_ns_ = 0;   ///< the same read on the steady clock
  robotiq::Reading first_;            ///< the frame that showed the stream had started
  bool have_first_ = false;
  std::uint64_t gap_pending_ = 0;  ///< frames a gap says were lost, unless a burst of late ones follows
  bool started_ = false;
};

}  // namespace hil::drivers
