#include <hil/calibration/observation.hpp>

#include <stdexcept>

namespace hil::calibration {

std::string parameter_name(const VjmModel& model, int spring, int row, int col) {
  const Spring& s = model.springs()[static_cast<std::size_t>(spring)];
  if (s.kind == SpringKind::joint) return s.name + ".k";
  return s.name + ".k" + std::to_string(row + 1) + std::to_string(col + 1);
}

ParameterSet complete_parameters(const VjmModel& model) {
  ParameterSet set;
  for (std::size_t s = 0; s < model.springs().size(); ++s) {
    const int d = model.springs()[s].dim;
    for (int r = 0; r < d; ++r)
      for (int c = 0; c < d; ++c) {
        Parameter p;
        p.spring = static_cast<int>(s);
        p.row = r;
        p.col = c;
        p.symmetric = false;
        p.name = parameter_name(model, p.spring, r, c);
        set.push_back(p);
      }
  }
  return set;
}

int find_parameter(const ParameterSet& set, const std::string& name) {
  for (std::size_t i = 0; i < set.size(); ++i)
    if (set[i].name == name) return static_cast<int>(i);
  return -1;
}

ComplianceSet assemble(const VjmModel& model, const ParameterSet& set, const Eigen::Ref<const Eigen::VectorXd>& values,
                       const ComplianceSet* base) {
  if (values.size() != static_cast<Eigen::Index>(set.size())) throw std::invalid_argument("assemble: one value per parameter");
  ComplianceSet k = base ? *base : model.zero_compliance();
  check_shapes(model, k);
  for (std::size_t i = 0; i < set.size(); ++i) {
    const Parameter& p = set[i];
    auto& m = k[static_cast<std::size_t>(p.spring)];
    m(p.row, p.col) += values[static_cast<Eigen::Index>(i)];
    if (p.symmetric && p.row != p.col) m(p.col, p.row) += values[static_cast<Eigen::Index>(i)];
  }
  return k;
}

Eigen::VectorXd parameter_values(const ParameterSet& set, const ComplianceSet& k) {
  Eigen::VectorXd v(static_cast<Eigen::Index>(set.size()));
  for (std::size_t i = 0; i < set.size(); ++i)
    v[static_cast<Eigen::Index>(i)] = k[static_cast<std::size_t>(set[i].spring)](set[i].row, set[i].col);
  return v;
}

ComplianceSet aggregate_joints(const VjmModel& model, const ComplianceSet& k) {
  check_shapes(model, k);
  ComplianceSet out = k;
  const ChainPoses p0 = forward(model.robot(), Eigen::VectorXd::Zero(model.dof()));
  for (int j = 1; j <= model.dof(); ++j) {
    const int js = model.joint_spring(j), ls = model.link_spring(j - 1);
    const Eigen::Matrix3d R_WS = model.spring_pose(ls, p0).linear();
    const Eigen::Vector3d e = R_WS.transpose() * p0.joint_axis_world[static_cast<std::size_t>(j - 1)];
    const int offset = model.robot().joints[static_cast<std::size_t>(j - 1)].kind == JointKind::revolute ? 3 : 0;
    out[static_cast<std::size_t>(ls)].block<3, 3>(offset, offset) += k[static_cast<std::size_t>(js)](0, 0) * e * e.transpose();
    out[static_cast<std::size_t>(js)].setZero();
  }
  return out;
}

void tool_observation(const VjmModel& model, const ParameterSet& set, const VjmWorkspace& ws, const Vector6d& w_world,
                      Eigen::Ref<Eigen::MatrixXd> A6) {
  // Spring wrenches u_s = J_sᵀ w, then column J_s E_p u_s.
  const std::size_t ns = model.springs().size();
  Eigen::Matrix<double, 6, Eigen::Dynamic> U(6, static_cast<Eigen::Index>(ns));
  for (std::size_t s = 0; s < ns; ++s) U.col(static_cast<Eigen::Index>(s)).noalias() = ws.J[s].transpose() * w_world;
  for (std::size_t i = 0; i < set.size(); ++i) {
    const Parameter& p = set[i];
    const auto s = static_cast<std::size_t>(p.spring);
    const auto col = static_cast<Eigen::Index>(i);
    A6.col(col).noalias() = ws.J[s].col(p.row) * U(p.col, p.spring);
    if (p.symmetric && p.row != p.col) A6.col(col).noalias() += ws.J[s].col(p.col) * U(p.row, p.spring);
  }
}

int measurement_rows(const Measurement& m) {
  switch (m.kind) {
    case MeasurementKind::pose6: return 6;
    case MeasurementKind::point3: return 3;
    case MeasurementKind::markers: return 3 * static_cast<int>(m.p_ee_marker_m.size());
  }
  return 0;
}

void row_axes(const Measurement& m, std::vector<int>& axes) {
  const int rows = measurement_rows(m);
  for (int r = 0; r < rows; ++r) axes.push_back(m.kind == MeasurementKind::pose6 ? r : r % 3);
}

Eigen::MatrixXd projection(const Measurement& m, const Eigen::Isometry3d& T_world_ee) {
  const int rows = measurement_rows(m);
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(rows, 6);
  if (m.kind == MeasurementKind::pose6) {
    S.setIdentity();
  } else if (m.kind == MeasurementKind::point3) {
    S.leftCols(3).setIdentity();
  } else {
    for (std::size_t k = 0; k < m.p_ee_marker_m.size(); ++k) {
      const auto r0 = static_cast<Eigen::Index>(3 * k);
      const Eigen::Vector3d r_W = T_world_ee.linear() * m.p_ee_marker_m[k];
      // δp_marker = δp_ee + δθ × r = δp_ee - [r]x δθ
      S.block<3, 3>(r0, 0).setIdentity();
      S.block<3, 3>(r0, 3) = -skew(r_W);
    }
  }
  return S;
}

WeightedSystem build_system(const VjmModel& model, const ParameterSet& set, const std::vector<Measurement>& data, const NoiseModel& noise) {
  Eigen::Index m = 0;
  for (const auto& d : data) m += measurement_rows(d);
  const auto n = static_cast<Eigen::Index>(set.size());
  WeightedSystem sys;
  sys.A_w.resize(m, n);
  sys.t_w.resize(m);
  sys.sigma.resize(m);
  sys.axis.reserve(static_cast<std::size_t>(m));
  sys.measurement.reserve(static_cast<std::size_t>(m));
  VjmWorkspace ws;
  Eigen::MatrixXd A6(6, n);
  Eigen::Index row = 0;
  for (std::size_t i = 0; i < data.size(); ++i) {
    const Measurement& d = data[i];
    if (d.q_rad.size() != model.dof())
      throw std::invalid_argument("measurement " + std::to_string(i) + ": expected " + std::to_string(model.dof()) + " joint values");
    const int rows = measurement_rows(d);
    if (rows == 0) throw std::invalid_argument("measurement " + std::to_string(i) + ": nothing measured (no markers)");
    if (d.displacement.size() != rows)
      throw std::invalid_argument("measurement " + std::to_string(i) + ": expected " + std::to_string(rows) + " measured values");
    model.jacobians(d.q_rad, ws);
    tool_observation(model, set, ws, d.w_world, A6);
    const Eigen::MatrixXd S = projection(d, ws.poses.T_world_ee);
    const std::size_t first = sys.axis.size();
    row_axes(d, sys.axis);
    for (int r = 0; r < rows; ++r) {
      const int axis = sys.axis[first + static_cast<std::size_t>(r)];
      const double sigma = axis < 3 ? noise.position_m : noise.rotation_rad;
      if (!(sigma > 0.0)) throw std::invalid_argument(axis < 3 ? "position noise must be > 0" : "rotation noise must be > 0");
      sys.sigma[row + r] = sigma;
      sys.measurement.push_back(static_cast<int>(i));
    }
    sys.A_w.middleRows(row, rows).noalias() = S * A6;
    sys.t_w.segment(row, rows) = d.displacement;
    for (int r = 0; r < rows; ++r) {
      sys.A_w.row(row + r) /= sys.sigma[row + r];
      sys.t_w[row + r] /= sys.sigma[row + r];
    }
    row += rows;
  }
  return sys;
}

Eigen::VectorXd predict(const VjmModel& model, const ComplianceSet& k, const Measurement& m) {
  check_shapes(model, k);
  VjmWorkspace ws;
  model.jacobians(m.q_rad, ws);
  const Vector6d t = model.deflection(k, ws, m.w_world);
  return projection(m, ws.poses.T_world_ee) * t;
}

}  // namespace hil::calibration
