#include <hil/format/rig.hpp>

#include <Eigen/SVD>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <hil/format/quaternion.hpp>
#include <hil/format/urdf.hpp>
#include <hil/format/yaml.hpp>

namespace hil::format {
using YNode = YamlNode;

const char* convention_name(DhConvention c) {
  switch (c) {
    case DhConvention::standard: return "standard";
    case DhConvention::modified: return "modified";
    case DhConvention::urdf: return "urdf";
  }
  return "standard";
}

Eigen::Isometry3d Pose::isometry() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rotation.toRotationMatrix();
  T.translation() = translation_m;
  return T;
}

Pose Pose::from_isometry(const Eigen::Isometry3d& T) {
  Pose p;
  p.translation_m = T.translation();
  p.rotation = Eigen::Quaterniond(T.linear()).normalized();
  return p;
}

std::size_t ObjectSpec::polyhedron_count() const {
  std::size_t n = 0;
  for (const auto& f : features) n += f.polyhedra.size();
  return n;
}

const std::string& TfNames::ros(const std::string& rig_frame) const {
  if (rig_frame == "world") return world;
  if (rig_frame == "ee") return ee;
  return rig_frame;
}

const FrameSpec* RigSpec::frame(const std::string& n) const {
  for (const auto& f : frames)
    if (f.name == n) return &f;
  return nullptr;
}

const ObjectSpec* RigSpec::object(const std::string& n) const {
  for (const auto& o : objects)
    if (o.name == n) return &o;
  return nullptr;
}

namespace {

// Walks the frame tree from `frame` up to `root`.
Eigen::Isometry3d chain(const RigSpec& rig, const std::string& frame, const std::string& root) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  std::string cur = frame;
  for (std::size_t hops = 0; cur != root; ++hops) {
    const FrameSpec* f = rig.frame(cur);
    if (!f) throw error::FormatError({rig.source, 0, 0, "frames"}, "frame '" + cur + "' does not lead to '" + root + "'");
    if (hops > rig.frames.size()) throw error::FormatError({rig.source, 0, 0, "frames"}, "frame tree has a cycle at '" + cur + "'");
    T = f->T_parent_frame.isometry() * T;
    cur = f->parent;
  }
  return T;
}

// Reads the pose keys of `n`; the caller has already checked which keys `n` may hold.
Pose read_pose_fields(const YNode& n) {
  Pose p;
  if (n.has("translation_m")) p.translation_m = n.child("translation_m").vec3();
  if (n.has("quaternion_wxyz") && n.has("rpy_rad")) n.fail("give the rotation either as quaternion_wxyz or as rpy_rad, not both");
  if (n.has("quaternion_wxyz")) {
    const YNode qn = n.child("quaternion_wxyz");
    const auto q = qn.nums();
    if (q.size() != 4) qn.fail("expected 4 numbers w x y z");
    const auto r = checked_unit_quaternion(q[0], q[1], q[2], q[3]);
    if (!r)
      qn.fail("not a unit quaternion (norm " + std::to_string(std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])) + ")");
    p.rotation = *r;
  }
  if (n.has("rpy_rad")) {
    const auto rpy = n.child("rpy_rad").vec3();
    // Fixed-axis roll (x), pitch (y), yaw (z): R = Rz(yaw) Ry(pitch) Rx(roll).
    p.rotation = Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
                 Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX());
  }
  return p;
}

Pose read_pose(const YNode& n) {
  n.only({"translation_m", "quaternion_wxyz", "rpy_rad"});
  return read_pose_fields(n);
}

std::string read_name(const YNode& n, const std::string& key) {
  const auto s = n.req(key).str();
  if (s.empty()) n.child(key).fail("must not be empty");
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'))
      n.child(key).fail("names use letters, digits, '_' and '-' only, found '" + s + "'");
  return s;
}

void check_polyhedron(const YNode& n, const PolyhedronSpec& p) {
  if (p.vertices_m.size() < 4)
    n.fail("degenerate polyhedron: " + std::to_string(p.vertices_m.size()) +
           " vertices, a convex polyhedron needs at least 4 non-coplanar vertices");
  Eigen::MatrixXd D(3, p.vertices_m.size() - 1);
  double scale = 0.0;
  for (std::size_t i = 1; i < p.vertices_m.size(); ++i) {
    D.col(static_cast<Eigen::Index>(i - 1)) = p.vertices_m[i] - p.vertices_m[0];
    scale = std::max(scale, D.col(static_cast<Eigen::Index>(i - 1)).norm());
  }
  if (scale <= 0.0) n.fail("degenerate polyhedron: all vertices coincide");
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(D);
  const double s3 = svd.singularValues()(2);
  if (s3 <= 1e-9 * scale)
    n.fail("degenerate polyhedron: its " + std::to_string(p.vertices_m.size()) +
           " vertices are coplanar (or collinear); at least 4 non-coplanar vertices are needed");
}

/// A tf frame id: letters, digits, '_', '-' and '/' (namespaced ids such as `arm1/base_link`), not
/// starting with '/' (tf2 refuses a leading slash).
std::string read_tf_name(const YNode& n, const std::string& key) {
  const auto s = n.req(key).str();
  if (s.empty()) n.child(key).fail("must not be empty");
  if (s.front() == '/') n.child(key).fail("tf frame ids do not start with '/', found '" + s + "'");
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '/'))
      n.child(key).fail("tf frame ids use letters, digits, '_', '-' and '/' only, found '" + s + "'");
  return s;
}

/// `tf: {world: W, base: B, ee: E}`, read after the robot (a URDF robot's base link is the default
/// base name). The names must differ from each other: two frames joined into one would break the tree.
TfNames read_tf(const YNode& n, const RigSpec& rig) {
  n.only({"world", "base", "ee"});
  TfNames t;
  if (rig.robot && rig.robot->convention == DhConvention::urdf && !rig.robot->base_link.empty()) t.base = rig.robot->base_link;
  if (n.has("world")) t.world = read_tf_name(n, "world");
  if (n.has("base")) t.base = read_tf_name(n, "base");
  if (n.has("ee")) t.ee = read_tf_name(n, "ee");
  std::map<std::string, std::string> used;  // tf name -> the key that took it
  for (const auto& [key, name] : {std::pair{"world", t.world}, {"base", t.base}, {"ee", t.ee}})
    if (!used.emplace(name, key).second)
      (n.has(key) ? n.child(key) : n).fail("'" + name + "' is already the tf name of '" + used[name] + "'");
  return t;
}

FrameSpec read_frame(const YNode& n) {
  n.only({"name", "parent", "translation_m", "quaternion_wxyz", "rpy_rad"});
  FrameSpec f;
  f.name = read_name(n, "name");
  f.parent = read_name(n, "parent");
  f.T_parent_frame = read_pose_fields(n);
  return f;
}

/// `robot: {urdf: FILE, base_link: L, tip_link: L}`: the chain from the URDF, the file relative to
/// the rig file's folder; `base` places the base link in world, `tool` goes after the tip link.
RobotSpec read_urdf_section(const YNode& n, const std::string& rig_path) {
  n.only({"name", "urdf", "base_link", "tip_link", "base", "tool"});
  std::filesystem::path file = n.req("urdf").str();
  if (file.is_relative()) file = std::filesystem::path(rig_path).parent_path() / file;
  RobotSpec r;
  try {
    r = read_urdf_robot(file.lexically_normal().string(), read_name(n, "base_link"), read_name(n, "tip_link"));
  } catch (const error::FormatError& e) {
    // Both places: the rig's line and what is wrong in the URDF.
    n.child("urdf").fail(e.what());
  }
  if (n.has("name")) r.name = read_name(n, "name");
  if (n.has("base")) r.T_world_base = read_pose(n.child("base"));
  if (n.has("tool")) r.T_flange_ee = Pose::from_isometry(r.T_flange_ee.isometry() * read_pose(n.child("tool")).isometry());
  return r;
}

RobotSpec read_robot(const YNode& n, const std::string& rig_path) {
  if (n.has("urdf")) return read_urdf_section(n, rig_path);
  n.only({"name", "convention", "joints", "base", "tool"});
  RobotSpec r;
  r.name = n.str("name", "robot");
  const auto conv = n.str("convention", "standard");
  if (conv == "standard") r.convention = DhConvention::standard;
  else if (conv == "modified") r.convention = DhConvention::modified;
  else n.child("convention").fail("expected 'standard' or 'modified', found '" + conv + "'");
  const auto joints = n.req("joints").seq();
  if (joints.empty()) n.child("joints").fail("a robot needs at least one joint");
  for (const auto& j : joints) {
    j.only({"name", "type", "a_m", "alpha_rad", "d_m", "theta_offset_rad", "lower", "upper"});
    DhJointSpec s;
    s.name = j.has("name") ? read_name(j, "name") : "j" + std::to_string(r.joints.size() + 1);
    const auto type = j.str("type", "revolute");
    if (type == "revolute") s.type = JointType::revolute;
    else if (type == "prismatic") s.type = JointType::prismatic;
    else j.child("type").fail("expected 'revolute' or 'prismatic', found '" + type + "'");
    s.a_m = j.req("a_m").num();
    s.alpha_rad = j.req("alpha_rad").num();
    s.d_m = j.req("d_m").num();
    s.theta_offset_rad = j.num("theta_offset_rad", 0.0);
    s.lower = j.num("lower", s.lower);
    s.upper = j.num("upper", s.upper);
    if (!(s.lower < s.upper)) j.fail("joint limits: lower must be below upper");
    r.joints.push_back(s);
  }
  if (n.has("base")) r.T_world_base = read_pose(n.child("base"));
  if (n.has("tool")) r.T_flange_ee = read_pose(n.child("tool"));
  return r;
}

ObjectSpec read_object(const YNode& n) {
  n.only({"name", "frame", "features"});
  ObjectSpec o;
  o.name = read_name(n, "name");
  o.frame = read_name(n, "frame");
  const auto features = n.req("features").seq();
  if (features.empty()) n.child("features").fail("an object needs at least one feature");
  std::set<std::string> names;
  for (const auto& fn : features) {
    fn.only({"name", "polyhedra"});
    FeatureSpec f;
    f.name = read_name(fn, "name");
    if (!names.insert(f.name).second) fn.child("name").fail("feature name '" + f.name + "' used twice in this object");
    const auto polys = fn.req("polyhedra").seq();
    if (polys.empty()) fn.child("polyhedra").fail("a feature needs at least one polyhedron");
    for (const auto& pn : polys) {
      pn.only({"vertices_m"});
      PolyhedronSpec p;
      const YNode vn = pn.req("vertices_m");
      for (const auto& v : vn.seq()) p.vertices_m.push_back(v.vec3());
      p.line = vn.where().line;
      check_polyhedron(vn, p);
      f.polyhedra.push_back(std::move(p));
    }
    o.features.push_back(std::move(f));
  }
  return o;
}

ContactModelSpec read_contact(const YNode& n) {
  n.only({"stiffness_n_per_m", "friction_coefficient", "sticking_threshold_m_per_s", "force_scale_n", "moment_scale_nm"});
  ContactModelSpec c;
  c.stiffness_n_per_m = n.req("stiffness_n_per_m").num();
  if (!(c.stiffness_n_per_m > 0.0)) n.child("stiffness_n_per_m").fail("contact stiffness K must be > 0");
  c.friction_coefficient = n.req("friction_coefficient").num();
  if (c.friction_coefficient < 0.0) n.child("friction_coefficient").fail("friction coefficient must be >= 0");
  c.sticking_threshold_m_per_s = n.num("sticking_threshold_m_per_s", c.sticking_threshold_m_per_s);
  if (c.sticking_threshold_m_per_s < 0.0) n.child("sticking_threshold_m_per_s").fail("must be >= 0");
  c.force_scale_n = n.num("force_scale_n", 0.0);
  c.moment_scale_nm = n.num("moment_scale_nm", 0.0);
  if (c.force_scale_n < 0.0 || c.moment_scale_nm < 0.0) n.fail("force_scale_n and moment_scale_nm must be >= 0");
  return c;
}

UncertaintySpec read_uncertainty(const YNode& n, const RigSpec& rig) {
  n.only({"name", "object", "feature", "kind", "axis", "point_m", "design_value", "prior_std"});
  UncertaintySpec u;
  u.name = read_name(n, "name");
  u.object = read_name(n, "object");
  u.feature = read_name(n, "feature");
  const ObjectSpec* obj = rig.object(u.object);
  if (!obj) n.child("object").fail("no object named '" + u.object + "' in objects");
  bool found = false;
  for (const auto& f : obj->features) found = found || f.name == u.feature;
  if (!found) n.child("feature").fail("object '" + u.object + "' has no feature '" + u.feature + "'");
  const auto kind = n.req("kind").str();
  if (kind == "translation") u.kind = UncertaintySpec::Kind::translation;
  else if (kind == "rotation") u.kind = UncertaintySpec::Kind::rotation;
  else n.child("kind").fail("expected 'translation' or 'rotation', found '" + kind + "'");
  u.axis = n.req("axis").vec3();
  if (u.axis.norm() < 1e-12) n.child("axis").fail("axis must not be zero");
  u.axis.normalize();
  if (n.has("point_m")) u.point_m = n.child("point_m").vec3();
  else if (u.kind == UncertaintySpec::Kind::rotation) n.fail("a rotation uncertainty needs point_m (a point on its axis)", "point_m");
  u.design_value = n.num("design_value", 0.0);
  u.prior_std = n.num("prior_std", 0.0);
  if (u.prior_std < 0.0) n.child("prior_std").fail("must be >= 0");
  return u;
}

CanSignalSpec read_signal(const YNode& n) {
  n.only({"component", "frame_id", "extended_id", "start_bit", "length_bits", "signed", "byte_order", "scale", "offset"});
  CanSignalSpec s;
  s.component = n.req("component").str();
  static const std::set<std::string> comps{"fx", "fy", "fz", "mx", "my", "mz", "status"};
  if (!comps.count(s.component)) n.child("component").fail("expected one of fx fy fz mx my mz status, found '" + s.component + "'");
  s.extended_id = n.has("extended_id") && n.child("extended_id").boolean();
  const long id = n.req("frame_id").integer();
  if (id < 0 || id > (s.extended_id ? 0x1FFFFFFFL : 0x7FFL)) n.child("frame_id").fail("CAN id out of range");
  s.frame_id = static_cast<std::uint32_t>(id);
  const long sb = n.req("start_bit").integer();
  const long len = n.req("length_bits").integer();
  if (sb < 0 || sb > 511) n.child("start_bit").fail("expected 0..511");
  if (len < 1 || len > 64) n.child("length_bits").fail("expected 1..64");
  s.start_bit = static_cast<unsigned>(sb);
  s.length_bits = static_cast<unsigned>(len);
  s.is_signed = !n.has("signed") || n.child("signed").boolean();
  const auto bo = n.str("byte_order", "little");
  if (bo == "little") s.big_endian = false;
  else if (bo == "big") s.big_endian = true;
  else n.child("byte_order").fail("expected 'little' or 'big', found '" + bo + "'");
  s.scale = n.num("scale", 1.0);
  s.offset = n.num("offset", 0.0);
  return s;
}

ForcePlateDeviceSpec read_force_plate(const YNode& n) {
  n.only({"protocol", "interface", "base_id", "host", "port", "calibration_xml", "counts_per_force", "counts_per_torque", "force_unit",
          "torque_unit", "serial_device", "baud", "slave", "allowed_writes", "rate_hz", "sensor_pose", "signals", "saturation_limits",
          "gain_tolerance"});
  ForcePlateDeviceSpec d;
  d.protocol = n.str("protocol", d.protocol);
  // Rig files written before the board was named for what it is (the protocol is NETCANOEM's).
  if (d.protocol == "ati_ft_can") d.protocol = "ati_netcanoem";
  if (d.protocol != "ati_netcanoem" && d.protocol != "declarative" && d.protocol != "ati_netft_rdt" && d.protocol != "ati_netft_can" &&
      d.protocol != "robotiq_ft300")
    n.child("protocol")
        .fail("expected 'ati_netcanoem', 'declarative', 'ati_netft_rdt', 'ati_netft_can' or 'robotiq_ft300', found '" + d.protocol + "'");
  const bool rdt = d.protocol == "ati_netft_rdt";
  const bool box_can = d.protocol == "ati_netft_can";
  const bool ft300 = d.protocol == "robotiq_ft300";
  if (box_can) {
    // The box's short answers: their scale is in no source found (docs/hardware.md), so it is
    // never assumed from the RDT page.
    for (const char* f : {"host", "port", "calibration_xml"})
      if (n.has(f)) n.child(f).fail("the ati_netft_can protocol is CAN: give interface, base_id and the counts per unit");
    if (!n.has("base_id")) n.fail("the Net F/T's CAN base address (its DIP switches) is needed", "base_id");
    if (!n.has("counts_per_force") || !n.has("counts_per_torque"))
      n.fail("the counts per unit of the box's 16-bit CAN values are needed (check them with a known load)",
             n.has("counts_per_force") ? "counts_per_torque" : "counts_per_force");
    d.counts_per_force = n.child("counts_per_force").num_positive();
    d.counts_per_torque = n.child("counts_per_torque").num_positive();
    d.force_unit = n.str("force_unit", d.force_unit);
    d.torque_unit = n.str("torque_unit", d.torque_unit);
  }
  for (const char* f : {"serial_device", "baud", "slave", "allowed_writes"})
    if (!ft300 && n.has(f)) n.child(f).fail("only the robotiq_ft300 protocol has this field");
  if (ft300 && (n.has("interface") || n.has("base_id") || n.has("host")))
    n.child(n.has("interface") ? "interface"
            : n.has("base_id") ? "base_id"
                               : "host")
        .fail("the robotiq_ft300 protocol is a serial line: give serial_device");
  if (ft300) {
    if (!n.has("serial_device")) n.fail("the robotiq_ft300 protocol needs its serial port (e.g. /dev/ttyUSB0)", "serial_device");
    d.serial_device = n.str("serial_device", "");
    if (n.has("baud")) {
      d.baud = static_cast<int>(n.child("baud").integer());
      if (d.baud != 19200) n.child("baud").fail("the FT 300 speaks at 19200 baud only");
    }
    if (n.has("slave")) {
      const long sl = n.child("slave").integer();
      if (sl < 1 || sl > 247) n.child("slave").fail("a Modbus slave id is 1..247 (the FT 300's is 9)");
      d.slave = static_cast<int>(sl);
    }
    if (n.has("allowed_writes")) {
      const auto w = n.child("allowed_writes");
      for (const auto& item : w.seq()) {
        const auto name = item.str();
        if (name != "stream_start")
          item.fail("the FT 300 has one write hil may make: 'stream_start' (0x0200 to register 410); found '" + name + "'");
        d.allowed_writes.push_back(name);
      }
    }
    d.rate_hz = d.allowed_writes.empty() ? 50.0 : 100.0;
  }
  for (const char* f : {"host", "port", "calibration_xml"})
    if (!rdt && !box_can && n.has(f)) n.child(f).fail("only the ati_netft_rdt protocol has this field");
  for (const char* f : {"counts_per_force", "counts_per_torque", "force_unit", "torque_unit"})
    if (!rdt && !box_can && n.has(f)) n.child(f).fail("only the ati_netft_rdt and ati_netft_can protocols have this field");
  if (rdt && (n.has("interface") || n.has("base_id")))
    n.child(n.has("interface") ? "interface" : "base_id").fail("the ati_netft_rdt protocol is UDP: give host and port");
  if (rdt) {
    if (!n.has("host")) n.fail("the ati_netft_rdt protocol needs the box's address", "host");
    d.host = n.str("host", "");
    if (n.has("port")) {
      const long p = n.child("port").integer();
      if (p < 1 || p > 65535) n.child("port").fail("must be 1..65535");
      d.port = static_cast<int>(p);
    }
    d.calibration_xml = n.str("calibration_xml", "");
    if (n.has("counts_per_force")) d.counts_per_force = n.child("counts_per_force").num_positive();
    if (n.has("counts_per_torque")) d.counts_per_torque = n.child("counts_per_torque").num_positive();
    d.force_unit = n.str("force_unit", d.force_unit);
    d.torque_unit = n.str("torque_unit", d.torque_unit);
    const bool counts = n.has("counts_per_force") || n.has("counts_per_torque");
    if (d.calibration_xml.empty() == !counts)
      n.fail(counts ? "give either calibration_xml or counts_per_force/counts_per_torque, not both"
                    : "the counts per unit are needed: calibration_xml (the box's netftapi2.xml saved to a file) or counts_per_force "
                      "and counts_per_torque (the box's Configuration page)",
             counts ? "calibration_xml" : "counts_per_force");
    if (counts && (d.counts_per_force <= 0.0 || d.counts_per_torque <= 0.0))
      n.fail("give both counts_per_force and counts_per_torque", d.counts_per_force <= 0.0 ? "counts_per_force" : "counts_per_torque");
  }
  d.interface = n.str("interface", d.interface);
  if (n.has("base_id")) {
    const long b = n.child("base_id").integer();
    if (box_can && (b < 0 || b > 0x7F9))
      n.child("base_id").fail("the Net F/T's CAN base address must be 0..0x7F9 (answers on base+5, base+6)");
    if (!box_can && (b < 0 || b > 0x7F)) n.child("base_id").fail("ATI base id must be 0..127 (11-bit id = base << 4 | opcode)");
    d.base_id = static_cast<std::uint32_t>(b);
  }
  if (n.has("rate_hz")) d.rate_hz = n.child("rate_hz").num_positive();
  if (n.has("sensor_pose")) d.T_fp_sensor = read_pose(n.child("sensor_pose"));
  if (n.has("signals"))
    for (const auto& s : n.child("signals").seq()) d.signals.push_back(read_signal(s));
  if (d.protocol == "declarative" && d.signals.empty()) n.fail("the declarative protocol needs a list of signals", "signals");
  if (n.has("saturation_limits")) {
    d.saturation_limits = n.child("saturation_limits").nums();
    if (d.saturation_limits.size() != 6) n.child("saturation_limits").fail("expected 6 limits fx fy fz mx my mz");
  }
  if (n.has("gain_tolerance")) {
    d.gain_tolerance = n.child("gain_tolerance").num_positive();
    if (d.gain_tolerance >= 1.0) n.child("gain_tolerance").fail("a relative scale error, > 0 and < 1 (0.15 is 15 %)");
  }
  return d;
}

RobotControllerSpec read_controller(const YNode& n) {
  n.only({"transport", "host", "port", "unit_id", "serial_device", "baud", "parity", "data_bits", "stop_bits", "rate_hz", "timeout_s",
          "register_map", "registers"});
  RobotControllerSpec c;
  c.transport = n.str("transport", c.transport);
  if (c.transport != "tcp" && c.transport != "rtu") n.child("transport").fail("expected 'tcp' or 'rtu', found '" + c.transport + "'");
  c.host = n.str("host", c.host);
  if (n.has("port")) {
    const long p = n.child("port").integer();
    if (p < 1 || p > 65535) n.child("port").fail("expected a TCP port 1..65535");
    c.port = static_cast<int>(p);
  }
  if (n.has("unit_id")) {
    const long u = n.child("unit_id").integer();
    if (u < 0 || u > 247) n.child("unit_id").fail("Modbus unit id must be 0..247");
    c.unit_id = static_cast<int>(u);
  }
  c.serial_device = n.str("serial_device", "");
  if (c.transport == "rtu" && c.serial_device.empty()) n.fail("Modbus RTU needs serial_device", "serial_device");
  if (n.has("baud")) c.baud = static_cast<int>(n.child("baud").integer());
  if (n.has("parity")) {
    const auto p = n.child("parity").str();
    if (p != "N" && p != "E" && p != "O") n.child("parity").fail("expected N, E or O");
    c.parity = p[0];
  }
  if (n.has("data_bits")) c.data_bits = static_cast<int>(n.child("data_bits").integer());
  if (n.has("stop_bits")) c.stop_bits = static_cast<int>(n.child("stop_bits").integer());
  if (n.has("rate_hz")) c.rate_hz = n.child("rate_hz").num_positive();
  if (n.has("timeout_s")) c.timeout_s = n.child("timeout_s").num_positive();
  c.register_map = n.str("register_map", c.register_map);
  if (c.register_map != "ur" && c.register_map != "float32" && c.register_map != "custom")
    n.child("register_map").fail("expected 'ur', 'float32' or 'custom', found '" + c.register_map + "'");
  if (n.has("registers")) {
    for (const auto& e : n.child("registers").seq()) {
      e.only({"quantity", "address", "table", "type", "word_order", "scale", "offset"});
      RegisterEntrySpec r;
      r.quantity = e.req("quantity").str();
      const bool joint = r.quantity.size() >= 2 && r.quantity[0] == 'j' &&
                         r.quantity.find_first_not_of("0123456789", 1) == std::string::npos;
      static const std::set<std::string> pose{"px", "py", "pz", "rx", "ry", "rz"};
      if (!joint && !pose.count(r.quantity)) e.child("quantity").fail("expected j1..jN, px py pz or rx ry rz, found '" + r.quantity + "'");
      const long a = e.req("address").integer();
      if (a < 0 || a > 65535) e.child("address").fail("register address must be 0..65535");
      r.address = static_cast<unsigned>(a);
      r.table = e.str("table", r.table);
      if (r.table != "holding" && r.table != "input") e.child("table").fail("expected 'holding' or 'input'");
      r.type = e.str("type", r.type);
      static const std::set<std::string> types{"int16", "uint16", "int32", "uint32", "float32"};
      if (!types.count(r.type)) e.child("type").fail("expected int16, uint16, int32, uint32 or float32, found '" + r.type + "'");
      r.word_order = e.str("word_order", r.word_order);
      if (r.word_order != "big" && r.word_order != "little") e.child("word_order").fail("expected 'big' or 'little'");
      r.scale = e.num("scale", 1.0);
      r.offset = e.num("offset", 0.0);
      c.registers.push_back(r);
    }
  }
  if (c.register_map == "custom" && c.registers.empty()) n.fail("register_map 'custom' needs a registers list", "registers");
  return c;
}

}  // namespace

Eigen::Isometry3d RigSpec::T_world(const std::string& f) const {
  if (f == "world") return Eigen::Isometry3d::Identity();
  return chain(*this, f, "world");
}

Eigen::Isometry3d RigSpec::T_ee(const std::string& f) const {
  if (f == "ee") return Eigen::Isometry3d::Identity();
  return chain(*this, f, "ee");
}

std::size_t total_polyhedra(const RigSpec& rig) {
  std::size_t n = 0;
  for (const auto& o : rig.objects) n += o.polyhedron_count();
  return n;
}

std::size_t total_features(const RigSpec& rig) {
  std::size_t n = 0;
  for (const auto& o : rig.objects) n += o.features.size();
  return n;
}

RigSpec parse_rig(const std::string& text, const std::string& display_name) {
  RigSpec rig;
  rig.source = display_name;
  const YAML::Node doc = load_yaml(text, display_name);
  if (!doc.IsDefined() || doc.IsNull()) throw error::FormatError({display_name, 0, 0, ""}, "empty rig file");
  const YNode root(doc, "", &rig.source);
  root.only({"format_version", "name", "frames", "robot", "objects", "devices", "model", "tf"});
  rig.format_version = static_cast<int>(root.req("format_version").integer());
  if (rig.format_version != 1)
    root.child("format_version").fail("this hil reads rig format version 1, found " + std::to_string(rig.format_version));
  rig.name = read_name(root, "name");

  std::set<std::string> frame_names{"world", "ee"};
  if (root.has("frames")) {
    for (const auto& fn : root.child("frames").seq()) {
      auto f = read_frame(fn);
      if (!frame_names.insert(f.name).second) fn.child("name").fail("frame '" + f.name + "' is defined twice (or is reserved: world, ee)");
      rig.frames.push_back(std::move(f));
    }
    for (std::size_t i = 0; i < rig.frames.size(); ++i)
      if (!frame_names.count(rig.frames[i].parent))
        root.child("frames").seq()[i].child("parent").fail("unknown parent frame '" + rig.frames[i].parent + "'");
    // Every frame must reach world or ee without a cycle.
    for (const auto& f : rig.frames) {
      std::string cur = f.name;
      std::size_t hops = 0;
      while (cur != "world" && cur != "ee") {
        if (++hops > rig.frames.size())
          throw error::FormatError({display_name, 0, 0, "frames"}, "frame tree has a cycle through '" + f.name + "'");
        cur = rig.frame(cur)->parent;
      }
    }
  }
  if (root.has("robot")) rig.robot = read_robot(root.child("robot"), display_name);
  if (root.has("tf")) {
    rig.tf = read_tf(root.child("tf"), rig);
  } else if (rig.robot && rig.robot->convention == DhConvention::urdf && !rig.robot->base_link.empty()) {
    rig.tf.base = rig.robot->base_link;
  }
  // The rig's own frames keep their names on /tf_static: none may take a name world, base or ee have there.
  for (std::size_t i = 0; i < rig.frames.size(); ++i) {
    const auto& name = rig.frames[i].name;
    if (name == rig.tf.world || (rig.robot && name == rig.tf.base) || name == rig.tf.ee)
      root.child("frames").seq()[i].child("name").fail("'" + name + "' is the name of " +
                                                       (name == rig.tf.world ? "world"
                                                        : name == rig.tf.ee  ? "ee"
                                                                             : "the robot base") +
                                                       " on /tf (tf: section; a URDF robot's base link): rename one");
  }
  if (root.has("objects")) {
    std::set<std::string> names;
    for (const auto& on : root.child("objects").seq()) {
      auto o = read_object(on);
      if (!names.insert(o.name).second) on.child("name").fail("object '" + o.name + "' is defined twice");
      if (!frame_names.count(o.frame)) on.child("frame").fail("unknown frame '" + o.frame + "' (define it under frames)");
      rig.objects.push_back(std::move(o));
    }
  }
  if (root.has("devices")) {
    const YNode d = root.child("devices");
    d.only({"force_plate", "robot"});
    if (d.has("force_plate")) rig.devices.force_plate = read_force_plate(d.child("force_plate"));
    if (d.has("robot")) rig.devices.robot = read_controller(d.child("robot"));
  }
  if (root.has("model")) {
    const YNode m = root.child("model");
    m.only({"contact", "uncertainties"});
    if (m.has("contact")) rig.model.contact = read_contact(m.child("contact"));
    if (m.has("uncertainties")) {
      std::set<std::string> names;
      for (const auto& un : m.child("uncertainties").seq()) {
        auto u = read_uncertainty(un, rig);
        if (!names.insert(u.name).second) un.child("name").fail("uncertainty '" + u.name + "' is defined twice");
        rig.model.uncertainties.push_back(u);
      }
    }
  }
  return rig;
}

RigSpec load_rig(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw error::FormatError({path, 0, 0, ""}, "cannot open rig file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (ss.str().find_first_not_of(" \t\r\n") == std::string::npos) throw error::FormatError({path, 0, 0, ""}, "empty rig file");
  return parse_rig(ss.str(), path);
}

}  // namespace hil::format
