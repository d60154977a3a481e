#include <hil/services/stiffness.hpp>

#include <Eigen/SVD>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <map>

#include <hil/so3/so3.hpp>
#include <hil/calibration/experiment.hpp>

namespace hil::services::stiffness {
namespace hc = hil::calibration;

namespace {
const char* const kAxis[] = {"dx", "dy", "dz", "rx", "ry", "rz"};
}  // namespace

void print_reduction_table(std::ostream& os, const std::vector<hc::ReductionLine>& lines) {
  os << fmt::format("{:<8} {:>6} {:>6} {:>8}  {}\n", "step", "count", "rank", "paper", "description");
  for (const auto& l : lines)
    os << fmt::format("{:<8} {:>6} {:>6} {:>8}  {}\n", l.step, l.count, l.rank >= 0 ? std::to_string(l.rank) : "-", hc::paper_count(l.step),
                      l.description);
}

void print_report(std::ostream& os, const hc::VjmModel& model, const hc::CalibrationResult& r) {
  os << fmt::format("stiffness identification: {} measurements, {} equations, robot '{}' ({} joints)\n", r.measurements, r.equations,
                    model.robot().name, model.dof());
  os << fmt::format("noise (σ per axis): position {:.3g} m, rotation {:.3g} rad{}\n\n", r.noise.position_m, r.noise.rotation_rad,
                    r.noise_estimated ? " (estimated from the residuals of a first fit)" : "");
  os << "model reduction (paper column: Table I, KUKA KR-270; see docs/calibration.md)\n";
  print_reduction_table(os, r.reduction);
  os << fmt::format("\nrank: complete physical model {}, after M5 {}, final {} = {} parameters{}\n", r.rank_physical, r.rank_algebraic,
                    r.rank_final, r.kept.size(), r.solution.full_rank ? "" : "  ** RANK DEFICIENT: standard deviations undefined **");
  const auto& sv = r.solution.singular_values;
  if (sv.size() > 0)
    os << fmt::format("singular values of the final column-scaled weighted observation matrix: {:.3g} .. {:.3g} (all in --json)\n", sv[0],
                      sv[sv.size() - 1]);
  os << fmt::format(
      "condition number (column-scaled, weighted): {:.3g}; variance factor σ0² = {:.3f} (about 1 if the noise model fits)\n\n",
      r.solution.condition, r.solution.sigma0_sq);
  os << fmt::format("{:<10} {:>13} {:>11} {:>27} {:>9} {:>5}\n", "parameter", "value", "std", "95% interval", "pnr", "class");
  for (const auto& p : r.kept)
    os << fmt::format("{:<10} {:>13.5e} {:>11.3e} [{:>12.4e}, {:>12.4e}] {:>9.1f} {:>5}\n", p.parameter.name, p.value, p.std_dev,
                      p.ci95_low, p.ci95_high, p.pnr, hc::to_string(p.cls));
  std::map<std::string, int> by_step;
  for (const auto& f : r.fixed) ++by_step[f.step];
  os << "\nfixed parameters:";
  for (const auto& [step, n] : by_step)
    os << fmt::format(" {} {} ({})", n, step == "M4b" ? "non-identifiable" : step == "M5c" ? "assigned" : "neglected", step);
  os << (r.fixed.empty() ? " none\n" : "\n");
  os << "\nresidual RMS per axis:";
  for (std::size_t a = 0; a < 6; ++a)
    if (r.residual_rows[a] > 0) os << fmt::format(" {} {:.3g} {}", kAxis[a], r.residual_rms[a], a < 3 ? "m" : "rad");
  os << "\n\nphysical checks (compliance matrices of the identified model, fixed entries included):\n";
  for (const auto& c : r.spd) {
    const bool zero = c.max_eigenvalue == 0.0 && c.min_eigenvalue == 0.0;
    if (zero) {
      os << fmt::format("  {:<4} rigid in this model (no parameter kept{})\n", c.spring,
                        c.spring[0] == 'J' ? "; aggregated into the preceding link by M3" : "");
      continue;
    }
    if (c.positive_definite)
      os << fmt::format("  {:<4} symmetric positive definite (eigenvalues {:.3g} .. {:.3g})\n", c.spring, c.min_eigenvalue,
                        c.max_eigenvalue);
    else
      os << fmt::format("  {:<4} NOT positive definite: eigenvalues {:.3g} .. {:.3g}{}\n", c.spring, c.min_eigenvalue, c.max_eigenvalue,
                        c.symmetric
                            ? " (entries fixed by M4b/M5c/M6 or absorbed by other links make it so; only combinations are identified)"
                            : " and not symmetric");
  }
}

std::vector<CompensationFailure> write_predictions(std::ostream& os, const models::ModelFile& mf, const models::StiffnessTable& table,
                                                   bool compensate) {
  std::vector<CompensationFailure> failures;
  const int n = mf.model.dof();
  const auto& first = table.rows.front();
  const bool markers = first.kind == hc::MeasurementKind::markers;
  os << "config";
  for (int j = 1; j <= n; ++j) os << ",j" << j;
  if (markers) {
    for (std::size_t k = 1; k <= first.p_ee_marker_m.size(); ++k) os << fmt::format(",m{0}_dx,m{0}_dy,m{0}_dz", k);
  } else {
    os << ",dx,dy,dz,rx,ry,rz";
  }
  if (compensate) {
    os << ",x,y,z,qx,qy,qz,cx,cy,cz,cqx,cqy,cqz";
    for (int j = 1; j <= n; ++j) os << ",cj" << j;
  }
  os << '\n';
  for (const auto& row : table.rows) {
    hc::Measurement m = row;
    if (!markers) m.kind = hc::MeasurementKind::pose6;
    const Eigen::VectorXd d = hc::predict(mf.model, mf.k, m);
    os << m.config;
    for (int j = 0; j < n; ++j) os << fmt::format(",{:.9g}", m.q_rad[j]);
    for (Eigen::Index i = 0; i < d.size(); ++i) os << fmt::format(",{:.6e}", d[i]);
    if (compensate) {
      // Target = the nominal pose at the given joints. First order: command the target moved by the
      // opposite of the deflection (position, and rotation vector composed on the left); in joint
      // space, Newton iterations q ← q - J⁺ (pose(q) ⊕ t(q) ⊖ target) on the deflected robot.
      const Eigen::Isometry3d T = hc::tool_pose(mf.model.robot(), m.q_rad);
      const hc::Vector6d t = mf.model.deflection(mf.k, m.q_rad, m.w_world);
      Eigen::Isometry3d Tc = T;
      Tc.translation() -= t.head<3>();
      Tc.linear() = so3::exp(-t.tail<3>()) * T.linear();
      const Eigen::Vector3d rv = so3::log(Eigen::Matrix3d(T.linear())), rvc = so3::log(Eigen::Matrix3d(Tc.linear()));
      double residual = 0.0;
      const Eigen::VectorXd qc = mf.model.compensate(mf.k, m.q_rad, m.w_world, 8, &residual);
      if (!(residual <= kCompensationResidual)) {
        const Eigen::JacobiSVD<Eigen::MatrixXd> svd(hc::tool_jacobian(mf.model.robot(), m.q_rad));
        failures.push_back({m.config, residual, svd.singularValues().minCoeff()});
        spdlog::warn("configuration {}: compensation did not converge (pose error {:.3g} left; smallest singular value of the tool "
                     "Jacobian {:.3g}; near a singular configuration the joint-space compensation is ill-posed)",
                     m.config, residual, failures.back().smallest_singular_value);
      }
      os << fmt::format(",{:.9f},{:.9f},{:.9f},{:.9f},{:.9f},{:.9f}", T.translation().x(), T.translation().y(), T.translation().z(), rv.x(),
                        rv.y(), rv.z());
      os << fmt::format(",{:.9f},{:.9f},{:.9f},{:.9f},{:.9f},{:.9f}", Tc.translation().x(), Tc.translation().y(), Tc.translation().z(),
                        rvc.x(), rvc.y(), rvc.z());
      for (int j = 0; j < n; ++j) os << fmt::format(",{:.9f}", qc[j]);
    }
    os << '\n';
  }
  return failures;
}

void write_simulated_table(std::ostream& os, const hc::VjmModel& model, const hc::ComplianceSet& truth, const hc::ExperimentPlan& plan,
                           const hc::NoiseModel& noise, const std::string& origin) {
  for (const auto& c : hc::check_spd(model, truth))
    if (!c.positive_definite && c.max_eigenvalue != 0.0) spdlog::warn("truth: {} is not symmetric positive definite", c.spring);
  const auto rows = hc::simulate(model, truth, plan, noise);
  os << fmt::format("# hil stiffness simulate: {}, seed {}, noise σ {} m / {} rad\n", origin, plan.seed, noise.position_m,
                    noise.rotation_rad);
  models::write_stiffness_table(os, rows, model.dof());
}

void print_table1(std::ostream& os, const hc::VjmModel& model, int configs, const std::string& measure, std::uint64_t seed,
                  bool complete_ranks) {
  hc::ExperimentPlan plan;
  plan.configurations = configs;
  plan.loads_per_config = 2;
  plan.moment_nm = measure == "point3-forces" ? 0.0 : 300.0;
  plan.kind = measure == "pose6" ? hc::MeasurementKind::pose6 : hc::MeasurementKind::point3;
  if (measure == "markers") {
    plan.kind = hc::MeasurementKind::markers;
    plan.p_ee_marker_m = {{0.2, 0.0, 0.0}, {0.0, 0.2, 0.0}, {0.0, 0.0, 0.1}};
  }
  plan.seed = seed;
  const auto data = hc::simulate(model, hc::example_compliance(model), plan, {});
  hc::PipelineOptions opt;
  opt.neglect_below = 0.0;  // M6 needs real noise; the counting stops at M5
  opt.complete_ranks = complete_ranks;
  const auto r = hc::calibrate(model, data, {1e-5, 1e-5}, opt);
  os << fmt::format("Table I counting for robot '{}' ({} configurations x 2 loads, measurement {}, noise-free)\n\n", model.robot().name,
                    configs, measure);
  print_reduction_table(os, r.reduction);
  os << fmt::format("\nrank(A) physical model {} = after M5 {} = dim {}\n", r.rank_physical, r.rank_algebraic, r.kept.size());
  auto names = [&](const char* label, const std::vector<int>& cols) {
    os << label;
    for (int c : cols) os << ' ' << r.base[static_cast<std::size_t>(c)].name;
    os << '\n';
  };
  names("G1 (identifiable):", r.partition.g1);
  names("G2 (non-identifiable):", r.partition.g2);
  for (std::size_t g = 0; g < r.splitting.groups.size(); ++g) {
    const auto& grp = r.splitting.groups[g];
    os << fmt::format("G3 group {} keeps {} of {}:", g + 1, grp.rank, grp.cols.size());
    for (int c : grp.cols) os << ' ' << r.base[static_cast<std::size_t>(c)].name;
    os << '\n';
  }
  os << "kept:";
  for (const auto& k : r.kept) os << ' ' << k.parameter.name;
  os << '\n';
}

std::unique_ptr<hc::OnlineIdentifier> make_online_identifier(const hc::VjmModel& model, const std::string& reduced_model_path,
                                                             const hc::NoiseModel& noise, const hc::PipelineOptions& options) {
  if (!reduced_model_path.empty()) {
    const auto m = models::read_reduced_model(reduced_model_path, model);
    return std::make_unique<hc::OnlineIdentifier>(model, m.free, m.fixed, m.fixed_values, noise, options, false);
  }
  std::vector<hc::ReductionLine> lines;
  return std::make_unique<hc::OnlineIdentifier>(model, hc::physical_reduction(model, options, lines), hc::ParameterSet{}, Eigen::VectorXd(),
                                                noise, options, true);
}

}  // namespace hil::services::stiffness
