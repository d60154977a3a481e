#include <hil/models/stiffness_model.hpp>

#include <fmt/format.h>

#include <cmath>
#include <fstream>

#include <hil/error/error.hpp>
#include <hil/calibration/experiment.hpp>
#include <hil/format/output.hpp>

namespace hil::models {
namespace hc = hil::calibration;
using error::FormatError;

nlohmann::json load_json(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw FormatError({path, 0, 0, ""}, "cannot open file");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw FormatError({path, 0, 0, ""}, fmt::format("not valid JSON (byte {}): {}", e.byte, e.what()));
  }
}

namespace {

double number(const nlohmann::json& j, const std::string& file, const std::string& field) {
  if (!j.is_number()) throw FormatError({file, 0, 0, field}, "expected a number");
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw FormatError({file, 0, 0, field}, "expected a finite number");
  return v;
}

double positive(const nlohmann::json& obj, const char* key, const std::string& file, const std::string& field) {
  if (!obj.contains(key)) throw FormatError({file, 0, 0, field + "." + key}, "missing");
  const double v = number(obj.at(key), file, field + "." + key);
  if (!(v > 0.0)) throw FormatError({file, 0, 0, field + "." + key}, "must be > 0");
  return v;
}

}  // namespace

hc::ComplianceSet read_springs(const nlohmann::json& springs, const hc::VjmModel& model, const std::string& file) {
  if (!springs.is_object()) throw FormatError({file, 0, 0, "springs"}, "expected an object {\"J1\": ..., \"L2\": ...}");
  hc::ComplianceSet k = model.zero_compliance();
  for (const auto& [name, value] : springs.items()) {
    const std::string field = "springs." + name;
    const int s = model.find(name);
    if (s < 0) throw FormatError({file, 0, 0, field}, fmt::format("unknown spring (the robot has J1..J{0} and L0..L{0})", model.dof()));
    const auto& sp = model.springs()[static_cast<std::size_t>(s)];
    auto& K = k[static_cast<std::size_t>(s)];
    if (sp.kind == hc::SpringKind::joint) {
      K(0, 0) = number(value, file, field);
      if (!(K(0, 0) >= 0.0)) throw FormatError({file, 0, 0, field}, "a joint compliance must be ≥ 0");
      continue;
    }
    if (value.is_array()) {
      if (value.size() != 6) throw FormatError({file, 0, 0, field}, "expected 6 rows of 6 numbers");
      for (std::size_t r = 0; r < 6; ++r) {
        if (!value[r].is_array() || value[r].size() != 6)
          throw FormatError({file, 0, 0, fmt::format("{}[{}]", field, r)}, "expected 6 numbers");
        for (std::size_t c = 0; c < 6; ++c)
          K(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = number(value[r][c], file, fmt::format("{}[{}][{}]", field, r, c));
      }
    } else if (value.is_object() && value.contains("beam")) {
      const auto& b = value.at("beam");
      const std::string bf = field + ".beam";
      // One at a time, in this order, so that the first missing value is the one reported.
      const double L = positive(b, "length_m", file, bf);
      const double EA = positive(b, "EA_n", file, bf);
      const double EIy = positive(b, "EIy_nm2", file, bf);
      const double EIz = positive(b, "EIz_nm2", file, bf);
      const double GJ = positive(b, "GJ_nm2", file, bf);
      K = hc::beam_compliance(L, EA, EIy, EIz, GJ);
    } else if (value.is_object()) {
      for (const auto& [key, v] : value.items()) {
        if (key == "diagonal") {
          if (!v.is_array() || v.size() != 6) throw FormatError({file, 0, 0, field + ".diagonal"}, "expected 6 numbers");
          for (std::size_t i = 0; i < 6; ++i)
            K(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)) = number(v[i], file, fmt::format("{}.diagonal[{}]", field, i));
        } else if (key.size() == 3 && key[0] == 'k' && key[1] >= '1' && key[1] <= '6' && key[2] >= '1' && key[2] <= '6') {
          const int r = key[1] - '1', c = key[2] - '1';
          K(r, c) = K(c, r) = number(v, file, field + "." + key);
        } else {
          throw FormatError({file, 0, 0, field + "." + key}, "unknown key: expected diagonal or kRC (R, C in 1..6, symmetric)");
        }
      }
    } else {
      throw FormatError({file, 0, 0, field}, "expected a 6x6 array, {\"beam\": {...}} or {\"diagonal\": [...], \"kRC\": v}");
    }
  }
  return k;
}

nlohmann::json springs_to_json(const hc::VjmModel& model, const hc::ComplianceSet& k) {
  nlohmann::json j = nlohmann::json::object();
  for (std::size_t s = 0; s < k.size(); ++s) {
    const auto& sp = model.springs()[s];
    if (sp.kind == hc::SpringKind::joint) {
      j[sp.name] = k[s](0, 0);
    } else {
      nlohmann::json rows = nlohmann::json::array();
      for (int r = 0; r < 6; ++r) {
        nlohmann::json row = nlohmann::json::array();
        for (int c = 0; c < 6; ++c) row.push_back(k[s](r, c));
        rows.push_back(row);
      }
      j[sp.name] = rows;
    }
  }
  return j;
}

const char* convention_name(hc::DhConvention c) {
  return c == hc::DhConvention::standard ? "standard" : c == hc::DhConvention::modified ? "modified" : "urdf";
}

nlohmann::json pose_to_json(const Eigen::Isometry3d& T) {
  const Eigen::Matrix4d M = T.matrix();
  nlohmann::json m = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) m.push_back({M(r, 0), M(r, 1), M(r, 2), M(r, 3)});
  return m;
}

Eigen::Isometry3d pose_from_json(const nlohmann::json& m) {
  Eigen::Matrix4d M;
  for (int rr = 0; rr < 4; ++rr)
    for (int c = 0; c < 4; ++c) M(rr, c) = m.at(static_cast<std::size_t>(rr)).at(static_cast<std::size_t>(c)).get<double>();
  Eigen::Isometry3d T;
  T.matrix() = M;
  return T;
}

nlohmann::json robot_to_json(const hc::SerialRobot& robot) {
  nlohmann::json j;
  j["name"] = robot.name;
  j["convention"] = convention_name(robot.convention);
  j["joints"] = nlohmann::json::array();
  for (const auto& r : robot.joints) {
    nlohmann::json row = {{"name", r.name},   {"type", r.kind == hc::JointKind::revolute ? "revolute" : "prismatic"},
                          {"a_m", r.a_m},     {"alpha_rad", r.alpha_rad},
                          {"d_m", r.d_m},     {"theta_offset_rad", r.theta_offset_rad},
                          {"lower", r.lower}, {"upper", r.upper}};
    if (robot.convention == hc::DhConvention::urdf) {
      row["T_parent_joint"] = pose_to_json(r.T_parent_joint);
      row["axis"] = {r.axis.x(), r.axis.y(), r.axis.z()};
      if (r.mimic_master >= 0)
        row["mimic"] = {{"joint", robot.joints[static_cast<std::size_t>(r.mimic_master)].name},
                        {"multiplier", r.mimic_multiplier},
                        {"offset", r.mimic_offset}};
    }
    j["joints"].push_back(row);
  }
  const auto& pose = pose_to_json;
  j["T_world_base"] = pose(robot.T_world_base);
  j["T_flange_ee"] = pose(robot.T_flange_ee);
  return j;
}

hc::SerialRobot robot_from_json(const nlohmann::json& j, const std::string& file) {
  try {
    hc::SerialRobot r;
    r.name = j.at("name").get<std::string>();
    const auto conv = j.at("convention").get<std::string>();
    if (conv != "standard" && conv != "modified" && conv != "urdf")
      throw FormatError({file, 0, 0, "robot.convention"}, "expected standard, modified or urdf");
    r.convention = conv == "standard"   ? hc::DhConvention::standard
                   : conv == "modified" ? hc::DhConvention::modified
                                        : hc::DhConvention::urdf;
    for (const auto& jr : j.at("joints")) {
      hc::DhRow row;
      row.name = jr.at("name").get<std::string>();
      row.kind = jr.at("type").get<std::string>() == "prismatic" ? hc::JointKind::prismatic : hc::JointKind::revolute;
      row.a_m = jr.at("a_m").get<double>();
      row.alpha_rad = jr.at("alpha_rad").get<double>();
      row.d_m = jr.at("d_m").get<double>();
      row.theta_offset_rad = jr.at("theta_offset_rad").get<double>();
      row.lower = jr.at("lower").get<double>();
      row.upper = jr.at("upper").get<double>();
      if (r.convention == hc::DhConvention::urdf) {
        row.T_parent_joint = pose_from_json(jr.at("T_parent_joint"));
        const auto& a = jr.at("axis");
        row.axis = Eigen::Vector3d(a.at(0).get<double>(), a.at(1).get<double>(), a.at(2).get<double>());
        if (!(std::abs(row.axis.norm() - 1.0) < 1e-9))
          throw FormatError({file, 0, 0, "robot.joints." + row.name + ".axis"}, "the axis is not a unit vector");
      }
      r.joints.push_back(row);
    }
    // Mimic records name their master, which may come later in the file: resolved once all are read.
    for (std::size_t i = 0; i < r.joints.size(); ++i) {
      const auto& jr = j.at("joints").at(i);
      if (r.convention != hc::DhConvention::urdf || !jr.contains("mimic")) continue;
      const auto& m = jr.at("mimic");
      const auto master = m.at("joint").get<std::string>();
      const std::string where = "robot.joints." + r.joints[i].name + ".mimic";
      for (std::size_t k = 0; k < r.joints.size(); ++k)
        if (r.joints[k].name == master && k != i && !j.at("joints").at(k).contains("mimic")) r.joints[i].mimic_master = static_cast<int>(k);
      if (r.joints[i].mimic_master < 0) throw FormatError({file, 0, 0, where}, "'" + master + "' is not an independent joint of the chain");
      r.joints[i].mimic_multiplier = m.at("multiplier").get<double>();
      r.joints[i].mimic_offset = m.at("offset").get<double>();
      if (!std::isfinite(r.joints[i].mimic_multiplier) || !std::isfinite(r.joints[i].mimic_offset))
        throw FormatError({file, 0, 0, where}, "the multiplier and offset must be numbers");
    }
    auto pose = [&](const char* key) { return pose_from_json(j.at(key)); };
    r.T_world_base = pose("T_world_base");
    r.T_flange_ee = pose("T_flange_ee");
    if (r.joints.empty()) throw FormatError({file, 0, 0, "robot.joints"}, "no joints");
    return r;
  } catch (const nlohmann::json::exception& e) {
    throw FormatError({file, 0, 0, "robot"}, std::string("bad robot description: ") + e.what());
  }
}

namespace {

nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

const char* const kAxis[] = {"dx", "dy", "dz", "rx", "ry", "rz"};

}  // namespace

void check_model_format(const nlohmann::json& j, const std::string& file, bool required) {
  const std::string want = "hil.stiffness_model";
  if (!j.is_object()) throw FormatError({file, 0, 0, ""}, "expected a JSON object (a " + want + " file)");
  if (!j.contains("format")) {
    if (required)
      throw FormatError({file, 0, 0, "format"},
                        "not a stiffness model: no \"format\": \"" + want + "\" (write one with `hil stiffness identify --json`)");
    return;
  }
  const auto& f = j.at("format");
  const std::string kind = f.is_string() ? f.get<std::string>() : f.dump();
  if (kind != want && kind != "hil-stiffness-model")
    throw FormatError({file, 0, 0, "format"},
                      "this is a '" + kind + "' file, not a stiffness model (" + want + ", written by `hil stiffness identify --json`)");
  if (j.contains("format_version")) {
    const auto& v = j.at("format_version");
    if (!v.is_number_integer() || v.get<long>() < 1 || v.get<long>() > format::kJsonFormatVersion)
      throw FormatError({file, 0, 0, "format_version"},
                        fmt::format("expected 1 to {} (this hil's version of {}), found {}", format::kJsonFormatVersion, want, v.dump()));
  }
}

nlohmann::json result_to_json(const hc::VjmModel& model, const hc::CalibrationResult& r) {
  nlohmann::json j;
  format::tag_format(j, "stiffness_model");
  j["version"] = format::kJsonFormatVersion;  // the key of files before "format_version", kept for their readers
  j["parameters"] = nlohmann::json::array();
  for (const auto& p : r.kept)
    j["parameters"].push_back({{"name", p.parameter.name},
                               {"value", p.value},
                               {"std", number_or_null(p.std_dev)},
                               {"ci95", {number_or_null(p.ci95_low), number_or_null(p.ci95_high)}},
                               {"pnr", number_or_null(p.pnr)},
                               {"class", hc::to_string(p.cls)}});
  j["fixed"] = nlohmann::json::array();
  for (const auto& f : r.fixed) j["fixed"].push_back({{"name", f.parameter.name}, {"value", f.value}, {"step", f.step}});
  j["reduction"] = nlohmann::json::array();
  for (const auto& l : r.reduction) {
    nlohmann::json row = {{"step", l.step}, {"description", l.description}, {"count", l.count}};
    if (l.rank >= 0) row["rank"] = l.rank;
    const auto pc = hc::paper_count(l.step);
    if (!pc.empty()) row["paper"] = pc;
    j["reduction"].push_back(row);
  }
  j["rank"] = r.rank_final;
  j["rank_physical"] = r.rank_physical;
  j["rank_algebraic"] = r.rank_algebraic;
  j["condition"] = number_or_null(r.solution.condition);
  // Singular values of the column-scaled weighted observation matrix: of the physical (M3) set,
  // whose count above the tolerance is its rank, and of the final set.
  j["singular_values_physical"] = std::vector<double>(r.partition.singular_values.data(),
                                                      r.partition.singular_values.data() + r.partition.singular_values.size());
  j["singular_values"] = std::vector<double>(r.solution.singular_values.data(),
                                             r.solution.singular_values.data() + r.solution.singular_values.size());
  j["sigma0_sq"] = number_or_null(r.solution.sigma0_sq);
  j["measurements"] = r.measurements;
  j["equations"] = r.equations;
  j["residual_rms"] = nlohmann::json::object();
  for (std::size_t a = 0; a < 6; ++a)
    if (r.residual_rows[a] > 0) j["residual_rms"][kAxis[a]] = r.residual_rms[a];
  j["noise"] = {{"position_m", r.noise.position_m}, {"rotation_rad", r.noise.rotation_rad}, {"estimated", r.noise_estimated}};
  j["spd"] = nlohmann::json::array();
  for (const auto& c : r.spd)
    j["spd"].push_back({{"spring", c.spring},
                        {"symmetric", c.symmetric},
                        {"positive_definite", c.positive_definite},
                        {"min_eigenvalue", c.min_eigenvalue},
                        {"max_eigenvalue", c.max_eigenvalue}});
  j["springs"] = springs_to_json(model, r.compliance);
  j["robot"] = robot_to_json(model.robot());
  return j;
}

ModelFile read_model_file(const std::string& path, const hc::SerialRobot* robot) {
  const auto j = load_json(path);
  check_model_format(j, path, false);
  if (!j.is_object() || !j.contains("springs")) throw FormatError({path, 0, 0, "springs"}, "a model file needs a \"springs\" object");
  hc::SerialRobot r;
  if (robot) r = *robot;
  else if (j.contains("robot")) r = robot_from_json(j.at("robot"), path);
  else throw FormatError({path, 0, 0, "robot"}, "no robot in the model file: give --rig");
  hc::VjmModel model(r);
  auto k = read_springs(j.at("springs"), model, path);
  return {std::move(model), std::move(k)};
}

hc::ComplianceSet read_truth_file(const std::string& path, const hc::VjmModel& model) {
  const auto j = load_json(path);
  check_model_format(j, path, false);
  if (!j.is_object() || !j.contains("springs")) throw FormatError({path, 0, 0, "springs"}, "a truth file needs a \"springs\" object");
  return read_springs(j.at("springs"), model, path);
}

ReducedModel read_reduced_model(const std::string& path, const hc::VjmModel& model) {
  const auto j = load_json(path);
  check_model_format(j, path, true);
  const auto all = hc::m1_symmetrise(hc::complete_parameters(model));
  auto lookup = [&](const nlohmann::json& e, const char* list) {
    const std::string name = e.at("name").get<std::string>();
    const int i = hc::find_parameter(all, name);
    if (i < 0) throw FormatError({path, 0, 0, std::string(list) + ".name"}, "unknown parameter '" + name + "'");
    return all[static_cast<std::size_t>(i)];
  };
  ReducedModel m;
  std::vector<double> values;
  try {
    for (const auto& e : j.at("parameters")) m.free.push_back(lookup(e, "parameters"));
    for (const auto& e : j.at("fixed")) {
      m.fixed.push_back(lookup(e, "fixed"));
      values.push_back(e.at("value").get<double>());
    }
  } catch (const nlohmann::json::exception& e) {
    throw FormatError({path, 0, 0, "parameters"}, std::string("not an identify --json model: ") + e.what());
  }
  m.fixed_values = Eigen::Map<Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
  return m;
}

}  // namespace hil::models
