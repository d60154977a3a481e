#include <hil/models/contact.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>

#include <hil/format/csv.hpp>
#include <hil/error/error.hpp>
#include <hil/format/yaml.hpp>
#include <hil/so3/so3.hpp>

namespace hil::models {

namespace cid = hil::contact_id;
using error::FormatError;

namespace {

/// "ee" or "world": where the frame chain of `frame` ends.
std::string root_of(const format::RigSpec& rig, const std::string& frame) {
  std::string f = frame;
  for (int guard = 0; guard < 64; ++guard) {
    if (f == "world" || f == "ee") return f;
    const auto* fs = rig.frame(f);
    if (!fs) throw FormatError({rig.source, 0, 0, "frames"}, "unknown frame '" + f + "'");
    f = fs->parent;
  }
  throw FormatError({rig.source, 0, 0, "frames"}, "frame chain of '" + frame + "' does not end at world or ee");
}

}  // namespace

cid::Scene scene_from_rig(const format::RigSpec& rig) {
  cid::Scene s;
  int held = -1, fixed = -1;
  for (std::size_t i = 0; i < rig.objects.size(); ++i) {
    const auto root = root_of(rig, rig.objects[i].frame);
    if (root == "ee") {
      if (held >= 0)
        throw FormatError({rig.source, 0, 0, "objects"},
                          "contact identification needs exactly one object held by the end effector; found '" +
                              rig.objects[static_cast<std::size_t>(held)].name + "' and '" + rig.objects[i].name + "'");
      held = static_cast<int>(i);
    } else {
      if (fixed >= 0)
        throw FormatError({rig.source, 0, 0, "objects"}, "contact identification needs exactly one fixed object; found '" +
                                                             rig.objects[static_cast<std::size_t>(fixed)].name + "' and '" +
                                                             rig.objects[i].name + "'");
      fixed = static_cast<int>(i);
    }
  }
  if (held < 0 || fixed < 0)
    throw FormatError({rig.source, 0, 0, "objects"},
                      "contact identification needs one object on the end effector (frame chain ending at 'ee') and one fixed object");
  const int idx[2] = {held, fixed};
  for (int b = 0; b < 2; ++b) {
    const auto& o = rig.objects[static_cast<std::size_t>(idx[b])];
    auto& body = s.bodies[static_cast<std::size_t>(b)];
    body.name = o.name;
    body.on_end_effector = b == 0;
    body.T_attach = b == 0 ? rig.T_ee(o.frame) : rig.T_world(o.frame);
    for (const auto& f : o.features) {
      cid::Feature feat;
      feat.name = f.name;
      for (const auto& p : f.polyhedra) {
        try {
          feat.polyhedra.push_back(cid::Polyhedron::from_vertices(p.vertices_m));
        } catch (const std::invalid_argument& e) {
          throw FormatError({rig.source, p.line, 0, "objects." + o.name + "." + f.name}, e.what());
        }
      }
      body.features.push_back(std::move(feat));
    }
  }
  for (const auto& u : rig.model.uncertainties) {
    cid::Uncertainty cu;
    cu.name = u.name;
    cu.body = u.object == rig.objects[static_cast<std::size_t>(held)].name ? 0 : 1;
    if (cu.body == 1 && u.object != rig.objects[static_cast<std::size_t>(fixed)].name)
      throw FormatError({rig.source, 0, 0, "model.uncertainties." + u.name}, "unknown object '" + u.object + "'");
    const auto& feats = s.bodies[static_cast<std::size_t>(cu.body)].features;
    cu.feature = -1;
    for (std::size_t f = 0; f < feats.size(); ++f)
      if (feats[f].name == u.feature) cu.feature = static_cast<int>(f);
    if (cu.feature < 0) throw FormatError({rig.source, 0, 0, "model.uncertainties." + u.name}, "unknown feature '" + u.feature + "'");
    cu.kind = u.kind == format::UncertaintySpec::Kind::translation ? cid::Uncertainty::Kind::translation : cid::Uncertainty::Kind::rotation;
    if (!(u.axis.norm() > 0.0)) throw FormatError({rig.source, 0, 0, "model.uncertainties." + u.name + ".axis"}, "axis must not be zero");
    cu.axis = u.axis.normalized();
    cu.point = u.point_m;
    cu.design_value = u.design_value;
    cu.prior_std = u.prior_std;
    s.uncertainties.push_back(cu);
  }
  if (rig.frame("force_plate")) s.T_world_fp = rig.T_world("force_plate");
  return s;
}

cid::ContactModel model_from_rig(const format::RigSpec& rig) {
  if (!rig.model.contact) throw FormatError({rig.source, 0, 0, "model.contact"}, "the rig has no contact model (model.contact)");
  const auto& c = *rig.model.contact;
  cid::ContactModel m{c.stiffness_n_per_m, c.friction_coefficient, c.sticking_threshold_m_per_s};
  try {
    m.check();
  } catch (const std::invalid_argument& e) {
    throw FormatError({rig.source, 0, 0, "model.contact"}, e.what());
  }
  return m;
}

cid::Measurement measurement(const format::Sample& s) {
  cid::Measurement m;
  m.t_s = s.t_s;
  m.kin.T_world_ee.linear() = s.q_world_ee.normalized().toRotationMatrix();
  m.kin.T_world_ee.translation() = s.p_world_ee_m;
  m.kin.v_world_ee = s.v_world_ee_m_per_s;
  m.kin.w_world_ee = s.w_world_ee_rad_per_s;
  m.w_fp << s.f_fp_n, s.m_fp_nm;
  return m;
}

format::Sample sample(const cid::Measurement& m) {
  format::Sample s;
  s.t_s = m.t_s;
  s.p_world_ee_m = m.kin.T_world_ee.translation();
  s.q_world_ee = Eigen::Quaterniond(m.kin.T_world_ee.linear());
  s.v_world_ee_m_per_s = m.kin.v_world_ee;
  s.w_world_ee_rad_per_s = m.kin.w_world_ee;
  s.f_fp_n = m.w_fp.head<3>();
  s.m_fp_nm = m.w_fp.tail<3>();
  return s;
}

std::vector<cid::Measurement> measurements(const format::SampleTable& t) {
  std::vector<cid::Measurement> out;
  out.reserve(t.size());
  for (const auto& s : t.samples) out.push_back(measurement(s));
  return out;
}

Trajectory read_trajectory(const std::string& path) {
  format::CsvOptions o;
  o.required = {"t", "px", "py", "pz", "qw", "qx", "qy", "qz"};
  o.numeric_if_present = [](const std::string& c) { return c == "vx" || c == "vy" || c == "vz" || c == "wx" || c == "wy" || c == "wz"; };
  const auto csv = format::read_csv(path, o);
  const auto n = csv.rows();
  if (n < 2) throw FormatError({path, 0, 0, ""}, "a trajectory needs at least two rows");
  const bool vel = csv.has("vx") && csv.has("vy") && csv.has("vz") && csv.has("wx") && csv.has("wy") && csv.has("wz");
  Trajectory tr;
  const auto& t = csv.numeric("t");
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0 && !(t[i] > t[i - 1])) throw FormatError({path, csv.row_line[i], 0, "t"}, "time must increase strictly");
    Eigen::Quaterniond q(csv.numeric("qw")[i], csv.numeric("qx")[i], csv.numeric("qy")[i], csv.numeric("qz")[i]);
    if (std::abs(q.norm() - 1.0) > 1e-6) throw FormatError({path, csv.row_line[i], 0, "qw"}, "quaternion is not unit length");
    cid::Kinematics k;
    k.T_world_ee.linear() = q.normalized().toRotationMatrix();
    k.T_world_ee.translation() = Eigen::Vector3d(csv.numeric("px")[i], csv.numeric("py")[i], csv.numeric("pz")[i]);
    if (vel) {
      k.v_world_ee = Eigen::Vector3d(csv.numeric("vx")[i], csv.numeric("vy")[i], csv.numeric("vz")[i]);
      k.w_world_ee = Eigen::Vector3d(csv.numeric("wx")[i], csv.numeric("wy")[i], csv.numeric("wz")[i]);
    }
    tr.t.push_back(t[i]);
    tr.kin.push_back(k);
  }
  if (!vel) {
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t a = i == 0 ? 0 : i - 1, b = i + 1 < n ? i + 1 : n - 1;
      const double dt = tr.t[b] - tr.t[a];
      tr.kin[i].v_world_ee = (tr.kin[b].T_world_ee.translation() - tr.kin[a].T_world_ee.translation()) / dt;
      tr.kin[i].w_world_ee = so3::log(Eigen::Matrix3d(tr.kin[b].T_world_ee.linear() * tr.kin[a].T_world_ee.linear().transpose())) / dt;
    }
  }
  return tr;
}

namespace {

Truth truth_from(const YAML::Node& doc, const std::string& path, const format::RigSpec& rig) {
  Truth t;
  t.model = model_from_rig(rig);
  if (!doc.IsDefined() || doc.IsNull()) return t;  // an empty truth: the rig's nominal model
  const format::YamlNode root(doc, "", &path);
  root.only({"stiffness_n_per_m", "friction_coefficient", "sticking_threshold_m_per_s", "sensor", "geometric"});
  const auto non_negative = [](const format::YamlNode& n) {
    const double v = n.num();
    if (v < 0.0) n.fail("expected a number >= 0, found " + n.raw().Scalar());
    return v;
  };
  if (root.has("stiffness_n_per_m")) t.model.K = root.child("stiffness_n_per_m").num_positive();
  if (root.has("friction_coefficient")) t.model.mu = non_negative(root.child("friction_coefficient"));
  if (root.has("sticking_threshold_m_per_s")) t.model.v_tm = root.child("sticking_threshold_m_per_s").num_positive();
  if (root.has("sensor")) {
    const auto s = root.child("sensor");
    s.only({"position_resolution_m", "velocity_resolution_m_per_s", "force_resolution_n", "moment_resolution_nm", "force_noise_n",
            "moment_noise_nm", "seed"});
    t.sensor.position_resolution_m = s.has("position_resolution_m") ? non_negative(s.child("position_resolution_m")) : 0.0;
    t.sensor.velocity_resolution_m_per_s = s.has("velocity_resolution_m_per_s") ? non_negative(s.child("velocity_resolution_m_per_s"))
                                                                                : 0.0;
    t.sensor.force_resolution_n = s.has("force_resolution_n") ? non_negative(s.child("force_resolution_n")) : 0.0;
    t.sensor.moment_resolution_nm = s.has("moment_resolution_nm") ? non_negative(s.child("moment_resolution_nm")) : 0.0;
    t.sensor.force_noise_n = s.has("force_noise_n") ? non_negative(s.child("force_noise_n")) : 0.0;
    t.sensor.moment_noise_nm = s.has("moment_noise_nm") ? non_negative(s.child("moment_noise_nm")) : 0.0;
    if (s.has("seed")) {
      const auto n = s.child("seed");
      const long seed = n.integer();
      if (seed < 0 || seed > static_cast<long>(std::numeric_limits<unsigned>::max()))
        n.fail("expected a seed from 0 to " + std::to_string(std::numeric_limits<unsigned>::max()));
      t.sensor.seed = static_cast<unsigned>(seed);
    }
  }
  if (root.has("geometric")) {
    const auto g = root.child("geometric");
    for (const auto& name : g.keys()) t.geometric[name] = g.child(name).num();
  }
  try {
    t.model.check();
  } catch (const std::invalid_argument& e) {
    throw FormatError({path, 0, 0, ""}, e.what());
  }
  return t;
}

}  // namespace

Truth read_truth(const std::string& path, const format::RigSpec& rig) { return truth_from(format::load_yaml_file(path), path, rig); }

Truth parse_truth(const std::string& yaml_text, const std::string& display_name, const format::RigSpec& rig) {
  return truth_from(format::load_yaml(yaml_text, display_name), display_name, rig);
}

Eigen::VectorXd uncertainty_vector(const cid::Scene& s, const std::map<std::string, double>& values, const std::string& where) {
  Eigen::VectorXd x = s.design();
  for (const auto& [name, v] : values) {
    bool found = false;
    for (std::size_t j = 0; j < s.uncertainties.size(); ++j)
      if (s.uncertainties[j].name == name) {
        x[static_cast<Eigen::Index>(j)] = v;
        found = true;
      }
    if (!found) throw std::runtime_error(where + ": unknown geometric uncertainty '" + name + "' (not in the rig's model.uncertainties)");
  }
  return x;
}

}  // namespace hil::models
