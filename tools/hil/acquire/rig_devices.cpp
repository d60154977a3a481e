#include "rig_devices.hpp"

#include "hil/drivers/error.hpp"

namespace hil::cli {

drivers::ForcePlateConfig plate_config(const format::ForcePlateDeviceSpec& s) {
  drivers::ForcePlateConfig c;
  c.protocol = s.protocol == "declarative" ? drivers::ForcePlateProtocol::declarative : drivers::ForcePlateProtocol::ati_ft_can;
  c.interface = s.interface;
  c.base_id = s.base_id;
  c.rate_hz = s.rate_hz;
  c.T_fp_sensor = s.T_fp_sensor.isometry();
  c.saturation_limits = s.saturation_limits;
  for (std::size_t i = 0; i < s.signals.size(); ++i) {
    const auto& g = s.signals[i];
    drivers::CanSignal d;
    d.component = drivers::parse_wrench_component(g.component, "devices.force_plate.signals[" + std::to_string(i) + "].component");
    d.frame_id = g.frame_id;
    d.extended_id = g.extended_id;
    d.start_bit = g.start_bit;
    d.length_bits = g.length_bits;
    d.is_signed = g.is_signed;
    d.big_endian = g.big_endian;
    d.scale = g.scale;
    d.offset = g.offset;
    c.signals.push_back(d);
  }
  c.validate();
  return c;
}

drivers::RegisterMap register_map(const format::RobotControllerSpec& s) {
  if (s.register_map != "custom") return drivers::builtin_register_map(s.register_map);
  drivers::RegisterMap m;
  m.name = "custom";
  for (const auto& e : s.registers) {
    drivers::RegisterEntry r;
    r.quantity = e.quantity;
    r.address = e.address;
    r.table = e.table == "input" ? drivers::RegisterTable::input : drivers::RegisterTable::holding;
    static const std::pair<const char*, drivers::RegisterType> types[] = {{"int16", drivers::RegisterType::int16},
                                                                         {"uint16", drivers::RegisterType::uint16},
                                                                         {"int32", drivers::RegisterType::int32},
                                                                         {"uint32", drivers::RegisterType::uint32},
                                                                         {"float32", drivers::RegisterType::float32}};
    for (const auto& [name, t] : types)
      if (e.type == name) r.type = t;
    r.word_order = e.word_order == "little" ? drivers::WordOrder::little : drivers::WordOrder::big;
    r.scale = e.scale;
    r.offset = e.offset;
    m.entries.push_back(r);
  }
  m.validate();
  return m;
}

drivers::ModbusConfig modbus_config(const format::RobotControllerSpec& s) {
  drivers::ModbusConfig c;
  c.transport = s.transport == "rtu" ? drivers::ModbusTransport::rtu : drivers::ModbusTransport::tcp;
  c.host = s.host;
  c.port = s.port;
  c.unit_id = s.unit_id;
  c.serial_device = s.serial_device;
  c.baud = s.baud;
  c.parity = s.parity;
  c.data_bits = s.data_bits;
  c.stop_bits = s.stop_bits;
  c.rate_hz = s.rate_hz;
  c.timeout_s = s.timeout_s;
  c.map = register_map(s);
  c.validate();
  return c;
}

calibration::SerialRobot robot_model(const format::RobotSpec& s) {
  calibration::SerialRobot r;
  r.name = s.name;
  r.convention = s.convention == format::DhConvention::modified ? calibration::DhConvention::modified
                                                                : calibration::DhConvention::standard;
  for (const auto& j : s.joints) {
    calibration::DhRow row;
    row.name = j.name;
    row.kind = j.type == format::JointType::prismatic ? calibration::JointKind::prismatic : calibration::JointKind::revolute;
    row.a_m = j.a_m;
    row.alpha_rad = j.alpha_rad;
    row.d_m = j.d_m;
    row.theta_offset_rad = j.theta_offset_rad;
    row.lower = j.lower;
    row.upper = j.upper;
    r.joints.push_back(row);
  }
  r.T_world_base = s.T_world_base.isometry();
  r.T_flange_ee = s.T_flange_ee.isometry();
  return r;
}

std::shared_ptr<const drivers::Scenario> scenario_from_run(const format::Run& run, const Eigen::Isometry3d& T_world_base) {
  std::vector<drivers::ScenarioPoint> pts;
  pts.reserve(run.samples.size());
  const Eigen::Isometry3d T_base_world = T_world_base.inverse();
  for (std::size_t i = 0; i < run.samples.size(); ++i) {
    const auto& s = run.samples.samples[i];
    drivers::ScenarioPoint p;
    p.t_s = s.t_s;
    p.w_fp << s.f_fp_n, s.m_fp_nm;
    Eigen::Isometry3d T_world_ee = Eigen::Isometry3d::Identity();
    T_world_ee.linear() = s.q_world_ee.toRotationMatrix();
    T_world_ee.translation() = s.p_world_ee_m;
    const Eigen::Isometry3d T_base_ee = T_base_world * T_world_ee;
    p.p_base_tcp_m = T_base_ee.translation();
    p.q_base_tcp = Eigen::Quaterniond(T_base_ee.linear()).normalized();
    for (Eigen::Index j = 0; j < run.samples.joints_rad.cols(); ++j)
      p.joints_rad.push_back(run.samples.joints_rad(static_cast<Eigen::Index>(i), j));
    pts.push_back(std::move(p));
  }
  return std::make_shared<const drivers::Scenario>(std::move(pts));
}

}  // namespace hil::cli
