#pragma once
// The acquisition run behind `hil acquire` and `hil demo`.
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include <hil/acquisition/monitor.hpp>
#include <hil/acquisition/streams.hpp>
#include <hil/drivers/fake_devices.hpp>
#include <hil/dds/bus.hpp>

namespace hil::rig_service {

struct AcquireOptions {
  std::string rig, out;
  double duration_s = 0.0;
  double output_rate_hz = 50.0;
  std::string can_interface, robot_host;
  int robot_port = 0;
  bool no_robot = false;
  bool scan = false;  ///< check: first ask every NETCANOEM base id 0..0x7F for its serial
  bool tare = false;
  bool ros_topics = true;
  bool tf = true;
  bool sensor_best_effort =
      false;  ///< --sensor-qos best-effort  ///< the moving base -> ee transform on rt/tf (and /tf in run.mcap) with every sample
  bool no_bus = false;
  bool progress = true;
  int wait_subscribers = 0;
  int rt_priority = 0;  ///< SCHED_FIFO priority of the device threads (0: normal)
  std::string play;     ///< run folder for the in-process fake rig
  double play_speed = 1.0;
  /// The played run starts again at its end (a soak): the acquisition then ends at duration_s or
  /// on Ctrl-C, not at the run's end.
  bool play_loop = false;
  bool play_over_socketcan = false;  ///< the fake plate talks on the SocketCAN interface instead of loopback
  drivers::CanFaults plate_faults;
  drivers::StreamFaults stream_faults;        ///< --play with an ati_netft_rdt or robotiq_ft300 plate (its stream)
  drivers::ModbusFaults plate_modbus_faults;  ///< --play with a robotiq_ft300 plate: its Modbus side
  drivers::ModbusFaults robot_faults;
  bool mcap = false;                      ///< also record run.mcap (docs/mcap.md)
  std::string mcap_compression = "zstd";  ///< none | zstd | lz4
  /// The bus participant (unless no_bus). The default is domain 0 with hil's host-only profile;
  /// a command passes cli::participant_options() so that --dds-domain, --dds-profile and --secure hold.
  dds::ParticipantOptions participant;
};

struct AcquireResult {
  std::uint64_t samples = 0, gaps = 0;
  std::vector<acquisition::DeviceHealth> health;
  std::string summary;
};

/// Runs one acquisition to its end (duration, played run's end, or Ctrl-C). \throws on bad
/// configuration or a device that cannot be started.
AcquireResult run_acquisition(const AcquireOptions& o, const std::function<void(const acquisition::SyncedSample&)>& observer);

/// `hil acquire --check`: each device's identity and one reading, printed to `out`.
/// \returns 0 when every device answered, 1 otherwise. \throws on a bad rig file.
int run_check(const AcquireOptions& o, std::ostream& out);

}  // namespace hil::rig_service
