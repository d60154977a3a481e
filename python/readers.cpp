// read_samples / read_run / read_rig: the project's strict readers (every error names file, line,
// column or field), their results as numpy arrays and dicts. Docs: docs/python.md.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>  // paths as str or os.PathLike

#include <cmath>
#include <cstdint>

#include "bindings.hpp"
#include "convert.hpp"
#include <hil/format/csv.hpp>
#include <hil/format/run.hpp>

namespace hil::python {

namespace fmt_ = hil::format;

namespace {

py::dict pose_dict(const fmt_::Pose& p) {
  py::dict d;
  d["translation_m"] = array(p.translation_m);
  const auto& q = p.rotation;
  d["rotation_wxyz"] = column(4, [&](std::size_t i) { return i == 0 ? q.w() : q.vec()[static_cast<Eigen::Index>(i - 1)]; });
  d["matrix"] = homogeneous(p.isometry());
  return d;
}

/// The extra (unknown) columns' values: the sample reader keeps only their names, so the file is
/// read again by the same CSV reader with every column as text. A column whose cells are all
/// finite numbers becomes a float array, any other a list of strings.
py::dict extra_columns(const fmt_::SampleTable& t) {
  py::dict d;
  if (t.extra_columns.empty()) return d;
  fmt_::CsvOptions o;
  o.display_name = t.file;
  const auto csv = fmt_::read_csv(t.file, o);
  for (const auto& name : t.extra_columns) {
    const auto& cells = csv.text(name);
    std::vector<double> v;
    for (const auto& c : cells) {
      std::size_t used = 0;
      double x = NAN;
      try {
        x = std::stod(c, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != c.size() || c.empty() || !std::isfinite(x)) break;
      v.push_back(x);
    }
    if (v.size() == cells.size()) d[py::str(name)] = array(v);
    else d[py::str(name)] = py::cast(cells);
  }
  return d;
}

py::dict samples_dict(const fmt_::SampleTable& t) {
  const auto n = t.size();
  const auto& s = t.samples;
  auto rows3 = [&](auto member) {
    return matrix(n, 3, [&](std::size_t i, std::size_t c) { return (s[i].*member)[static_cast<Eigen::Index>(c)]; });
  };
  py::dict d;
  d["file"] = t.file;
  d["t"] = column(n, [&](std::size_t i) { return s[i].t_s; });
  d["p"] = rows3(&fmt_::Sample::p_world_ee_m);
  d["q"] = matrix(n, 4, [&](std::size_t i, std::size_t c) {
    const auto& q = s[i].q_world_ee;
    return c == 0 ? q.w() : q.vec()[static_cast<Eigen::Index>(c - 1)];
  });
  d["v"] = rows3(&fmt_::Sample::v_world_ee_m_per_s);
  d["w"] = rows3(&fmt_::Sample::w_world_ee_rad_per_s);
  d["f"] = rows3(&fmt_::Sample::f_fp_n);
  d["m"] = rows3(&fmt_::Sample::m_fp_nm);
  d["joints"] = array(t.joints_rad);
  std::vector<std::string> joint_names;
  for (std::size_t j = 1; j <= t.joint_count(); ++j) joint_names.push_back("j" + std::to_string(j));
  std::vector<std::string> columns = fmt_::sample_columns();
  columns.insert(columns.end(), joint_names.begin(), joint_names.end());
  columns.insert(columns.end(), t.extra_columns.begin(), t.extra_columns.end());
  d["joint_names"] = joint_names;
  d["columns"] = columns;
  d["extra"] = extra_columns(t);
  py::array_t<std::int64_t> line(static_cast<py::ssize_t>(t.line.size()));
  for (std::size_t i = 0; i < t.line.size(); ++i) line.mutable_at(static_cast<py::ssize_t>(i)) = static_cast<std::int64_t>(t.line[i]);
  d["line"] = line;
  return d;
}

py::dict meta_dict(const fmt_::RunInfo& info) {
  py::dict d;
  d["format_version"] = info.format_version;
  d["rig"] = info.rig;
  d["start_time"] = info.start_time_utc;
  d["output_rate_hz"] = info.output_rate_hz;
  py::list sources;
  for (const auto& s : info.sources) {
    py::dict x;
    x["name"] = s.name;
    x["kind"] = s.kind;
    x["rate_hz"] = s.rate_hz;
    x["raw"] = s.raw;
    py::dict identity;  // in the recorded order
    for (const auto& [key, value] : s.identity) identity[py::str(key)] = value;
    x["identity"] = identity;
    sources.append(x);
  }
  d["sources"] = sources;
  d["notes"] = info.notes;
  return d;
}

py::dict robot_dict(const fmt_::RobotSpec& r) {
  py::dict d;
  d["name"] = r.name;
  d["convention"] = fmt_::convention_name(r.convention);
  if (r.convention == fmt_::DhConvention::urdf) {
    d["urdf"] = r.urdf_file;
    d["base_link"] = r.base_link;
    d["tip_link"] = r.tip_link;
    d["body_links"] = r.body_links;
    d["masses_kg"] = matrix(r.inertials.size(), 1, [&](std::size_t i, std::size_t) { return r.inertials[i].mass_kg; });
  }
  py::list joints;
  for (const auto& j : r.joints) {
    py::dict x;
    x["name"] = j.name;
    x["type"] = j.type == fmt_::JointType::revolute ? "revolute" : "prismatic";
    x["a_m"] = j.a_m;
    x["alpha_rad"] = j.alpha_rad;
    x["d_m"] = j.d_m;
    x["theta_offset_rad"] = j.theta_offset_rad;
    x["lower"] = j.lower;
    x["upper"] = j.upper;
    if (r.convention == fmt_::DhConvention::urdf) {
      x["T_parent_joint"] = pose_dict(j.T_parent_joint);
      x["axis"] = std::vector<double>{j.axis.x(), j.axis.y(), j.axis.z()};
      if (!j.mimic_of.empty()) {
        py::dict m;
        m["joint"] = j.mimic_of;
        m["multiplier"] = j.mimic_multiplier;
        m["offset"] = j.mimic_offset;
        x["mimic"] = m;
      }
    }
    joints.append(x);
  }
  d["joints"] = joints;
  const auto nj = r.joints.size();
  // The DH table as one array, columns named by dh_columns.
  d["dh"] = matrix(nj, 4, [&](std::size_t i, std::size_t c) {
    const auto& j = r.joints[i];
    return c == 0 ? j.a_m : c == 1 ? j.alpha_rad : c == 2 ? j.d_m : j.theta_offset_rad;
  });
  d["dh_columns"] = std::vector<std::string>{"a_m", "alpha_rad", "d_m", "theta_offset_rad"};
  d["limits"] = matrix(nj, 2, [&](std::size_t i, std::size_t c) { return c == 0 ? r.joints[i].lower : r.joints[i].upper; });
  d["T_world_base"] = pose_dict(r.T_world_base);
  d["T_flange_ee"] = pose_dict(r.T_flange_ee);
  return d;
}

py::list objects_list(const std::vector<fmt_::ObjectSpec>& objects) {
  py::list out;
  for (const auto& o : objects) {
    py::dict x;
    x["name"] = o.name;
    x["frame"] = o.frame;
    py::list features;
    for (const auto& f : o.features) {
      py::dict fd;
      fd["name"] = f.name;
      py::list polyhedra;
      for (const auto& p : f.polyhedra)
        polyhedra.append(matrix(p.vertices_m.size(), 3,
                                [&](std::size_t i, std::size_t c) { return p.vertices_m[i][static_cast<Eigen::Index>(c)]; }));
      fd["polyhedra"] = polyhedra;
      features.append(fd);
    }
    x["features"] = features;
    out.append(x);
  }
  return out;
}

py::dict devices_dict(const fmt_::DevicesSpec& dev) {
  py::dict d;
  d["force_plate"] = py::none();
  d["robot"] = py::none();
  if (dev.force_plate) {
    const auto& fp = *dev.force_plate;
    py::dict x;
    x["protocol"] = fp.protocol;
    x["interface"] = fp.interface;
    x["base_id"] = fp.base_id;
    x["rate_hz"] = fp.rate_hz;
    x["T_fp_sensor"] = pose_dict(fp.T_fp_sensor);
    py::list signals;
    for (const auto& s : fp.signals) {
      py::dict sd;
      sd["component"] = s.component;
      sd["frame_id"] = s.frame_id;
      sd["extended_id"] = s.extended_id;
      sd["start_bit"] = s.start_bit;
      sd["length_bits"] = s.length_bits;
      sd["signed"] = s.is_signed;
      sd["big_endian"] = s.big_endian;
      sd["scale"] = s.scale;
      sd["offset"] = s.offset;
      signals.append(sd);
    }
    x["signals"] = signals;
    x["saturation_limits"] = array(fp.saturation_limits);
    x["gain_tolerance"] = fp.gain_tolerance;
    d["force_plate"] = x;
  }
  if (dev.robot) {
    const auto& r = *dev.robot;
    py::dict x;
    x["transport"] = r.transport;
    x["host"] = r.host;
    x["port"] = r.port;
    x["unit_id"] = r.unit_id;
    x["serial_device"] = r.serial_device;
    x["baud"] = r.baud;
    x["parity"] = std::string(1, r.parity);
    x["data_bits"] = r.data_bits;
    x["stop_bits"] = r.stop_bits;
    x["rate_hz"] = r.rate_hz;
    x["timeout_s"] = r.timeout_s;
    x["register_map"] = r.register_map;
    py::list regs;
    for (const auto& e : r.registers) {
      py::dict rd;
      rd["quantity"] = e.quantity;
      rd["address"] = e.address;
      rd["table"] = e.table;
      rd["type"] = e.type;
      rd["word_order"] = e.word_order;
      rd["scale"] = e.scale;
      rd["offset"] = e.offset;
      regs.append(rd);
    }
    x["registers"] = regs;
    d["robot"] = x;
  }
  return d;
}

py::dict model_dict(const fmt_::ModelSpec& m) {
  py::dict d;
  d["contact"] = py::none();
  if (m.contact) {
    py::dict c;
    c["stiffness_n_per_m"] = m.contact->stiffness_n_per_m;
    c["friction_coefficient"] = m.contact->friction_coefficient;
    c["sticking_threshold_m_per_s"] = m.contact->sticking_threshold_m_per_s;
    c["force_scale_n"] = m.contact->force_scale_n;
    c["moment_scale_nm"] = m.contact->moment_scale_nm;
    d["contact"] = c;
  }
  py::list us;
  for (const auto& u : m.uncertainties) {
    py::dict x;
    x["name"] = u.name;
    x["object"] = u.object;
    x["feature"] = u.feature;
    x["kind"] = u.kind == fmt_::UncertaintySpec::Kind::translation ? "translation" : "rotation";
    x["axis"] = array(u.axis);
    x["point_m"] = array(u.point_m);
    x["design_value"] = u.design_value;
    x["prior_std"] = u.prior_std;
    us.append(x);
  }
  d["uncertainties"] = us;
  return d;
}

py::dict rig_dict(const fmt_::RigSpec& rig) {
  py::dict d;
  d["format_version"] = rig.format_version;
  d["name"] = rig.name;
  d["source"] = rig.source;
  py::list frames;
  for (const auto& f : rig.frames) {
    py::dict x;
    x["name"] = f.name;
    x["parent"] = f.parent;
    x["T_parent_frame"] = pose_dict(f.T_parent_frame);
    frames.append(x);
  }
  d["frames"] = frames;
  py::dict tf;
  tf["world"] = rig.tf.world;
  tf["base"] = rig.tf.base;
  tf["ee"] = rig.tf.ee;
  d["tf"] = tf;
  d["robot"] = rig.robot ? py::object(robot_dict(*rig.robot)) : py::none();
  d["objects"] = objects_list(rig.objects);
  d["devices"] = devices_dict(rig.devices);
  d["model"] = model_dict(rig.model);
  return d;
}

}  // namespace

void add_readers(py::module_& m) {
  m.def(
      "read_samples",
      [](const Path& path) {
        fmt_::SampleTable t;
        {
          py::gil_scoped_release free;
          t = fmt_::read_samples(path.string());
        }
        return samples_dict(t);
      },
      py::arg("path"),
      "Reads samples.csv strictly into a dict of numpy arrays: t (N,) s; p (N,3) m, q (N,4) w x y z, "
      "v (N,3) m/s, w (N,3) rad/s of the ee in world; f (N,3) N, m (N,3) N m on the plate in its frame; "
      "joints (N,J) rad; joint_names, columns, extra {name: values}, line (source line per sample), file.");
  m.def(
      "read_run",
      [](const Path& path, const Path& rig) {
        fmt_::Run run;
        {
          py::gil_scoped_release free;
          run = fmt_::load_run(path.string(), rig.string());
        }
        py::dict d = samples_dict(run.samples);
        d["dir"] = run.dir;
        d["meta"] = meta_dict(run.info);
        d["rig"] = run.rig ? py::object(rig_dict(*run.rig)) : py::none();
        return d;
      },
      py::arg("path"), py::arg("rig") = "",
      "Reads a run folder: the read_samples arrays of its samples.csv, plus meta (run.yaml), rig (the "
      "rig file given, else the run's rig.yaml, else None) and dir.");
  m.def(
      "read_rig",
      [](const Path& path) {
        fmt_::RigSpec rig;
        {
          py::gil_scoped_release free;
          rig = fmt_::load_rig(path.string());
        }
        return rig_dict(rig);
      },
      py::arg("path"),
      "Reads a rig file strictly into a dict: name, frames, robot (DH table or URDF chain), objects (polyhedra as "
      "(V,3) vertex arrays in m), devices, model (contact model, geometric uncertainties).");
}

}  // namespace hil::python
