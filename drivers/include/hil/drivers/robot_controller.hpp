#pragma once
/// \file The robot-controller driver: Modbus TCP or RTU through libmodbus, polling a register map.
/// **Read-only by design**: this driver only issues read requests (function codes 3 and 4, and
/// 0x11 Report Server ID once for the controller's identity); no write function is compiled into it.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <hil/drivers/register_map.hpp>
#include <hil/drivers/status.hpp>

namespace hil::drivers {

enum class ModbusTransport : std::uint8_t { tcp, rtu };

/// T_base_tool from the first `joints` joint values (rad or m) of a poll: the robot's forward
/// kinematics, given by whoever knows the robot (the driver does not). Called on the polling thread.
struct ForwardKinematics {
  std::size_t joints = 0;
  std::function<Eigen::Isometry3d(const double* q)> T_base_tool;
};

struct ModbusConfig {
  ModbusTransport transport = ModbusTransport::tcp;
  std::string host = "127.0.0.1";  ///< tcp
  int port = 502;                  ///< tcp
  int unit_id = 1;                 ///< slave / unit identifier
  std::string serial_device;       ///< rtu, e.g. /dev/ttyUSB0
  int baud = 115200;
  char parity = 'N';  ///< N, E or O
  int data_bits = 8;
  int stop_bits = 1;
  double rate_hz = 125.0;
  double timeout_s = 0.2;  ///< response timeout per request
  RegisterMap map = ur_register_map();
  int retries = 1;                ///< extra tries per poll after a timeout/garbled answer (flush first)
  double reconnect_min_s = 0.05;  ///< back-off after a lost link, doubled per failed attempt...
  double reconnect_max_s = 2.0;   ///< ...up to this
  /// When the map has joints but no tool pose: the pose by the robot's forward kinematics (from the
  /// rig's robot description, hil::rig_service; needs at least as many mapped joints).
  std::optional<ForwardKinematics> kinematics;
  /// \throws ConfigError naming the field.
  void validate() const;
  /// "tcp 127.0.0.1:502 unit 1" / "rtu /dev/ttyUSB0 115200 8N1 unit 1".
  std::string describe() const;
};

/// One reading of the controller.
struct RobotSample {
  std::int64_t t_ns = 0;    ///< midpoint of the first request and the last response, CLOCK_REALTIME ns
  std::int64_t rtt_ns = 0;  ///< first request to last response
  std::uint64_t sequence = 0;
  std::array<double, kMaxJoints> joints{};  ///< rad (or m for prismatic joints)
  unsigned joint_count = 0;
  bool has_pose = false;
  bool pose_from_kinematics = false;  ///< the pose was computed from the joints
  Eigen::Vector3d p_base_tcp_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d r_base_tcp = Eigen::Vector3d::Zero();  ///< rotation vector (rad)
  Eigen::Quaterniond q_base_tcp = Eigen::Quaterniond::Identity();
};

/// What a controller says about itself (Modbus function 0x11, Report Server ID). Many
/// controllers (Universal Robots' server among them) do not implement it: then `answered` is
/// false and `error` holds the Modbus exception.
struct ControllerIdentity {
  bool answered = false;
  int server_id = -1;    ///< the first byte of the answer (device specific)
  bool running = false;  ///< run indicator (0xFF = on)
  std::string text;      ///< the additional bytes, printable ASCII kept, others as \xNN
  std::string error;     ///< why there is no answer
};

/// Polls one controller. Holds one libmodbus context: use one driver per thread.
class RobotControllerDriver {
 public:
  /// \throws ConfigError. Does not connect.
  explicit RobotControllerDriver(ModbusConfig cfg);
  ~RobotControllerDriver();
  RobotControllerDriver(const RobotControllerDriver&) = delete;
  RobotControllerDriver& operator=(const RobotControllerDriver&) = delete;

  /// Connects now. \throws DeviceError naming the controller and the reason.
  void connect();
  /// Reads the map once. Never throws. Timeouts and garbled answers: flush and retry; after the
  /// retries, or when the link breaks: disconnect and reconnect on later polls with back-off.
  PollStatus poll(RobotSample& out) noexcept;
  void disconnect() noexcept;
  /// Asks the connected controller for its identity (one request, no retry). Never throws.
  ControllerIdentity identify() noexcept;

  const DeviceCounters& counters() const noexcept { return counters_; }
  const std::string& last_problem() const noexcept { return last_problem_; }
  const ModbusConfig& config() const noexcept { return cfg_; }
  const std::vector<ReadBlock>& read_plan() const noexcept { return plan_; }

 private:
  struct Impl;
  bool try_connect() noexcept;
  void set_problem(const char* what, int err) noexcept;
  /// One block into its image; on failure counts, sets the problem and \returns why (ok = read).
  PollStatus read_block(const ReadBlock& b, std::uint16_t* dst) noexcept;
  /// Angles whose turn counter is read in another request (UR: 270-275 vs 320-325): after the
  /// plan, their blocks are read again; a wrap in between means the counter may belong to the
  /// other side of 0 rad, so the counters and angles are read again until no angle wrapped.
  PollStatus read_untorn() noexcept;
  ModbusConfig cfg_;
  std::unique_ptr<Impl> impl_;
  std::vector<ReadBlock> plan_;
  std::vector<std::uint16_t> holding_, input_;
  std::vector<std::uint16_t> holding_again_, input_again_;  ///< second reads of angle blocks
  std::vector<std::size_t> angle_blocks_, turn_blocks_;     ///< plan indices (split angle/turn pairs)
  std::vector<const RegisterEntry*> split_turned_;          ///< entries whose turns are in another block
  struct Decoded {
    Quantity q;
    const RegisterEntry* e;
  };
  std::vector<Decoded> decoded_;
  DeviceCounters counters_;
  std::string last_problem_;
  std::uint64_t sequence_ = 0;
  std::chrono::steady_clock::time_point next_attempt_{};
  double backoff_s_ = 0.0;
  bool ever_connected_ = false;
};

}  // namespace hil::drivers
