#pragma once
/// \file The ATI Net F/T box streaming RDT records over UDP (netft_rdt.hpp for the wire format).
/// The box pushes records at its RDT rate once asked; poll() hands them out one by one, in order,
/// none skipped: a record lost on the way shows as a gap in rdt_sequence and is counted
/// (DeviceCounters::dropped_frames), as are the socket's own drops (SO_RXQ_OVFL). A silent box is
/// asked to stream again, so a box that rebooted or lost the request recovers by itself.
#include <cstdint>
#include <string>
#include <vector>

#include <hil/drivers/force_plate.hpp>
#include <hil/drivers/netft_can.hpp>
#include <hil/drivers/netft_rdt.hpp>

namespace hil::drivers {

class NetFtRdtDriver final : public ForcePlate {
 public:
  /// \throws ConfigError on a bad configuration (protocol ati_netft_rdt, host, port, calibration).
  explicit NetFtRdtDriver(const ForcePlateConfig& cfg);
  /// Asks the box to stop streaming.
  ~NetFtRdtDriver() override;

  /// Opens the socket, asks for real-time streaming and waits for the first record.
  /// \throws DeviceError naming the box and what did not answer.
  ForcePlateInfo start() override;
  PollStatus poll(WrenchSample& out) noexcept override;
  std::string describe_status(const WrenchSample& s) const override;
  std::string link() const override;
  bool paced() const noexcept override { return false; }  ///< the box pushes at its RDT rate

  /// Asks the box to bias its readings at the present load (RDT 0x0042). False if not sent.
  bool bias_on_device() noexcept;
  /// Clears the box's latched monitor condition (RDT 0x0041, status bit 16). False if not sent.
  bool reset_latch() noexcept;
  /// The rdt_sequence of the last record handed out.
  std::uint32_t last_rdt_sequence() const noexcept { return last_rdt_seq_; }

 private:
  bool send(netft::RdtCommand c, std::uint32_t sample_count = 0) noexcept;
  /// Waits until `deadline_ns` (steady clock) for a datagram and unpacks its records into pending_.
  PollStatus receive(std::int64_t deadline_ns) noexcept;

  int fd_ = -1;
  std::vector<std::uint8_t> buffer_;
  std::vector<netft::RdtRecord> pending_;  ///< records of the last datagram not yet handed out
  std::size_t next_ = 0;
  std::int64_t pending_t_ns_ = 0;
  StampSource pending_stamp_ = StampSource::none;
  std::uint32_t last_rdt_seq_ = 0;
  bool have_seq_ = false;
  std::uint32_t socket_drops_ = 0;  ///< SO_RXQ_OVFL's running count
  double n_per_count_ = 0.0, nm_per_count_ = 0.0;
  std::int64_t last_restart_ns_ = 0;  ///< steady clock
  std::int64_t last_record_ns_ = 0;   ///< steady clock
  bool started_ = false;
};

/// The Net F/T box in CAN mode, short data (netft_can.hpp): one request per poll, two answers. The
/// 16-bit values are scaled by the rig's counts per unit (ForcePlateConfig::netft_calibration);
/// any status bit marks the reading a device fault.
class NetFtCanDriver final : public CanForcePlate {
 public:
  /// \throws ConfigError on a bad configuration (protocol ati_netft_can, base address, counts).
  NetFtCanDriver(const ForcePlateConfig& cfg, std::unique_ptr<CanChannel> channel);
  /// Asks for one reading until the box answers. \throws DeviceError naming the base address.
  ForcePlateInfo start() override;
  PollStatus poll(WrenchSample& out) noexcept override;
  std::string describe_status(const WrenchSample& s) const override;
  /// Asks the box to bias its readings at the present load (0x04). False if not sent.
  bool bias_on_device() noexcept;
  /// The box's sample number in the last reading handed out.
  std::uint16_t last_sample_number() const noexcept { return last_sample_; }

 private:
  void drain() noexcept;
  double n_per_count_ = 0.0, nm_per_count_ = 0.0;
  std::uint16_t last_sample_ = 0;
  bool started_ = false;
};

}  // namespace hil::drivers
