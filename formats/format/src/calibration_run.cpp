#include <hil/format/calibration_run.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <hil/error/error.hpp>
#include <hil/format/csv.hpp>
#include <hil/format/edit_distance.hpp>

namespace hil::format {
namespace {

using error::FormatError;

const char* const kPoint[] = {"px", "py", "pz"};
const char* const kRotation[] = {"rx", "ry", "rz"};
const char* const kWrench[] = {"fx", "fy", "fz", "mx", "my", "mz"};
const char* const kPayloadCom[] = {"payload_cx", "payload_cy", "payload_cz"};

bool starts_with(const std::string& s, const char* p) { return s.rfind(p, 0) == 0; }

/// `tilt_<link>_rx` / `tilt_<link>_ry` -> link and axis; false when the column is not of that form.
bool tilt_column(const std::string& c, std::string& link, int& axis) {
  if (!starts_with(c, "tilt_") || c.size() < 9) return false;
  const std::string tail = c.substr(c.size() - 3);
  if (tail != "_rx" && tail != "_ry") return false;
  link = c.substr(5, c.size() - 8);
  axis = tail == "_rx" ? 0 : 1;
  return !link.empty();
}

std::size_t column_index(const CsvTable& t, const std::string& name) {
  const auto it = std::find(t.header.begin(), t.header.end(), name);
  return it == t.header.end() ? 0 : static_cast<std::size_t>(it - t.header.begin()) + 1;
}

/// A mimic joint without its own column: the URDF's coupling applied to its master's value (the
/// URDF reader resolves mimics of mimics, so the master is independent and has its column).
double mimic_value(const DhJointSpec& spec, const CsvTable& t, std::size_t row) {
  return spec.mimic_multiplier * t.numeric(spec.mimic_of)[row] + spec.mimic_offset;
}

}  // namespace

bool looks_like_calibration_run(const std::vector<std::string>& header) {
  auto has = [&](const char* c) { return std::find(header.begin(), header.end(), c) != header.end(); };
  return has("posture") && has("px") && has("py") && has("pz");
}

CalibrationRun parse_calibration_run(const std::string& text, const std::string& display_name, const RobotSpec& robot) {
  std::set<std::string> joints;
  for (const auto& j : robot.joints) joints.insert(j.name);
  std::set<std::string> links(robot.body_links.begin(), robot.body_links.end());

  CsvOptions opt;
  opt.display_name = display_name;
  opt.required = {"px", "py", "pz"};
  // A mimic joint's column may be left out: its value follows from its master's (below).
  for (const auto& j : robot.joints)
    if (j.mimic_of.empty()) opt.required.push_back(j.name);
  opt.numeric_if_present = [](const std::string& c) { return c != "posture" && c != "station"; };
  const CsvTable t = parse_csv(text, opt);

  CalibrationRun run;
  run.file = display_name;
  for (const auto& j : robot.joints) run.joint_names.push_back(j.name);
  auto where = [&](std::size_t row, const std::string& col) {
    return error::Location{display_name, row < t.rows() ? t.row_line[row] : t.header_line, column_index(t, col), col};
  };
  if (t.rows() == 0) throw FormatError({display_name, t.header_line, 0, ""}, "a calibration run needs at least one posture");
  if (!t.has("posture")) throw FormatError(where(t.rows(), "posture"), "no 'posture' column: each row needs its posture's id");

  // Every column must be one this format knows: a typo is an error, not a silently ignored column.
  std::set<std::string> known{"posture", "station", "px", "py", "pz", "rx", "ry", "rz", "sigma_m", "sigma_rad", "payload_kg"};
  for (const char* c : kWrench) known.insert(c);
  for (const char* c : kPayloadCom) known.insert(c);
  for (const auto& c : t.header) {
    std::string link;
    int axis = 0;
    if (known.count(c) || joints.count(c)) continue;
    if (starts_with(c, "flag_") && c.size() > 5) {
      run.flag_names.push_back(c.substr(5));
      continue;
    }
    if (tilt_column(c, link, axis)) {
      if (!links.empty() && !links.count(link)) {
        std::string all;
        for (const auto& l : robot.body_links) all += (all.empty() ? "" : ", ") + l;
        throw FormatError(where(t.rows(), c), "tilt of link '" + link + "', which the robot's chain does not have (links: " + all + ")");
      }
      run.tilts.push_back({c, link, axis});
      continue;
    }
    std::string best;
    std::size_t best_d = 4;
    for (const auto& k : known)
      if (const auto d = edit_distance(c, k); d < best_d) best_d = d, best = k;
    for (const auto& k : joints)
      if (const auto d = edit_distance(c, k); d < best_d) best_d = d, best = k;
    throw FormatError(where(t.rows(), c), "unknown column" + (best.empty() ? std::string() : " (did you mean '" + best + "'?)") +
                                              "; a calibration run has posture, station, the joints by name, px py pz, rx ry rz, "
                                              "sigma_m, sigma_rad, flag_<name>, tilt_<link>_rx|ry, payload_kg, payload_cx|cy|cz, fx..mz");
  }
  auto all_or_none = [&](const char* const* names, std::size_t n, const char* what) {
    std::size_t present = 0;
    for (std::size_t i = 0; i < n; ++i) present += t.has(names[i]) ? 1 : 0;
    if (present != 0 && present != n)
      for (std::size_t i = 0; i < n; ++i)
        if (!t.has(names[i])) throw FormatError(where(t.rows(), names[i]), std::string("missing: ") + what + " needs all of its columns");
    return present == n;
  };
  run.has_orientation = all_or_none(kRotation, 3, "a measured orientation (rx ry rz)");
  run.has_wrench = all_or_none(kWrench, 6, "an external wrench (fx fy fz mx my mz)");
  run.has_payload = t.has("payload_kg");
  for (const char* c : kPayloadCom)
    if (t.has(c) && !run.has_payload) throw FormatError(where(t.rows(), c), "a payload's centre of mass without payload_kg");
  if (t.has("sigma_rad") && !run.has_orientation)
    throw FormatError(where(t.rows(), "sigma_rad"), "sigma_rad without a measured orientation (rx ry rz)");
  run.has_sigma = t.has("sigma_m");

  const std::size_t nj = robot.joints.size();
  std::set<std::string> ids;
  for (std::size_t r = 0; r < t.rows(); ++r) {
    CalibrationPosture p;
    p.line = t.row_line[r];
    p.id = t.text("posture")[r];
    if (p.id.empty()) throw FormatError(where(r, "posture"), "empty posture id");
    if (!ids.insert(p.id).second) throw FormatError(where(r, "posture"), "posture '" + p.id + "' appears twice");
    p.station = t.has("station") ? t.text("station")[r] : "1";
    if (p.station.empty()) throw FormatError(where(r, "station"), "empty station id");
    if (std::find(run.stations.begin(), run.stations.end(), p.station) == run.stations.end()) run.stations.push_back(p.station);
    p.q.resize(static_cast<Eigen::Index>(nj));
    for (std::size_t j = 0; j < nj; ++j) {
      const auto& spec = robot.joints[j];
      const bool derived = !spec.mimic_of.empty() && !t.has(spec.name);
      const double v = derived ? mimic_value(spec, t, r) : t.numeric(spec.name)[r];
      // A small tolerance: a posture commanded at the limit reads back a hair beyond it.
      constexpr double kSlack = 1e-6;
      if (v < spec.lower - kSlack || v > spec.upper + kSlack) {
        std::ostringstream m;
        m << v << " is outside the joint's limits [" << spec.lower << ", " << spec.upper << "]"
          << (spec.type == JointType::revolute ? " rad (degrees?)" : " m (millimetres?)");
        if (derived) {
          m.str("");
          m << "joint '" << spec.name << "' mimics '" << spec.mimic_of << "': " << spec.mimic_multiplier << " × "
            << t.numeric(spec.mimic_of)[r] << " + " << spec.mimic_offset << " = " << v << " is outside its limits [" << spec.lower << ", "
            << spec.upper << "]";
          throw FormatError(where(r, spec.mimic_of), m.str());
        }
        throw FormatError(where(r, spec.name), m.str());
      }
      p.q[static_cast<Eigen::Index>(j)] = v;
    }
    for (int k = 0; k < 3; ++k) p.p_measured_m[k] = t.numeric(kPoint[k])[r];
    if (run.has_orientation) {
      Eigen::Vector3d rv;
      for (int k = 0; k < 3; ++k) rv[k] = t.numeric(kRotation[k])[r];
      if (rv.norm() > 3.141592653589793 + 1e-9)
        throw FormatError(where(r, "rx"), "a rotation vector longer than π: give the shorter rotation (rad, not degrees?)");
      p.r_measured_rad = rv;
    }
    if (run.has_sigma) {
      p.sigma_m = t.numeric("sigma_m")[r];
      if (!(p.sigma_m > 0.0)) throw FormatError(where(r, "sigma_m"), "a standard deviation must be > 0");
    }
    if (t.has("sigma_rad")) {
      p.sigma_rad = t.numeric("sigma_rad")[r];
      if (!(p.sigma_rad > 0.0)) throw FormatError(where(r, "sigma_rad"), "a standard deviation must be > 0");
    }
    for (const auto& f : run.flag_names) {
      const double v = t.numeric("flag_" + f)[r];
      if (v != 0.0 && v != 1.0) throw FormatError(where(r, "flag_" + f), "a flag is 0 or 1");
      p.flags.push_back(v == 1.0);
    }
    for (const auto& tc : run.tilts) {
      const double v = t.numeric(tc.column)[r];
      if (std::abs(v) > 0.5)
        throw FormatError(where(r, tc.column), "a tilt beyond 0.5 rad: an inclinometer's reading is in rad (degrees?)");
      p.tilts_rad.push_back(v);
    }
    if (run.has_payload) {
      p.payload_kg = t.numeric("payload_kg")[r];
      if (!(p.payload_kg >= 0.0)) throw FormatError(where(r, "payload_kg"), "a payload's mass must be >= 0");
      for (int k = 0; k < 3; ++k)
        if (t.has(kPayloadCom[k])) p.payload_com_m[k] = t.numeric(kPayloadCom[k])[r];
    }
    if (run.has_wrench) {
      Eigen::Matrix<double, 6, 1> w;
      for (int k = 0; k < 6; ++k) w[k] = t.numeric(kWrench[k])[r];
      p.wrench = w;
    }
    run.postures.push_back(std::move(p));
  }
  return run;
}

CalibrationRun read_calibration_run(const std::string& path, const RobotSpec& robot) {
  std::ifstream in(path);
  if (!in) throw FormatError({path, 0, 0, ""}, "cannot open the calibration run");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_calibration_run(ss.str(), path, robot);
}

}  // namespace hil::format
