#pragma once
/// \file Force-plate drivers on a CanChannel: the ATI NETCANOEM protocol and a declarative
/// decoder configured per signal (frame id, bits, byte order, scale, offset, wrench component).
/// Both produce the wrench on the force plate, about the plate origin, in the force-plate frame
/// (`w_fp` = [f_fp (N); m_fp (N·m)]), after a software tare and the sensor→plate transform.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <chrono>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <hil/drivers/ati_protocol.hpp>
#include <hil/drivers/can_channel.hpp>
#include <hil/drivers/netft_rdt.hpp>
#include <hil/drivers/robotiq_ft300.hpp>
#include <hil/drivers/status.hpp>
#include <hil/so3/so3.hpp>

namespace hil::drivers {

using hil::Matrix6d;
using hil::Vector6d;

enum class WrenchComponent : std::uint8_t { fx, fy, fz, mx, my, mz, status };
/// "fx".."mz", "status". \throws ConfigError(field) on anything else.
WrenchComponent parse_wrench_component(const std::string& s, const std::string& field);
const char* to_string(WrenchComponent c) noexcept;

/// One signal of the declarative decoder (a DBC-style signal).
struct CanSignal {
  WrenchComponent component = WrenchComponent::fx;
  std::uint32_t frame_id = 0;
  bool extended_id = false;
  unsigned start_bit = 0;  ///< little endian: LSB position (Intel); big endian: MSB position (Motorola/DBC)
  unsigned length_bits = 16;
  bool is_signed = true;
  bool big_endian = false;
  double scale = 1.0;  ///< physical = raw * scale + offset (N, N·m; status: raw)
  double offset = 0.0;
};

/// Raw bits of a signal (sign-extended when signed). \pre the frame holds the signal's bytes.
std::int64_t extract_raw(const CanSignal& s, const std::uint8_t* data) noexcept;
/// Writes raw bits into a payload (for fakes and tests).
void insert_raw(const CanSignal& s, std::int64_t raw, std::uint8_t* data) noexcept;
/// Payload bytes a signal needs.
unsigned bytes_needed(const CanSignal& s) noexcept;
/// \throws ConfigError naming `signals[i].<field>`.
void validate_signals(const std::vector<CanSignal>& signals);

/// ati_netcanoem, declarative and ati_netft_can (the Net F/T box's CAN mode) speak CAN;
/// ati_netft_rdt is the Net F/T box's UDP stream; robotiq_ft300 is Modbus RTU (and its stream) on a
/// serial line.
enum class ForcePlateProtocol : std::uint8_t { ati_netcanoem, declarative, ati_netft_rdt, robotiq_ft300, ati_netft_can };
const char* to_string(ForcePlateProtocol p) noexcept;

struct ForcePlateConfig {
  ForcePlateProtocol protocol = ForcePlateProtocol::ati_netcanoem;
  std::string interface = "vcan0";            ///< SocketCAN interface (used by whoever opens the channel)
  std::uint32_t base_id = ati::kFactoryBase;  ///< NETCANOEM base id (0..0x7F), factory 0x20
  std::string host;                           ///< ati_netft_rdt: the box's IPv4 address
  int port = netft::kRdtPort;                 ///< ati_netft_rdt: UDP port
  netft::Calibration netft_calibration;       ///< ati_netft_rdt: counts per unit (rig file or the box's netftapi2.xml)
  std::string serial_device;                  ///< robotiq_ft300: the serial port (/dev/ttyUSB0)
  int serial_baud = robotiq::kBaud;           ///< robotiq_ft300: 19200 only
  int modbus_slave = robotiq::kSlave;         ///< robotiq_ft300: slave id, 9
  /// robotiq_ft300: the rig file allows the one write the driver may make (0x0200 to register
  /// 410, which starts the 100 Hz stream). Without it the driver only reads registers 180-185.
  bool robotiq_stream = false;
  double rate_hz = 1000.0;                                        ///< polling rate (CAN); the box's RDT output rate (ati_netft_rdt)
  Eigen::Isometry3d T_fp_sensor = Eigen::Isometry3d::Identity();  ///< sensor frame in the plate frame
  std::vector<CanSignal> signals;                                 ///< declarative only
  std::vector<double> saturation_limits;                          ///< |fx fy fz mx my mz| limits in N, N·m; empty = unknown
  double response_timeout_s = 0.0;                                ///< per poll; 0 = 0.9 period (NETCANOEM) or 3 periods (declarative, RDT)
  double startup_timeout_s = 0.1;                                 ///< per start-up request (NETCANOEM; RDT: for the first record)
  int startup_tries = 3;
  unsigned tare_samples = 16;  ///< samples averaged by tare()
  /// \throws ConfigError naming the field.
  void validate() const;
  double response_timeout() const noexcept;
};

/// One wrench sample.
struct WrenchSample {
  std::int64_t t_ns = 0;  ///< kernel receive time of the (first) frame, CLOCK_REALTIME ns
  StampSource stamp = StampSource::none;
  std::uint64_t sequence = 0;
  Vector6d w_fp = Vector6d::Zero();      ///< tared, force-plate frame, about the plate origin
  Vector6d w_sensor = Vector6d::Zero();  ///< raw, sensor frame, before tare
  ati::Gauges gauges{};                  ///< ATI only
  std::uint32_t status_word = 0;         ///< the device's status word (ATI) / declarative `status` signal
  std::uint8_t saturated_axes = 0;       ///< bit i: |w_fp[i]| ≥ saturation_limits[i]
  bool gauge_saturated = false;          ///< a strain gauge at its int16 limit
  /// The device flagged this reading as bad (ATI: any status bit). Such a sample is delivered with
  /// the device-fault quality flag and counted (DeviceCounters::device_faults), never as good.
  bool device_fault = false;
  bool taring = false;             ///< a tare is being averaged
  std::uint32_t error_frames = 0;  ///< CAN error frames seen during this poll
};

/// What start() learned about the device.
struct ForcePlateInfo {
  std::string protocol;
  std::string serial;
  std::string firmware;
  std::string units;
  std::int32_t counts_per_force = 0, counts_per_torque = 0;
  Matrix6d calibration = Matrix6d::Zero();  ///< ATI: M (gauges → counts)
};

/// A force plate, whatever its link (CAN, UDP, serial). Not thread-safe, except tare() which any
/// thread may call.
class ForcePlate {
 public:
  virtual ~ForcePlate() = default;
  ForcePlate(const ForcePlate&) = delete;
  ForcePlate& operator=(const ForcePlate&) = delete;

  /// Reads what the device must tell before polling (ATI: serial, firmware, units, counts,
  /// calibration matrix). \throws DeviceError naming the device and the step that failed.
  virtual ForcePlateInfo start() = 0;
  /// One sample: ATI sends a request and waits for the answer; the declarative decoder waits for
  /// one complete set of frames. Never throws; \returns the status, `out` is valid only on ok.
  virtual PollStatus poll(WrenchSample& out) noexcept = 0;
  /// Why the device flagged `s` (device_fault): its status word in words. Not real-time safe.
  virtual std::string describe_status(const WrenchSample& s) const;
  /// The link's own trouble during the poll that produced `s` (CAN error frames); empty if none.
  virtual std::string describe_link_errors(const WrenchSample& s) const;
  /// Both of the above, joined: what makes `s` a device-fault sample. Not real-time safe.
  std::string describe_fault(const WrenchSample& s) const;
  /// The link, for messages: "can0", "udp 127.0.0.1:49152".
  virtual std::string link() const = 0;
  /// True when the device answers requests and the caller paces the polls at rate_hz; false for a
  /// device that pushes its readings (poll() then waits for the next one and must be called again
  /// at once, or a backlog builds up behind the pacing).
  virtual bool paced() const noexcept { return true; }

  /// Averages the next `samples` raw wrenches (0 = config.tare_samples) and subtracts them from then
  /// on (sensor frame). Thread-safe.
  void tare(unsigned samples = 0) noexcept;
  /// Removes the tare. Thread-safe.
  void clear_tare() noexcept;
  Vector6d tare_bias() const;

  const DeviceCounters& counters() const noexcept { return counters_; }
  /// Text of the last non-ok poll (not real-time safe to read concurrently).
  const std::string& last_problem() const noexcept { return last_problem_; }
  const ForcePlateConfig& config() const noexcept { return cfg_; }

 protected:
  /// \throws ConfigError on a bad configuration.
  explicit ForcePlate(const ForcePlateConfig& cfg);
  /// Tare, transform, saturation. Real-time safe.
  void finish(WrenchSample& s) noexcept;
  void problem(const char* what) noexcept;

  ForcePlateConfig cfg_;
  DeviceCounters counters_;
  std::string last_problem_;
  std::uint64_t sequence_ = 0;

 private:
  Matrix6d X_fp_sensor_ = Matrix6d::Identity();  ///< wrench transform sensor → plate
  Vector6d bias_ = Vector6d::Zero();
  Vector6d tare_sum_ = Vector6d::Zero();
  unsigned tare_count_ = 0;
  unsigned tare_target_ = 0;
  std::atomic<unsigned> tare_request_{0};
  std::atomic<bool> clear_request_{false};
  std::array<double, 6> limits_{};
  bool have_limits_ = false;
};

/// A force plate behind a CanChannel: error frames, bus-off and the channel's losses.
class CanForcePlate : public ForcePlate {
 public:
  /// The last error frame seen.
  const CanErrorInfo& last_bus_error() const noexcept { return last_bus_error_; }
  CanChannel& channel() noexcept { return *channel_; }
  std::string link() const override { return channel_->name(); }
  std::string describe_link_errors(const WrenchSample& s) const override;

 protected:
  /// \throws ConfigError on a bad configuration or without a channel.
  CanForcePlate(const ForcePlateConfig& cfg, std::unique_ptr<CanChannel> channel);
  /// Books an error frame (bus-off state, counters).
  void book_error_frame(const CanFrame& f) noexcept;
  /// Waits until `deadline` for the next data frame: error frames are booked (and counted in
  /// `out`) on the way. \returns ok with `f` filled, timeout at the deadline, closed, bus_error
  /// at once on a bus-off error frame, or bad_frame on a channel error (`context` names what was
  /// awaited). Real-time safe.
  PollStatus next_data_frame(std::chrono::steady_clock::time_point deadline, CanFrame& f, WrenchSample& out, const char* context) noexcept;
  /// Sends a reading's request. \returns ok, or what the poll returns when it could not be sent
  /// (counted; `what` names the request in the problem text). Real-time safe.
  PollStatus send_request(const CanFrame& request, std::chrono::nanoseconds timeout, const char* what) noexcept;
  /// The poll's deadline passed without a whole answer: counted, and named by `missing` unless the
  /// bus's state (bus-off, error frames seen during the poll) explains it. Real-time safe.
  PollStatus answer_missing(const WrenchSample& out, const char* missing) noexcept;

  std::unique_ptr<CanChannel> channel_;
  CanErrorInfo last_bus_error_;
};

/// The ATI NETCANOEM board.
class AtiNetCanOemDriver final : public CanForcePlate {
 public:
  /// \throws ConfigError on a bad configuration.
  AtiNetCanOemDriver(const ForcePlateConfig& cfg, std::unique_ptr<CanChannel> channel);
  ForcePlateInfo start() override;
  PollStatus poll(WrenchSample& out) noexcept override;
  std::string describe_status(const WrenchSample& s) const override;
  /// gauges → wrench in SI units, sensor frame (valid after start()).
  const Matrix6d& gauge_to_wrench() const noexcept { return G_; }

 private:
  bool transaction(std::uint8_t opcode, int arg, unsigned frames, std::array<CanFrame, 3>& out);
  void drain() noexcept;
  Matrix6d G_ = Matrix6d::Zero();
  bool started_ = false;
};

/// The declarative decoder: a sample is complete when every configured frame id has been received
/// since the previous sample.
class DeclarativeForcePlate final : public CanForcePlate {
 public:
  /// \throws ConfigError naming `signals[i].<field>`.
  DeclarativeForcePlate(const ForcePlateConfig& cfg, std::unique_ptr<CanChannel> channel);
  ForcePlateInfo start() override;
  PollStatus poll(WrenchSample& out) noexcept override;
  bool paced() const noexcept override { return false; }  ///< the plate sends on its own
  /// Decodes one frame into the pending sample; true when the sample is complete. Pure, fast.
  bool feed(const CanFrame& f, WrenchSample& out) noexcept;

 private:
  struct FrameSlot {
    std::uint32_t id;
    bool extended;
    unsigned min_len;
    std::vector<unsigned> signals;
  };
  std::vector<FrameSlot> slots_;
  std::uint64_t seen_mask_ = 0;
  std::uint64_t full_mask_ = 0;
  Vector6d pending_ = Vector6d::Zero();
  std::uint16_t pending_status_ = 0;
  std::int64_t first_t_ns_ = 0;
  StampSource first_stamp_ = StampSource::none;
  bool bad_ = false;
};

/// The driver the configuration asks for. \throws ConfigError.
/// A NETCANOEM board that answered a scan.
struct NetCanOemBoard {
  std::uint32_t base_id = 0;
  std::string serial;
};
/// Asks every base id 0..0x7F for its serial number (opcode 0x5) and lists the boards that
/// answered within `answer_window_s` of the last request, by base id. Sends 128 frames on ids
/// (base << 4) | 0x5: run it on a bus whose other nodes do not use those ids. Never throws on
/// silence (an empty list).
std::vector<NetCanOemBoard> scan_netcanoem(CanChannel& channel, double answer_window_s = 0.2);

std::unique_ptr<CanForcePlate> make_force_plate(const ForcePlateConfig& cfg, std::unique_ptr<CanChannel> channel);

}  // namespace hil::drivers
