#pragma once
/// \file The fake devices (what `hil fake-rig` runs): a fake ATI NETCANOEM force plate answering the protocol on any CanChannel,
/// and a fake robot controller (a libmodbus TCP server on 127.0.0.0/8) serving a register map.
/// Both play a Scenario (e.g. a recorded run) in real time or faster, with fault injection.
/// Product features: users test their setups with them; the tests use them as real peers.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <hil/drivers/ati_protocol.hpp>
#include <hil/drivers/netft_can.hpp>
#include <hil/drivers/netft_rdt.hpp>
#include <hil/drivers/can_channel.hpp>
#include <hil/drivers/force_plate.hpp>
#include <hil/drivers/register_map.hpp>
#include <hil/drivers/robotiq_ft300.hpp>

namespace hil::drivers {

/// The state of the rig at one instant.
struct ScenarioPoint {
  double t_s = 0.0;
  Vector6d w_fp = Vector6d::Zero();  ///< wrench on the plate, plate frame [N; N·m]
  std::vector<double> joints_rad;
  Eigen::Vector3d p_base_tcp_m = Eigen::Vector3d::Zero();  ///< tool pose in the robot base frame
  Eigen::Quaterniond q_base_tcp = Eigen::Quaterniond::Identity();
};

/// A timeline of states, interpolated (linear; slerp for orientation).
class Scenario {
 public:
  /// \throws ConfigError if empty, times not strictly increasing, or joint counts differ.
  explicit Scenario(std::vector<ScenarioPoint> points, bool loop = false);
  /// State at scenario time t (clamped to the ends, or wrapped when looping). Allocation-free when
  /// `out.joints_rad` already has the right size.
  void at(double t_s, ScenarioPoint& out) const;
  double duration_s() const noexcept { return points_.back().t_s - points_.front().t_s; }
  std::size_t size() const noexcept { return points_.size(); }
  bool loop() const noexcept { return loop_; }

 private:
  std::vector<ScenarioPoint> points_;
  bool loop_;
};

/// A device clock: scenario time = ((wall - start) · (1 + drift_ppm·1e-6) + offset_s) · speed.
struct DeviceClock {
  double offset_s = 0.0;
  double drift_ppm = 0.0;
  double speed = 1.0;  ///< playback speed factor
  double scenario_time(double wall_s) const noexcept { return (wall_s * (1.0 + drift_ppm * 1e-6) + offset_s) * speed; }
};

/// The wrench a fake force plate plays: the scenario's at the device clock's time, else the value
/// of set(). Thread-safe (the fake's thread reads, the test or CLI thread sets).
class WrenchSource {
 public:
  WrenchSource(std::shared_ptr<const Scenario> scenario, DeviceClock clock) : scenario_(std::move(scenario)), clock_(clock) {}
  void set(const Vector6d& w_fp);
  /// The wrench on the plate (plate frame) at `t_s` seconds of wall time since the fake started.
  Vector6d at(double t_s) const;

 private:
  std::shared_ptr<const Scenario> scenario_;
  DeviceClock clock_;
  mutable std::mutex m_;  // guards wrench_ and point_
  Vector6d wrench_ = Vector6d::Zero();
  mutable ScenarioPoint point_;
};

/// A time window relative to the fake's start.
struct TimeWindow {
  double start_s = 0.0;
  double duration_s = 0.0;
  bool contains(double t) const noexcept { return t >= start_s && t < start_s + duration_s; }
};

/// Status bits a fake device sets in its answers during a window.
struct StatusWindow {
  TimeWindow window;
  std::uint32_t bits = 0;
};

struct CanFaults {
  double drop_fraction = 0.0;        ///< share of response frames not sent
  double corrupt_fraction = 0.0;     ///< share of responses sent with a wrong length (truncated)
  std::vector<TimeWindow> silent;    ///< no answers at all
  std::vector<TimeWindow> bus_off;   ///< a bus-off error frame, silence, then "controller restarted"
  double error_frame_rate_hz = 0.0;  ///< error-passive error frames per second (status bit 0x4000 set meanwhile)
  double extra_delay_s = 0.0;        ///< every answer this much later
  bool silent_now = false;           ///< switch: silent until cleared
  /// Status-word bits in the gauge answers (ATI: bit 15, any error, joins any other bit, as the
  /// board does); `status_now` is a switch.
  std::vector<StatusWindow> status;
  std::uint32_t status_now = 0;
};

struct ModbusFaults {
  double exception_fraction = 0.0;            ///< share of requests answered with exception 6 (server busy)
  std::vector<TimeWindow> exception_windows;  ///< every request answered with an exception
  double slow_fraction = 0.0;                 ///< share of requests answered after slow_delay_s
  double slow_delay_s = 0.0;
  std::vector<TimeWindow> silent;  ///< requests not answered
  double extra_delay_s = 0.0;      ///< every answer this much later
  bool silent_now = false;
};

// ---- fake ATI NETCANOEM plate --------------------------------------------------------------------

/// A plausible, well-conditioned calibration matrix (gauges → counts) for fakes and tests.
Matrix6d default_ati_calibration();

struct FakeNetCanOemConfig {
  /// Answer as a Net F/T box in CAN mode instead (short data on base+5 and base+6, little-endian
  /// F/T counts at `box_calibration`; base_id is then its 11-bit base address). The faults are
  /// the same.
  bool netft_box = false;
  netft::Calibration box_calibration{100.0, 1000.0, "N", "Nm"};
  std::uint32_t base_id = ati::kFactoryBase;
  Matrix6d calibration = default_ati_calibration();
  std::int32_t counts_per_force = 1000;
  std::int32_t counts_per_torque = 100000;
  std::uint8_t force_units = 2;   ///< N
  std::uint8_t torque_units = 3;  ///< N·m
  std::string serial = "FT-FAKE1";
  ati::Firmware firmware{1, 0, 42};
  Eigen::Isometry3d T_fp_sensor = Eigen::Isometry3d::Identity();  ///< how the sensor is mounted
  CanFaults faults;
  DeviceClock clock;
  std::uint64_t seed = 1;
};

/// Wrench on the plate (about its origin, plate frame) → wrench on the sensor (sensor frame), for
/// a sensor mounted at T_fp_sensor. Pure.
Matrix6d plate_to_sensor_wrench(const Eigen::Isometry3d& T_fp_sensor);

/// The gauges that a wrench on the plate produces: w_fp → sensor frame → device units → counts →
/// M⁻¹ → rounded int16. `saturated` is set when a gauge had to be clamped. Pure.
class AtiGaugeModel {
 public:
  explicit AtiGaugeModel(const FakeNetCanOemConfig& cfg);
  ati::Gauges gauges(const Vector6d& w_fp, bool& saturated) const noexcept;

 private:
  Matrix6d A_;  ///< w_fp → gauges (real valued)
};

class FakeNetCanOemBoard {
 public:
  /// \param scenario wrench source; null = the value of set_wrench().
  FakeNetCanOemBoard(FakeNetCanOemConfig cfg, std::unique_ptr<CanChannel> channel, std::shared_ptr<const Scenario> scenario = nullptr);
  ~FakeNetCanOemBoard();
  FakeNetCanOemBoard(const FakeNetCanOemBoard&) = delete;
  FakeNetCanOemBoard& operator=(const FakeNetCanOemBoard&) = delete;

  /// Starts answering (a thread). The fault windows and the clock count from here.
  void start();
  void stop() noexcept;
  void set_wrench(const Vector6d& w_fp);
  void set_faults(const CanFaults& f);

  struct Stats {
    std::uint64_t requests = 0, gauge_answers = 0, frames_sent = 0, frames_dropped = 0, answers_corrupted = 0, error_frames_sent = 0,
                  ignored_silent = 0;
    /// Gauge answers whose frames all went out intact (none dropped, corrupted or refused by the
    /// channel): the readings a driver could have received.
    std::uint64_t gauge_answers_delivered = 0;
  };
  Stats stats() const;

 private:
  void run() noexcept;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::jthread thread_;
};

// ---- fake robot controller ---------------------------------------------------------------------

/// Faults of a streaming device (the Net F/T's RDT): records lost on the way, datagrams cut short,
/// silences, late datagrams, status bits.
struct StreamFaults {
  double drop_fraction = 0.0;        ///< share of records not sent (their rdt_sequence is used up)
  double corrupt_fraction = 0.0;     ///< share of datagrams sent cut short (not whole records)
  double duplicate_fraction = 0.0;   ///< share of datagrams sent twice (a network duplicate)
  std::vector<TimeWindow> silent;    ///< nothing sent, the stream's counters running on
  std::vector<TimeWindow> deaf;      ///< requests ignored (a stream asked for then does not start)
  double extra_delay_s = 0.0;        ///< every datagram this much later than its record's time
  std::vector<StatusWindow> status;  ///< status bits in the records (bit 31, any error, joins bits 17-30 and 0-15)
  std::uint32_t status_now = 0;
  bool silent_now = false;
};

struct FakeNetFtConfig {
  std::string host = "127.0.0.1";     ///< must be in 127.0.0.0/8
  int port = 0;                       ///< 0 = an ephemeral port (see port())
  double rate_hz = 1000.0;            ///< the box's RDT output rate
  unsigned records_per_datagram = 1;  ///< in buffered mode (command 0x0003)
  netft::Calibration calibration{1'000'000.0, 1'000'000.0, "N", "Nm"};
  Eigen::Isometry3d T_fp_sensor = Eigen::Isometry3d::Identity();
  StreamFaults faults;
  DeviceClock clock;
  std::uint64_t seed = 1;
};

/// A Net F/T box streaming RDT over UDP on 127.0.0.0/8: answers start (real-time, buffered), stop,
/// bias and latch-reset requests from one client at a time, and streams the scenario's wrench as
/// counts at rate_hz (absolute deadlines, no drift).
class FakeNetFtRdt {
 public:
  explicit FakeNetFtRdt(FakeNetFtConfig cfg, std::shared_ptr<const Scenario> scenario = nullptr);
  ~FakeNetFtRdt();
  FakeNetFtRdt(const FakeNetFtRdt&) = delete;
  FakeNetFtRdt& operator=(const FakeNetFtRdt&) = delete;

  int port() const noexcept;
  void start();
  void stop() noexcept;
  void set_wrench(const Vector6d& w_fp);
  void set_faults(const StreamFaults& f);

  struct Stats {
    std::uint64_t requests = 0, bad_requests = 0, starts = 0, stops = 0, biases = 0, latch_resets = 0, ignored_deaf = 0;
    std::uint64_t records = 0;       ///< records made (rdt_sequence used)
    std::uint64_t records_sent = 0;  ///< records that went out in whole datagrams
    std::uint64_t records_dropped = 0, datagrams_corrupted = 0, datagrams_duplicated = 0, records_silenced = 0;
    std::uint64_t records_flagged = 0;  ///< records sent with a non-zero status
  };
  Stats stats() const;

 private:
  void run() noexcept;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::jthread thread_;
};

struct FakeRobotConfig {
  std::string host = "127.0.0.1";  ///< must be in 127.0.0.0/8
  int port = 0;                    ///< 0 = an ephemeral port (see port())
  RegisterMap map = ur_register_map();
  ModbusFaults faults;
  DeviceClock clock;
  /// > 0: lock-step playback, the scenario advances this much per request (the first request sees
  /// t = 0) whatever the wall clock does: a replay that is the same on a loaded machine, and a
  /// motion placed exactly between two requests of one poll. 0: the scenario plays in wall time.
  double scenario_step_per_request_s = 0.0;
  std::uint64_t seed = 1;
};

/// A libmodbus TCP server. Reads of holding (and input, same contents) registers answer the
/// current state; writes are refused with "illegal function" and counted.
class FakeRobotController {
 public:
  /// Binds and listens. \throws DeviceError (port in use, ...) or ConfigError (not loopback, bad map).
  explicit FakeRobotController(FakeRobotConfig cfg, std::shared_ptr<const Scenario> scenario = nullptr);
  ~FakeRobotController();
  FakeRobotController(const FakeRobotController&) = delete;
  FakeRobotController& operator=(const FakeRobotController&) = delete;

  int port() const noexcept;
  void start();
  void stop() noexcept;
  /// State served when there is no scenario.
  void set_state(std::span<const double> joints_rad, const Eigen::Vector3d& p_base_tcp_m, const Eigen::Quaterniond& q_base_tcp);
  void set_faults(const ModbusFaults& f);

  struct Stats {
    std::uint64_t connections = 0, requests = 0, replies = 0, exceptions = 0, slow = 0, ignored_silent = 0, writes_refused = 0;
  };
  Stats stats() const;

 private:
  void run() noexcept;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::jthread thread_;
};

// ---- fake Robotiq FT 300 -------------------------------------------------------------------------

struct FakeFt300Config {
  int slave = robotiq::kSlave;
  double stream_rate_hz = robotiq::kStreamRateHz;
  std::string serial_prefix = "FAK";
  std::uint32_t serial_number = 300;
  std::uint16_t production_year = 2026;
  std::string firmware_prefix = "FTS";
  std::array<std::uint8_t, 3> firmware{3, 1, 4};
  Eigen::Isometry3d T_fp_sensor = Eigen::Isometry3d::Identity();
  bool streaming_at_start = false;  ///< a sensor a previous client left streaming
  /// The stream: drop (frames not sent), corrupt (a byte flipped: the CRC fails), silent, deaf (the
  /// stream-start write ignored), extra_delay_s (every frame late). A serial line neither
  /// duplicates nor carries a status word: duplicate_fraction and status are refused.
  StreamFaults stream;
  double noise_fraction = 0.0;  ///< share of frames preceded by stray bytes on the line
  ModbusFaults modbus;          ///< the Modbus side: exceptions, silence, slow answers
  DeviceClock clock;
  std::uint64_t seed = 1;
};

/// A Robotiq FT 300 on a pseudo-terminal pair: the driver opens device_path() as it would
/// /dev/ttyUSB0. Modbus RTU as slave 9 (FC03 on its documented registers, FC16 to register 410
/// starts the stream; anything else an exception), the 100 Hz stream on absolute deadlines, stopped
/// by 50 bytes 0xFF. Bytes are checked as the sensor would: a request failing its CRC is ignored.
class FakeRobotiqFt300 {
 public:
  /// Opens the pseudo-terminal. 	hrows DeviceError or ConfigError (refused faults).
  explicit FakeRobotiqFt300(FakeFt300Config cfg, std::shared_ptr<const Scenario> scenario = nullptr);
  ~FakeRobotiqFt300();
  FakeRobotiqFt300(const FakeRobotiqFt300&) = delete;
  FakeRobotiqFt300& operator=(const FakeRobotiqFt300&) = delete;

  /// The port's path (/dev/pts/N).
  const std::string& device_path() const noexcept;
  void start();
  void stop() noexcept;
  void set_wrench(const Vector6d& w_fp);
  void set_faults(const StreamFaults& stream, const ModbusFaults& modbus);
  bool streaming() const noexcept;

  struct Stats {
    std::uint64_t requests = 0, bad_requests = 0, other_slave = 0, replies = 0, exceptions = 0, ignored_silent = 0, ignored_deaf = 0;
    std::uint64_t stream_starts = 0, stream_stops = 0;
    std::uint64_t frames = 0;       ///< frames made
    std::uint64_t frames_sent = 0;  ///< frames that went out whole and intact: what a reader can receive
    std::uint64_t frames_dropped = 0, frames_corrupted = 0, frames_silenced = 0, noise_bytes = 0;
    std::uint64_t overruns = 0;  ///< frames the line's buffer had no room for (nobody reading)
  };
  Stats stats() const;

 private:
  void run() noexcept;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::jthread thread_;
};

/// Writes a state into a register image (size ≥ highest address + 2) through a map. Pure.
void encode_state(const RegisterMap& map, std::span<const double> joints_rad, const Eigen::Vector3d& p_m, const Eigen::Quaterniond& q,
                  std::span<std::uint16_t> holding);

}  // namespace hil::drivers
