#include <hil/calibration/experiment.hpp>

#include <random>
#include <stdexcept>

namespace hil::calibration {
namespace {

bool within_limits(const SerialRobot& robot, const Eigen::VectorXd& q) {
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    const auto v = q[static_cast<Eigen::Index>(j)];
    if (v < robot.joints[j].lower || v > robot.joints[j].upper) return false;
  }
  return true;
}

}  // namespace

std::vector<Measurement> simulate(const VjmModel& model, const ComplianceSet& truth, const ExperimentPlan& plan, const NoiseModel& noise) {
  check_shapes(model, truth);
  if (plan.configurations < 1 || plan.loads_per_config < 1)
    throw std::invalid_argument("simulate: need at least one configuration and load");
  if (plan.kind == MeasurementKind::markers && plan.p_ee_marker_m.empty())
    throw std::invalid_argument("simulate: markers kind without markers");
  std::mt19937_64 rng(plan.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  auto random_direction = [&] {
    Eigen::Vector3d v;
    do {
      v = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
    } while (v.norm() < 1e-6);
    return v.normalized();
  };
  std::vector<Measurement> out;
  VjmWorkspace ws;
  const int n = model.dof();
  for (int c = 0; c < plan.configurations; ++c) {
    Eigen::VectorXd q(n);
    // A mimic joint's value follows its master and may leave its own limits: such a posture is
    // drawn again (a robot with coupled joints cannot reach it).
    for (int attempt = 0;; ++attempt) {
      for (int j = 0; j < n; ++j) {
        const auto& row = model.robot().joints[static_cast<std::size_t>(j)];
        q[j] = row.lower + (row.upper - row.lower) * unit(rng);
      }
      fill_mimic_joints(model.robot(), q);
      if (within_limits(model.robot(), q)) break;
      if (attempt == 1000)
        throw std::invalid_argument(
            "simulate: no posture within every joint's limits in 1000 draws; do the mimic joints' limits fit their masters'?");
    }
    model.jacobians(q, ws);
    for (int l = 0; l < plan.loads_per_config; ++l) {
      Measurement m;
      m.config = c + 1;
      m.q_rad = q;
      m.kind = plan.kind;
      m.p_ee_marker_m = plan.p_ee_marker_m;
      m.w_world << plan.force_n * random_direction(), plan.moment_nm * random_direction();
      const Vector6d t = model.deflection(truth, ws, m.w_world);
      m.displacement = projection(m, ws.poses.T_world_ee) * t;
      std::vector<int> axes;
      row_axes(m, axes);
      for (Eigen::Index r = 0; r < m.displacement.size(); ++r) {
        const double sigma = axes[static_cast<std::size_t>(r)] < 3 ? noise.position_m : noise.rotation_rad;
        if (sigma > 0.0) m.displacement[r] += sigma * gauss(rng);
      }
      out.push_back(std::move(m));
    }
  }
  return out;
}

Matrix6d beam_compliance(double L, double EA, double EIy, double EIz, double GJ) {
  if (!(L > 0.0 && EA > 0.0 && EIy > 0.0 && EIz > 0.0 && GJ > 0.0)) throw std::invalid_argument("beam_compliance: all values must be > 0");
  Matrix6d k = Matrix6d::Zero();
  k(0, 0) = L / EA;
  k(1, 1) = L * L * L / (3.0 * EIz);
  k(1, 5) = k(5, 1) = L * L / (2.0 * EIz);
  k(5, 5) = L / EIz;
  k(2, 2) = L * L * L / (3.0 * EIy);
  k(2, 4) = k(4, 2) = -L * L / (2.0 * EIy);
  k(4, 4) = L / EIy;
  k(3, 3) = L / GJ;
  return k;
}

ComplianceSet example_compliance(const VjmModel& model, double link_scale, double joint_scale) {
  ComplianceSet k = model.zero_compliance();
  // A hollow steel section (E 210 GPa, G 81 GPa) of 0.3 m outer, 0.26 m inner diameter.
  constexpr double kPi = 3.141592653589793;
  const double E = 210e9, G = 81e9, ro = 0.15, ri = 0.13;
  const double area = kPi * (ro * ro - ri * ri);
  const double I = kPi / 4.0 * (ro * ro * ro * ro - ri * ri * ri * ri);
  const double Jp = 2.0 * I;
  const double joint_table[] = {0.25e-6, 0.30e-6, 0.41e-6, 3.0e-6, 3.3e-6, 2.4e-6};
  for (std::size_t s = 0; s < model.springs().size(); ++s) {
    const Spring& sp = model.springs()[s];
    if (sp.kind == SpringKind::link) {
      const double L = sp.length_m > 1e-3 ? sp.length_m : 0.2;
      // Slightly different rigidities about y and z so that the two bending planes differ.
      k[s] = link_scale * beam_compliance(L, E * area, 1.1 * E * I, E * I, G * Jp);
    } else {
      k[s](0, 0) = joint_scale * joint_table[static_cast<std::size_t>(sp.index - 1) % 6];
    }
  }
  return k;
}

}  // namespace hil::calibration
