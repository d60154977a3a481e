#pragma once
/// \file From the run/rig formats to the pure numerics of hil::contact_id, and back.
#include <map>
#include <string>
#include <vector>

#include <hil/contact_id/identification.hpp>
#include <hil/format/rig.hpp>
#include <hil/format/samples.hpp>

namespace hil::models {

/// The contact scene of a rig: the object hanging off `ee` is object 1, the one fixed in the world
/// object 2; the force-plate frame is `force_plate` if the rig has one, else world.
/// \throws error::FormatError naming the rig file when the rig has not exactly one held and one
/// fixed object, or a polyhedron is degenerate.
contact_id::Scene scene_from_rig(const format::RigSpec& rig);

/// The rig's contact model (K, μ, v_t,m). \throws FormatError if missing or not physical.
contact_id::ContactModel model_from_rig(const format::RigSpec& rig);

/// A sample -> a measurement (pose, twist, plate wrench).
contact_id::Measurement measurement(const format::Sample& s);
/// A measurement -> a sample (the inverse of measurement()).
format::Sample sample(const contact_id::Measurement& m);
/// Samples -> measurements.
std::vector<contact_id::Measurement> measurements(const format::SampleTable& t);

/// A trajectory CSV (t, px, py, pz, qw, qx, qy, qz and optionally vx vy vz wx wy wz; velocities
/// by central differences when absent). \throws FormatError naming file, line and column.
struct Trajectory {
  std::vector<double> t;
  std::vector<contact_id::Kinematics> kin;
};
Trajectory read_trajectory(const std::string& path);

/// The hidden truth of a simulation (YAML): stiffness_n_per_m, friction_coefficient, optional
/// sensor {...} and geometric {name: value}. Values absent fall back to the rig's.
struct Truth {
  contact_id::ContactModel model;
  contact_id::SensorModel sensor;
  std::map<std::string, double> geometric;
};
/// \throws FormatError naming the file, line and field.
Truth read_truth(const std::string& path, const format::RigSpec& rig);
/// read_truth on text; `display_name` names it in errors.
Truth parse_truth(const std::string& yaml_text, const std::string& display_name, const format::RigSpec& rig);

/// x_u from name -> value (others at their design value). \throws std::runtime_error on unknown names.
Eigen::VectorXd uncertainty_vector(const contact_id::Scene& s, const std::map<std::string, double>& values, const std::string& where);

}  // namespace hil::models
