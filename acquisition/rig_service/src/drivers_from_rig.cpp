#include <hil/rig_service/drivers_from_rig.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <hil/calibration/robot.hpp>
#include <hil/drivers/error.hpp>
#include <hil/error/error.hpp>
#include <hil/models/stiffness.hpp>

namespace hil::rig_service {
namespace {

template <typename F>
auto rethrow_as_format(const std::string& source, const std::string& prefix, F f) -> decltype(f()) {
  try {
    return f();
  } catch (const drivers::ConfigError& e) {
    error::Location where;
    where.file = source;
    where.field = e.field().empty() ? prefix : prefix + "." + e.field();
    const std::string what = e.what();
    const std::string head = e.field() + ": ";
    throw error::FormatError(where, what.rfind(head, 0) == 0 ? what.substr(head.size()) : what);
  }
}

}  // namespace

drivers::ForcePlateConfig force_plate_config(const format::RigSpec& rig) {
  if (!rig.devices.force_plate) {
    error::Location where;
    where.file = rig.source;
    where.field = "devices.force_plate";
    throw error::FormatError(where, "the rig has no force plate device");
  }
  const auto& d = *rig.devices.force_plate;
  return rethrow_as_format(rig.source, "devices.force_plate", [&] {
    drivers::ForcePlateConfig c;
    if (d.protocol == "ati_netcanoem") c.protocol = drivers::ForcePlateProtocol::ati_netcanoem;
    else if (d.protocol == "declarative") c.protocol = drivers::ForcePlateProtocol::declarative;
    else if (d.protocol == "ati_netft_rdt") c.protocol = drivers::ForcePlateProtocol::ati_netft_rdt;
    else if (d.protocol == "robotiq_ft300") c.protocol = drivers::ForcePlateProtocol::robotiq_ft300;
    else if (d.protocol == "ati_netft_can") c.protocol = drivers::ForcePlateProtocol::ati_netft_can;
    else
      throw drivers::ConfigError("protocol",
                                 "'" + d.protocol +
                                     "' is not a protocol (ati_netcanoem, declarative, ati_netft_rdt, ati_netft_can, robotiq_ft300)");
    c.interface = d.interface;
    c.base_id = d.base_id;
    c.host = d.host;
    c.port = d.port;
    if (!d.calibration_xml.empty()) {
      // Relative to the rig file, like every path in it.
      std::filesystem::path p(d.calibration_xml);
      if (p.is_relative()) p = std::filesystem::path(rig.source).parent_path() / p;
      std::ifstream in(p, std::ios::binary);
      if (!in) throw drivers::ConfigError("calibration_xml", "cannot read " + p.string());
      std::ostringstream text;
      text << in.rdbuf();
      c.netft_calibration = drivers::netft::parse_calibration_xml(text.str(), p.string());
    } else {
      c.netft_calibration = {d.counts_per_force, d.counts_per_torque, d.force_unit, d.torque_unit};
    }
    c.serial_device = d.serial_device;
    c.serial_baud = d.baud;
    c.modbus_slave = d.slave;
    c.robotiq_stream = std::find(d.allowed_writes.begin(), d.allowed_writes.end(), "stream_start") != d.allowed_writes.end();
    c.rate_hz = d.rate_hz;
    c.T_fp_sensor = d.T_fp_sensor.isometry();
    c.saturation_limits = d.saturation_limits;
    for (std::size_t i = 0; i < d.signals.size(); ++i) {
      const auto& s = d.signals[i];
      drivers::CanSignal x;
      x.component = drivers::parse_wrench_component(s.component, "signals[" + std::to_string(i) + "].component");
      x.frame_id = s.frame_id;
      x.extended_id = s.extended_id;
      x.start_bit = s.start_bit;
      x.length_bits = s.length_bits;
      x.is_signed = s.is_signed;
      x.big_endian = s.big_endian;
      x.scale = s.scale;
      x.offset = s.offset;
      c.signals.push_back(x);
    }
    c.validate();
    return c;
  });
}

drivers::RegisterMap register_map(const format::RobotControllerSpec& spec, const std::string& rig_source) {
  return rethrow_as_format(rig_source, "devices.robot", [&] {
    if (spec.register_map != "custom") return drivers::builtin_register_map(spec.register_map);
    drivers::RegisterMap m;
    m.name = "custom";
    for (std::size_t i = 0; i < spec.registers.size(); ++i) {
      const auto& r = spec.registers[i];
      const std::string f = "registers[" + std::to_string(i) + "].";
      drivers::RegisterEntry e;
      e.quantity = r.quantity;
      e.address = r.address;
      e.table = drivers::parse_register_table(r.table, f + "table");
      e.type = drivers::parse_register_type(r.type, f + "type");
      e.word_order = drivers::parse_word_order(r.word_order, f + "word_order");
      e.scale = r.scale;
      e.offset = r.offset;
      m.entries.push_back(e);
    }
    m.validate();
    return m;
  });
}

drivers::ModbusConfig robot_controller_config(const format::RigSpec& rig) {
  if (!rig.devices.robot) {
    error::Location where;
    where.file = rig.source;
    where.field = "devices.robot";
    throw error::FormatError(where, "the rig has no robot controller device");
  }
  const auto& r = *rig.devices.robot;
  drivers::ModbusConfig c;
  c.map = register_map(r, rig.source);
  return rethrow_as_format(rig.source, "devices.robot", [&] {
    if (r.transport == "tcp") c.transport = drivers::ModbusTransport::tcp;
    else if (r.transport == "rtu") c.transport = drivers::ModbusTransport::rtu;
    else throw drivers::ConfigError("transport", "'" + r.transport + "' is not a transport (tcp, rtu)");
    c.host = r.host;
    c.port = r.port;
    c.unit_id = r.unit_id;
    c.serial_device = r.serial_device;
    c.baud = r.baud;
    c.parity = r.parity;
    c.data_bits = r.data_bits;
    c.stop_bits = r.stop_bits;
    c.rate_hz = r.rate_hz;
    c.timeout_s = r.timeout_s;
    if (!c.map.has_pose() && rig.robot) c.kinematics = forward_kinematics(*rig.robot);
    c.validate();
    return c;
  });
}

drivers::ForwardKinematics forward_kinematics(const format::RobotSpec& robot) {
  calibration::SerialRobot r = models::to_serial_robot(robot);
  r.T_world_base = Eigen::Isometry3d::Identity();  // the controller reports the tool in its base
  drivers::ForwardKinematics fk;
  fk.joints = r.joints.size();
  fk.T_base_tool = [r = std::move(r)](const double* q) { return calibration::tool_in_base(r, q); };
  return fk;
}

Eigen::Isometry3d world_to_base(const format::RigSpec& rig) {
  return rig.robot ? rig.robot->T_world_base.isometry() : Eigen::Isometry3d::Identity();
}

drivers::Scenario scenario_from_run(const format::Run& run, const Eigen::Isometry3d& T_world_base, bool loop) {
  const auto& t = run.samples;
  std::vector<drivers::ScenarioPoint> pts(t.size());
  const Eigen::Isometry3d T_base_world = T_world_base.inverse();
  for (std::size_t i = 0; i < t.size(); ++i) {
    const auto& s = t.samples[i];
    auto& p = pts[i];
    p.t_s = s.t_s;
    p.w_fp << s.f_fp_n, s.m_fp_nm;
    Eigen::Isometry3d T_world_ee = Eigen::Isometry3d::Identity();
    T_world_ee.linear() = s.q_world_ee.normalized().toRotationMatrix();
    T_world_ee.translation() = s.p_world_ee_m;
    const Eigen::Isometry3d T_base_ee = T_base_world * T_world_ee;
    p.p_base_tcp_m = T_base_ee.translation();
    p.q_base_tcp = Eigen::Quaterniond(T_base_ee.linear());
    p.joints_rad.resize(t.joint_count());
    for (std::size_t j = 0; j < t.joint_count(); ++j)
      p.joints_rad[j] = t.joints_rad(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
  }
  return rethrow_as_format(t.file, "samples", [&] { return drivers::Scenario(std::move(pts), loop); });
}

}  // namespace hil::rig_service
