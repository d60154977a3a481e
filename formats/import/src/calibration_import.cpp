#include <hil/import/calibration_import.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <hil/error/error.hpp>
#include <hil/format/yaml.hpp>
#include "config_internal.hpp"

namespace hil::import {
namespace {

using error::FormatError;
using Node = format::YamlNode;

std::array<std::string, 3> three_columns(const Node& n) {
  const auto seq = n.seq();
  if (seq.size() != 3) n.fail("expected three column names");
  return {seq[0].str(), seq[1].str(), seq[2].str()};
}

/// Shortest text that reads back as the same double.
std::string num(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

}  // namespace

CalibrationImportConfig parse_calibration_import_config(const std::string& text, const std::string& display_name) {
  CalibrationImportConfig c;
  c.file = display_name;
  const YAML::Node doc = format::load_yaml(text, display_name);
  if (!doc.IsDefined() || doc.IsNull()) throw FormatError({display_name, 0, 0, ""}, "empty import config");
  const Node root(doc, "", &c.file);
  root.only({"format_version", "kind", "csv", "posture", "station", "joints", "point", "orientation", "sigma_m", "sigma_rad", "flags"});
  if (root.req("format_version").count(1) != 1) root.child("format_version").fail("this hil reads import config version 1");
  if (config_kind(doc, display_name) != "calibration_run") root.fail("kind: calibration_run is required here", "kind");
  if (root.has("csv")) read_csv_section(root.child("csv"), c.delimiter, c.header, c.columns);
  if (root.has("posture")) c.posture_column = root.child("posture").str();
  if (root.has("station")) {
    const auto n = root.child("station");
    if (n.is_map()) {
      n.only({"column"});
      c.station_column = n.req("column").str();
    } else {
      c.station_value = n.str();
      if (c.station_value.empty()) n.fail("an empty station id");
    }
  }
  if (root.has("joints")) {
    const auto n = root.child("joints");
    n.only({"unit", "columns"});
    if (n.has("unit")) c.joint_si_per_unit = n.child("unit").choice<double>({{"rad", 1.0}, {"deg", 3.141592653589793 / 180.0}});
    if (n.has("columns")) {
      const auto cols = n.child("columns");
      cols.expect_map();
      for (const auto& key : cols.keys()) c.joint_columns[key] = cols.child(key).str();
    }
  }
  const auto p = root.req("point");
  p.only({"columns", "unit"});
  c.point_columns = three_columns(p.req("columns"));
  if (p.has("unit")) c.point_m_per_unit = p.child("unit").choice<double>({{"m", 1.0}, {"cm", 1e-2}, {"mm", 1e-3}});
  if (root.has("orientation")) {
    const auto o = root.child("orientation");
    o.only({"columns", "form", "unit"});
    c.orientation_columns = three_columns(o.req("columns"));
    if (o.has("form"))
      c.orientation_form = o.child("form").choice<OrientationForm>({{"rpy", OrientationForm::rpy},
                                                                    {"rotation_vector", OrientationForm::rotation_vector}});
    if (o.has("unit")) c.orientation_rad_per_unit = o.child("unit").choice<double>({{"rad", 1.0}, {"deg", 3.141592653589793 / 180.0}});
  }
  if (root.has("sigma_m")) c.sigma_m = root.child("sigma_m").num_positive();
  if (root.has("sigma_rad")) {
    if (!c.orientation_columns) root.child("sigma_rad").fail("sigma_rad without an orientation");
    c.sigma_rad = root.child("sigma_rad").num_positive();
  }
  if (root.has("flags")) {
    const auto f = root.child("flags");
    f.expect_map();
    for (const auto& key : f.keys()) {
      if (key.empty() || key.find_first_of(", ") != std::string::npos) f.child(key).fail("a flag name without commas or spaces");
      c.flags[key] = f.child(key).str();
    }
  }
  return c;
}

CalibrationImportConfig load_calibration_import_config(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FormatError({path, 0, 0, ""}, "cannot open import config");
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_calibration_import_config(ss.str(), path);
}

std::string import_calibration_table(const format::CsvTable& t, const CalibrationImportConfig& cfg, const format::RobotSpec& robot) {
  // read_delimited keeps every cell as text: each is read here, with its place in the source.
  struct Col {
    std::string name;
    std::size_t index = 0;  ///< 1-based
    const std::vector<std::string>* cells = nullptr;
  };
  auto column = [&](const std::string& name, const std::string& what) {
    if (!t.has(name)) throw FormatError({t.file, t.header_line, 0, name}, "no such column (" + what + ", from " + cfg.file + ")");
    const auto idx = static_cast<std::size_t>(std::find(t.header.begin(), t.header.end(), name) - t.header.begin()) + 1;
    return Col{name, idx, &t.text(name)};
  };
  // A missing cell stops the import where it is in the source, not later in the written run.
  auto at = [&](const Col& c, std::size_t row) {
    return format::read_number((*c.cells)[row], {t.file, t.row_line[row], c.index, c.name}, format::MissingCells::refuse);
  };
  for (const auto& [joint, _] : cfg.joint_columns) {
    bool known = false;
    for (const auto& j : robot.joints) known = known || j.name == joint;
    if (!known) throw FormatError({cfg.file, 0, 0, "joints.columns." + joint}, "the robot has no joint '" + joint + "'");
  }
  std::vector<Col> q;
  std::vector<std::string> q_names;
  for (const auto& j : robot.joints) {
    const auto it = cfg.joint_columns.find(j.name);
    const std::string source = it == cfg.joint_columns.end() ? j.name : it->second;
    // A mimic joint the source does not log is left out: the run's reader derives it from its master.
    if (!j.mimic_of.empty() && it == cfg.joint_columns.end() && !t.has(source)) continue;
    q.push_back(column(source, "joint " + j.name));
    q_names.push_back(j.name);
  }
  std::array<Col, 3> p{}, r{};
  for (std::size_t k = 0; k < 3; ++k) p[k] = column(cfg.point_columns[k], "the measured point");
  if (cfg.orientation_columns)
    for (std::size_t k = 0; k < 3; ++k) r[k] = column((*cfg.orientation_columns)[k], "the orientation");
  std::vector<std::pair<std::string, Col>> flags;
  for (const auto& [name, col] : cfg.flags) flags.emplace_back(name, column(col, "flag " + name));
  if (!cfg.posture_column.empty() && !t.has(cfg.posture_column))
    throw FormatError({t.file, t.header_line, 0, cfg.posture_column}, "no such column (the posture id, from " + cfg.file + ")");
  if (!cfg.station_column.empty() && !t.has(cfg.station_column))
    throw FormatError({t.file, t.header_line, 0, cfg.station_column}, "no such column (the station, from " + cfg.file + ")");
  auto cell_text = [&](const std::string& col, std::size_t row) {
    std::string v = t.text(col)[row];
    v.erase(0, v.find_first_not_of(" \t"));
    v.erase(v.find_last_not_of(" \t\r") + 1);
    if (v.empty() || v.find(',') != std::string::npos)
      throw FormatError({t.file, t.row_line[row], 0, col}, "a posture or station id must be non-empty text without commas");
    return v;
  };

  std::ostringstream out;
  out << "# hil calibration run, imported from " << t.file << " with " << cfg.file << "\n";
  out << "posture,station";
  for (const auto& name : q_names) out << ',' << name;
  out << ",px,py,pz";
  if (cfg.orientation_columns) out << ",rx,ry,rz";
  if (cfg.sigma_m > 0) out << ",sigma_m";
  if (cfg.sigma_rad > 0) out << ",sigma_rad";
  for (const auto& f : flags) out << ",flag_" << f.first;
  out << '\n';
  for (std::size_t row = 0; row < t.rows(); ++row) {
    out << (cfg.posture_column.empty() ? std::to_string(row + 1) : cell_text(cfg.posture_column, row)) << ','
        << (cfg.station_column.empty() ? cfg.station_value : cell_text(cfg.station_column, row));
    for (const auto& c : q) out << ',' << num(at(c, row) * cfg.joint_si_per_unit);
    for (const auto& c : p) out << ',' << num(at(c, row) * cfg.point_m_per_unit);
    if (cfg.orientation_columns) {
      Eigen::Vector3d a(at(r[0], row), at(r[1], row), at(r[2], row));
      a *= cfg.orientation_rad_per_unit;
      Eigen::Vector3d rv = a;
      if (cfg.orientation_form == OrientationForm::rpy) {
        // URDF's (and Pinocchio's) roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll).
        const Eigen::Matrix3d R = (Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
                                   Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()))
                                      .toRotationMatrix();
        const Eigen::AngleAxisd aa(R);
        rv = aa.angle() * aa.axis();
      }
      for (int k = 0; k < 3; ++k) out << ',' << num(rv[k]);
    }
    if (cfg.sigma_m > 0) out << ',' << num(cfg.sigma_m);
    if (cfg.sigma_rad > 0) out << ',' << num(cfg.sigma_rad);
    for (const auto& f : flags) out << ',' << num(at(f.second, row));
    out << '\n';
  }
  return out.str();
}

}  // namespace hil::import
