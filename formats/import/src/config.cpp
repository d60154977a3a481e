#include <hil/import/config.hpp>

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <numbers>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <set>
#include <sstream>

#include <hil/format/csv.hpp>
#include "config_internal.hpp"
#include <hil/error/error.hpp>
#include <hil/format/yaml.hpp>
#include <hil/import/timeparse.hpp>

namespace hil::import {
namespace {

using error::FormatError;
using error::Location;

using Node = format::YamlNode;

/// `[x, y, z]` column names.
std::array<std::string, 3> names3(const Node& n) {
  const auto items = n.seq();
  if (items.size() != 3) n.fail("expected a list of 3 column names (x, y, z), found " + std::to_string(items.size()));
  return {items[0].str(), items[1].str(), items[2].str()};
}

bool valid_name(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
  return true;
}

std::string checked_name(const Node& n) {
  const auto s = n.str();
  if (!valid_name(s)) n.fail("expected a name of letters, digits, '_' and '-', found '" + s + "'");
  return s;
}

/// `plate_axes: [x, y, z]`: entry i is the signed data axis that forms plate axis i.
Eigen::Matrix3d parse_plate_axes(const Node& n) {
  const auto items = n.seq();
  if (items.size() != 3) n.fail("expected 3 signed axes such as [x, y, z] or [-y, x, z]");
  Eigen::Matrix3d R = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i) {
    auto s = items[static_cast<std::size_t>(i)].str();
    double sign = 1.0;
    if (!s.empty() && (s[0] == '-' || s[0] == '+')) {
      sign = s[0] == '-' ? -1.0 : 1.0;
      s = s.substr(1);
    }
    if (s != "x" && s != "y" && s != "z")
      items[static_cast<std::size_t>(i)].fail("expected x, y or z with an optional sign, found '" + s + "'");
    R(i, s[0] - 'x') = sign;
  }
  if (std::abs(R.determinant() - 1.0) > 1e-9)
    n.fail("the axes must form a right-handed frame (a rotation): each of x, y, z once, determinant +1");
  return R;
}

TimeSpec parse_time(const Node& n) {
  n.only({"column", "format", "unit", "start_time", "pattern", "utc_offset_h", "non_increasing", "gap_factor"});
  TimeSpec t;
  t.column = n.req("column").str();
  t.format = n.req("format").choice<TimeFormat>({{"seconds", TimeFormat::seconds}, {"datetime", TimeFormat::datetime}});
  if (t.format == TimeFormat::seconds) {
    for (const char* k : {"pattern", "utc_offset_h"})
      if (n.has(k)) n.child(k).fail("only for format: datetime");
    if (n.has("unit")) t.s_per_unit = n.child("unit").choice<double>({{"s", 1.0}, {"ms", 1e-3}, {"us", 1e-6}, {"ns", 1e-9}});
    if (n.has("start_time")) {
      t.start_time_utc = n.child("start_time").str();
      if (!parse_iso8601_utc_us(t.start_time_utc))
        n.child("start_time").fail("expected UTC ISO 8601 like 2026-11-21T10:00:00.000Z, found '" + t.start_time_utc + "'");
    }
  } else {
    for (const char* k : {"unit", "start_time"})
      if (n.has(k)) n.child(k).fail("only for format: seconds (a datetime column carries its own start time)");
    if (n.has("pattern")) {
      t.pattern = n.child("pattern").str();
      try {
        check_datetime_pattern(t.pattern);
      } catch (const std::invalid_argument& e) {
        n.child("pattern").fail(e.what());
      }
    }
    if (n.has("utc_offset_h")) {
      t.utc_offset_h = n.child("utc_offset_h").num();
      if (std::abs(*t.utc_offset_h) > 14.0) n.child("utc_offset_h").fail("expected an offset between -14 and 14 hours");
    }
  }
  if (n.has("non_increasing"))
    t.non_increasing =
        n.child("non_increasing").choice<NonIncreasingTime>({{"drop", NonIncreasingTime::drop}, {"error", NonIncreasingTime::error}});
  if (n.has("gap_factor")) {
    t.gap_factor = n.child("gap_factor").num();
    if (!(t.gap_factor > 1.0)) n.child("gap_factor").fail("expected a number > 1");
  }
  return t;
}

BodySpec parse_body(const Node& n) {
  n.only({"name", "markers", "reference_rows", "reference_m", "origin", "min_markers", "max_residual_m"});
  BodySpec b;
  b.name = checked_name(n.req("name"));
  std::set<std::string> seen;
  for (const auto& m : n.req("markers").seq()) {
    MarkerSpec ms;
    if (m.is_scalar()) {
      ms.name = checked_name(m);
      ms.columns = {ms.name + "_x", ms.name + "_y", ms.name + "_z"};
    } else {
      m.only({"name", "columns"});
      ms.name = checked_name(m.req("name"));
      ms.columns = names3(m.req("columns"));
    }
    if (!seen.insert(ms.name).second) m.fail("marker '" + ms.name + "' appears twice in this body");
    b.markers.push_back(ms);
  }
  if (b.markers.size() < 3)
    n.child("markers").fail("a rigid body needs at least 3 markers to fix its pose, found " + std::to_string(b.markers.size()));
  if (n.has("reference_m") && (n.has("reference_rows") || n.has("origin")))
    n.child("reference_m").fail("give either reference_m or reference_rows (with origin), not both");
  if (n.has("reference_m")) {
    const auto r = n.child("reference_m");
    r.expect_map();
    for (const auto& key : r.keys()) {
      bool known = false;
      for (const auto& m : b.markers) known = known || m.name == key;
      if (!known) r.child(key).fail("no marker named '" + key + "' in this body");
    }
    for (std::size_t i = 0; i < b.markers.size(); ++i) {
      if (!r.has(b.markers[i].name)) r.fail("required field is missing", b.markers[i].name);
      b.reference_body_m.push_back(r.child(b.markers[i].name).vec3());
    }
  } else {
    if (n.has("reference_rows")) b.reference_rows = n.child("reference_rows").count(1);
    if (n.has("origin"))
      b.origin = n.child("origin").choice<BodyOrigin>({{"marker_centroid", BodyOrigin::marker_centroid}, {"world", BodyOrigin::world}});
  }
  if (n.has("min_markers")) {
    b.min_markers = n.child("min_markers").count(3);
    if (b.min_markers > b.markers.size())
      n.child("min_markers").fail("larger than the body's " + std::to_string(b.markers.size()) + " markers");
  }
  if (n.has("max_residual_m")) b.max_residual_m = n.child("max_residual_m").num_positive();
  return b;
}

WrenchSpec parse_wrench(const Node& n) {
  n.only({"force", "moment", "force_unit", "moment_unit", "measured", "plate_axes", "moment_point_m"});
  WrenchSpec w;
  w.force_columns = names3(n.req("force"));
  w.moment_columns = names3(n.req("moment"));
  if (n.has("force_unit")) w.n_per_unit = n.child("force_unit").choice<double>({{"N", 1.0}, {"kN", 1e3}});
  if (n.has("moment_unit")) w.nm_per_unit = n.child("moment_unit").choice<double>({{"N*m", 1.0}, {"N*mm", 1e-3}, {"kN*m", 1e3}});
  if (n.has("measured")) w.measured_on_body = n.child("measured").choice<bool>({{"on_plate", false}, {"on_body", true}});
  if (n.has("plate_axes")) w.R_fp_data = parse_plate_axes(n.child("plate_axes"));
  if (n.has("moment_point_m")) w.moment_point_fp_m = n.child("moment_point_m").vec3();
  return w;
}

}  // namespace

std::vector<std::string> expand_columns(const std::vector<std::string>& names) {
  std::vector<std::string> out;
  for (const auto& s : names) {
    if (s.size() > 4 && s.compare(s.size() - 4, 4, "_xyz") == 0) {
      const auto stem = s.substr(0, s.size() - 3);
      for (const char* a : {"x", "y", "z"}) out.push_back(stem + a);
    } else {
      out.push_back(s);
    }
  }
  return out;
}

void read_csv_section(const Node& n, char& delimiter, bool& header, std::vector<std::string>& columns) {
  n.only({"delimiter", "header", "columns"});
  if (n.has("delimiter")) {
    const auto d = n.child("delimiter").str();
    if (d == "tab" || d == "\t") delimiter = '\t';
    else if (d.size() == 1 && d != "\"" && d != "#" && d != "." && !std::isalnum(static_cast<unsigned char>(d[0]))) delimiter = d[0];
    else n.child("delimiter").fail("expected one character such as ',' ';' or tab, found '" + d + "'");
  }
  if (n.has("header")) header = n.child("header").boolean();
  if (n.has("columns")) {
    if (header) n.child("columns").fail("columns name a file without a header: set header: false, or drop columns");
    std::vector<std::string> raw;
    for (const auto& e : n.child("columns").seq()) raw.push_back(e.str());
    columns = expand_columns(raw);
    std::set<std::string> seen;
    for (const auto& s : columns)
      if (!seen.insert(s).second) n.child("columns").fail("column '" + s + "' is named twice");
  } else if (!header) {
    n.fail("required field is missing", "columns");
  }
}

std::string config_kind(const YAML::Node& doc, const std::string& display_name) {
  if (!doc.IsDefined() || doc.IsNull() || !doc.IsMap()) return "run";
  std::string file = display_name;
  const Node root(doc, "", &file);
  if (!root.has("kind")) return "run";
  const auto k = root.child("kind").str();
  if (k != "run" && k != "calibration_run") root.child("kind").fail("expected 'run' or 'calibration_run', found '" + k + "'");
  return k;
}

std::string import_config_kind(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FormatError({path, 0, 0, ""}, "cannot open import config");
  std::ostringstream ss;
  ss << in.rdbuf();
  return config_kind(format::load_yaml(ss.str(), path), path);
}

ImportConfig parse_import_config(const std::string& text, const std::string& display_name) {
  ImportConfig c;
  c.file = display_name;
  const YAML::Node doc = format::load_yaml(text, display_name);
  if (!doc.IsDefined() || doc.IsNull()) throw FormatError({display_name, 0, 0, ""}, "empty import config");
  const Node root(doc, "", &c.file);
  root.only({"format_version", "kind", "rig", "source", "notes", "csv", "time", "markers", "bodies", "ee", "wrench", "joints",
             "extra_columns", "twist"});
  if (config_kind(doc, display_name) != "run") root.child("kind").fail("this is not a run import config");
  if (root.req("format_version").count(1) != 1) root.child("format_version").fail("this hil reads import config version 1");
  if (root.has("rig")) c.rig = checked_name(root.child("rig"));
  if (root.has("source")) c.source_name = checked_name(root.child("source"));
  c.notes = root.has("notes") ? root.child("notes").str() : "";

  if (root.has("csv")) read_csv_section(root.child("csv"), c.delimiter, c.header, c.columns);

  c.time = parse_time(root.req("time"));

  if (root.has("markers")) {
    const auto n = root.child("markers");
    n.only({"unit", "zero_is_missing"});
    if (n.has("unit")) c.marker_m_per_unit = n.child("unit").choice<double>({{"m", 1.0}, {"cm", 1e-2}, {"mm", 1e-3}});
    if (n.has("zero_is_missing")) c.zero_marker_is_missing = n.child("zero_is_missing").boolean();
  }

  std::set<std::string> body_names;
  for (const auto& b : root.req("bodies").seq()) {
    c.bodies.push_back(parse_body(b));
    if (!body_names.insert(c.bodies.back().name).second) b.child("name").fail("body name used twice");
  }
  if (c.bodies.empty()) root.child("bodies").fail("expected at least one body");
  c.ee_body = root.req("ee").str();
  if (!body_names.count(c.ee_body)) root.child("ee").fail("no body named '" + c.ee_body + "' in bodies");

  c.wrench = parse_wrench(root.req("wrench"));

  if (root.has("joints")) {
    const auto n = root.child("joints");
    n.only({"columns", "unit"});
    for (const auto& e : n.req("columns").seq()) c.joint_columns.push_back(e.str());
    if (n.has("unit")) c.joint_si_per_unit = n.child("unit").choice<double>({{"rad", 1.0}, {"deg", std::numbers::pi / 180.0}, {"m", 1.0}});
  }

  std::set<std::string> out_names;
  if (root.has("extra_columns")) {
    for (const auto& e : root.child("extra_columns").seq()) {
      ExtraColumnSpec x;
      if (e.is_scalar()) {
        x.column = e.str();
        x.name = x.column;
      } else {
        e.only({"column", "name", "scale"});
        x.column = e.req("column").str();
        x.name = e.has("name") ? e.child("name").str() : x.column;
        if (e.has("scale")) x.scale = e.child("scale").num();
      }
      if (!valid_name(x.name)) e.fail("output name '" + x.name + "' must be letters, digits, '_' and '-'");
      static const std::vector<std::string> req{"t",  "px", "py", "pz", "qw", "qx", "qy", "qz", "vx", "vy",
                                                "vz", "wx", "wy", "wz", "fx", "fy", "fz", "mx", "my", "mz"};
      const bool joint_like = x.name.size() >= 2 && x.name[0] == 'j' && x.name.find_first_not_of("0123456789", 1) == std::string::npos;
      if (std::find(req.begin(), req.end(), x.name) != req.end() || joint_like)
        e.fail("output name '" + x.name + "' is a samples.csv column of its own; give it another name");
      if (!out_names.insert(x.name).second) e.fail("output name '" + x.name + "' used twice");
      c.extras.push_back(x);
    }
  }

  if (root.has("twist")) {
    const auto n = root.child("twist");
    n.only({"window_s"});
    if (n.has("window_s")) c.twist_window_s = n.child("window_s").num_positive();
  }
  return c;
}

ImportConfig load_import_config(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FormatError({path, 0, 0, ""}, "cannot open import config");
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_import_config(ss.str(), path);
}

}  // namespace hil::import
