#include <hil/models/stiffness.hpp>

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <sstream>

#include <hil/calibration/experiment.hpp>
#include <hil/format/csv.hpp>
#include <hil/error/error.hpp>

namespace hil::models {
namespace hc = hil::calibration;
using error::FormatError;

hc::SerialRobot to_serial_robot(const format::RobotSpec& spec) {
  hc::SerialRobot r;
  r.name = spec.name;
  r.convention = spec.convention == format::DhConvention::standard   ? hc::DhConvention::standard
                 : spec.convention == format::DhConvention::modified ? hc::DhConvention::modified
                                                                     : hc::DhConvention::urdf;
  for (const auto& j : spec.joints) {
    hc::DhRow row;
    row.name = j.name;
    row.kind = j.type == format::JointType::revolute ? hc::JointKind::revolute : hc::JointKind::prismatic;
    row.a_m = j.a_m;
    row.alpha_rad = j.alpha_rad;
    row.d_m = j.d_m;
    row.theta_offset_rad = j.theta_offset_rad;
    row.lower = j.lower;
    row.upper = j.upper;
    row.T_parent_joint = j.T_parent_joint.isometry();
    row.axis = j.axis;
    row.mimic_multiplier = j.mimic_multiplier;
    row.mimic_offset = j.mimic_offset;
    r.joints.push_back(row);
  }
  for (std::size_t i = 0; i < spec.joints.size(); ++i) {
    if (spec.joints[i].mimic_of.empty()) continue;
    for (std::size_t m = 0; m < spec.joints.size(); ++m)
      if (spec.joints[m].name == spec.joints[i].mimic_of) r.joints[i].mimic_master = static_cast<int>(m);
    if (r.joints[i].mimic_master < 0)
      throw FormatError({spec.urdf_file, 0, 0, "joint " + spec.joints[i].name},
                        "joint '" + spec.joints[i].name + "' mimics '" + spec.joints[i].mimic_of + "', which the chain does not have");
  }
  for (const auto& in : spec.inertials) r.inertials.push_back({in.mass_kg, in.com_m, in.inertia_kgm2});
  r.body_links = spec.body_links;
  r.T_world_base = spec.T_world_base.isometry();
  r.T_flange_ee = spec.T_flange_ee.isometry();
  return r;
}

hc::SerialRobot load_robot(const std::string& rig_path) {
  const auto rig = format::load_rig(rig_path);
  if (!rig.robot) throw FormatError({rig_path, 0, 0, "robot"}, "the rig has no robot: stiffness calibration needs its DH table or URDF");
  return to_serial_robot(*rig.robot);
}

namespace {

const char* const kLoad[] = {"fx", "fy", "fz", "mx", "my", "mz"};
const char* const kDisp[] = {"dx", "dy", "dz", "rx", "ry", "rz"};

bool is_marker_column(const std::string& c, int& k, std::string& what) {
  if (c.size() < 5 || c[0] != 'm' || !std::isdigit(static_cast<unsigned char>(c[1]))) return false;
  const auto us = c.find('_');
  if (us == std::string::npos) return false;
  try {
    k = std::stoi(c.substr(1, us - 1));
  } catch (...) {
    return false;
  }
  what = c.substr(us + 1);
  static const char* const names[] = {"px", "py", "pz", "dx", "dy", "dz"};
  for (const char* n : names)
    if (what == n) return k >= 1;
  return false;
}

StiffnessTable from_csv(const format::CsvTable& t, int dof, bool require_measured) {
  for (int j = 1; j <= dof; ++j)
    if (!t.has("j" + std::to_string(j)))
      throw FormatError({t.file, 1, 0, "j" + std::to_string(j)}, fmt::format("missing joint column: the robot has {} joints", dof));
  for (const auto& h : t.header) {
    if (h.size() > 1 && h[0] == 'j' && std::isdigit(static_cast<unsigned char>(h[1]))) {
      const int j = std::atoi(h.c_str() + 1);
      if (j > dof) throw FormatError({t.file, 1, 0, h}, fmt::format("the robot has only {} joints", dof));
    }
  }
  int markers = 0;
  for (const auto& h : t.header) {
    int k = 0;
    std::string what;
    if (is_marker_column(h, k, what)) markers = std::max(markers, k);
  }
  for (int k = 1; k <= markers; ++k)
    for (const char* w : {"px", "py", "pz"}) {
      const std::string c = fmt::format("m{}_{}", k, w);
      if (!t.has(c))
        throw FormatError({t.file, 1, 0, c}, fmt::format("marker {} needs its position columns m{}_px m{}_py m{}_pz", k, k, k, k));
    }
  StiffnessTable out;
  const bool has_tool = t.has("dx");
  const bool has_markers_d = markers > 0 && t.has("m1_dx");
  if (has_tool && markers > 0)
    throw FormatError({t.file, 1, 0, "m1_px"}, "give either the tool displacement (dx dy dz) or marker columns, not both");
  if (has_tool)
    for (const char* c : {"dy", "dz"})
      if (!t.has(c)) throw FormatError({t.file, 1, 0, c}, "dx dy dz come together");
  const bool has_rot = t.has("rx");
  if (has_rot)
    for (const char* c : {"ry", "rz"})
      if (!t.has(c)) throw FormatError({t.file, 1, 0, c}, "rx ry rz come together");
  if (has_rot && !has_tool) throw FormatError({t.file, 1, 0, "rx"}, "rx ry rz need dx dy dz");
  if (has_markers_d)
    for (int k = 1; k <= markers; ++k)
      for (const char* w : {"dx", "dy", "dz"}) {
        const std::string c = fmt::format("m{}_{}", k, w);
        if (!t.has(c)) throw FormatError({t.file, 1, 0, c}, fmt::format("marker {} needs m{}_dx m{}_dy m{}_dz", k, k, k, k));
      }
  out.has_measured = has_tool || has_markers_d;
  if (require_measured && !out.has_measured)
    throw FormatError({t.file, 1, 0, "dx"}, "no measured columns: expected dx dy dz [rx ry rz] or marker columns mK_dx mK_dy mK_dz");
  const auto& config = t.numeric("config");
  for (std::size_t i = 0; i < t.rows(); ++i) {
    hc::Measurement m;
    if (config[i] != std::floor(config[i]) || config[i] < 0 || config[i] > 4e9)
      throw FormatError({t.file, t.row_line[i], 0, "config"}, fmt::format("expected a non-negative integer, found {}", config[i]));
    m.config = static_cast<int>(config[i]);
    m.q_rad.resize(dof);
    for (int j = 0; j < dof; ++j) m.q_rad[j] = t.numeric("j" + std::to_string(j + 1))[i];
    for (int c = 0; c < 6; ++c) m.w_world[c] = t.numeric(kLoad[c])[i];
    if (markers > 0) {
      m.kind = hc::MeasurementKind::markers;
      for (int k = 1; k <= markers; ++k)
        m.p_ee_marker_m.emplace_back(t.numeric(fmt::format("m{}_px", k))[i], t.numeric(fmt::format("m{}_py", k))[i],
                                     t.numeric(fmt::format("m{}_pz", k))[i]);
      if (has_markers_d) {
        m.displacement.resize(3 * markers);
        for (int k = 1; k <= markers; ++k)
          for (int a = 0; a < 3; ++a) m.displacement[3 * (k - 1) + a] = t.numeric(fmt::format("m{}_{}", k, kDisp[a]))[i];
      }
    } else {
      m.kind = (has_rot || !has_tool) ? hc::MeasurementKind::pose6 : hc::MeasurementKind::point3;
      if (has_tool) {
        m.displacement.resize(has_rot ? 6 : 3);
        for (int a = 0; a < (has_rot ? 6 : 3); ++a) m.displacement[a] = t.numeric(kDisp[a])[i];
      }
    }
    out.rows.push_back(std::move(m));
    out.lines.push_back(t.row_line[i]);
  }
  if (out.rows.empty()) throw FormatError({t.file, 0, 0, ""}, "the table has no rows");
  return out;
}

format::CsvOptions table_options(const std::string& name) {
  format::CsvOptions o;
  o.required = {"config", "fx", "fy", "fz", "mx", "my", "mz"};
  o.numeric_if_present = [](const std::string& c) {
    if (c.size() > 1 && c[0] == 'j' && std::isdigit(static_cast<unsigned char>(c[1]))) return true;
    for (const char* d : kDisp)
      if (c == d) return true;
    int k = 0;
    std::string w;
    return is_marker_column(c, k, w);
  };
  o.display_name = name;
  return o;
}

}  // namespace

StiffnessTable read_stiffness_table(const std::string& path, int dof, bool require_measured) {
  return from_csv(format::read_csv(path, table_options(path)), dof, require_measured);
}

StiffnessTable parse_stiffness_table(const std::string& text, const std::string& display_name, int dof, bool require_measured) {
  return from_csv(format::parse_csv(text, table_options(display_name)), dof, require_measured);
}

void write_stiffness_table(std::ostream& os, const std::vector<hc::Measurement>& rows, int dof) {
  if (rows.empty()) return;
  const hc::Measurement& first = rows.front();
  os << "config";
  for (int j = 1; j <= dof; ++j) os << ",j" << j;
  for (const char* c : kLoad) os << ',' << c;
  if (first.kind == hc::MeasurementKind::markers) {
    for (std::size_t k = 1; k <= first.p_ee_marker_m.size(); ++k) os << fmt::format(",m{0}_px,m{0}_py,m{0}_pz,m{0}_dx,m{0}_dy,m{0}_dz", k);
  } else {
    const int n = first.kind == hc::MeasurementKind::pose6 ? 6 : 3;
    for (int a = 0; a < n; ++a) os << ',' << kDisp[a];
  }
  os << '\n';
  for (const auto& m : rows) {
    os << m.config;
    for (int j = 0; j < dof; ++j) os << fmt::format(",{:.17g}", m.q_rad[j]);
    for (int c = 0; c < 6; ++c) os << fmt::format(",{:.17g}", m.w_world[c]);
    if (m.kind == hc::MeasurementKind::markers) {
      for (std::size_t k = 0; k < m.p_ee_marker_m.size(); ++k) {
        for (int a = 0; a < 3; ++a) os << fmt::format(",{:.17g}", m.p_ee_marker_m[k][a]);
        for (int a = 0; a < 3; ++a) os << fmt::format(",{:.17g}", m.displacement[static_cast<Eigen::Index>(3 * k) + a]);
      }
    } else {
      for (Eigen::Index a = 0; a < m.displacement.size(); ++a) os << fmt::format(",{:.17g}", m.displacement[a]);
    }
    os << '\n';
  }
}

}  // namespace hil::models
