#include <hil/acquisition/identity.hpp>

namespace hil::acquisition {

Identity plate_identity(const drivers::ForcePlateInfo& info) {
  Identity id{{"protocol", info.protocol}};
  if (!info.serial.empty()) id.emplace_back("serial", info.serial);
  if (!info.firmware.empty()) id.emplace_back("firmware", info.firmware);
  if (!info.units.empty()) id.emplace_back("units", info.units);
  if (info.counts_per_force > 0) id.emplace_back("counts_per_force", std::to_string(info.counts_per_force));
  if (info.counts_per_torque > 0) id.emplace_back("counts_per_torque", std::to_string(info.counts_per_torque));
  return id;
}

Identity robot_identity(const drivers::ModbusConfig& cfg, const drivers::ControllerIdentity& rid) {
  Identity id{{"link", cfg.describe()}, {"register_map", cfg.map.name}};
  if (rid.answered) {
    id.emplace_back("server_id", std::to_string(rid.server_id));
    id.emplace_back("running", rid.running ? "yes" : "no");
    if (!rid.text.empty()) id.emplace_back("server_text", rid.text);
  } else {
    id.emplace_back("server_id", "not reported (" + rid.error + ")");
  }
  return id;
}

}  // namespace hil::acquisition
