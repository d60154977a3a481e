#include "blind_runs.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <memory>
#include <set>
#include <sstream>

#include <hil/diagnose/contact_family.hpp>

namespace hil::diagnose::test {

ct::Scenario clean_scenario() {
  ct::Scenario sc = pressing_and_sliding(kDuration_s);
  sc.law.slip_regularisation_m_per_s = kSlipRegularisation_m_per_s;
  return sc;
}

Diagnosed diagnose_scenario(const ct::Scenario& sc, const TripodRigOptions& rig, const Resolution& r, double stick_below_m_per_s) {
  const cid::Scene scene = tripod_scene(sc.plate, sc.tripod, rig);
  auto data = make_contact_data(scene, stick_below_m_per_s, to_measurements(ct::simulate(sc), {r.position_m, r.velocity_m_per_s}));
  data.plate_gain_tolerance = rig.plate_gain_tolerance;
  const ModelFactory make = [&data](const std::set<std::string>& x) { return std::make_unique<ContactFamily>(data, x); };
  Diagnosed run{diagnose(make, contact_extensions(), data.obs, contact_context(data)), ""};
  const auto& d = run.d;
  const auto& a = d.nominal_residuals;
  std::ostringstream o;
  o << std::setprecision(3) << "cause " << d.cause << (d.second_cause.empty() ? "" : " + " + d.second_cause) << ", nominal "
    << 100 * d.nominal.cv_error << " %, noise " << 100 * d.noise_relative << " %, excess " << a.excess_variance << " [";
  for (int c = 0; c < 6; ++c) o << (c ? " " : "") << a.excess(c);
  o << "], Q " << a.ljung_box_q;
  for (std::size_t i = 0; i < 2 && i < a.correlations.size(); ++i) {
    const auto& k = a.correlations[i];
    o << "; " << k.component << "~" << k.signal << " r " << k.correlation << " lag " << k.lag << " expl " << k.explained;
  }
  if (!a.trends.empty())
    o << "; trend " << a.trends.front().component << " r " << a.trends.front().correlation << " expl " << a.trends.front().explained;
  if (d.extended)
    for (const auto& q : d.extended->full.reported)
      if (q.extension || q.name == "K" || q.name == "mu")
        o << "; " << q.name << " = " << q.value << " ± " << q.std << " [a " << q.std_asymptotic << " f " << q.std_folds << " m "
          << q.std_model_form << " s " << q.std_sandwich << " nu " << q.sandwich_dof << (q.model_based ? " MODEL" : "")
          << (q.std_components > 0 ? " COMPONENTS " + q.components_disagree : "") << "]";
  if (a.structured()) o << " | STRUCTURE: " << a.structure_text();
  if (d.extended && d.extended_residuals.structured()) o << " | LEFT: " << d.extended_residuals.structure_text();
  run.line = o.str();
  return run;
}

double linear_damping_of(const ct::Scenario& s) {
  const auto n = static_cast<std::size_t>(std::floor(s.duration_s * s.sensor.rate_hz + 1e-9));
  double num = 0.0, den = 0.0;
  std::vector<ct::FootContact> feet;
  for (std::size_t k = 0; k < n; ++k) {
    ct::plate_wrench(s.plate, s.tripod, s.law, ct::true_state(s, static_cast<double>(k) / s.sensor.rate_hz), &feet);
    for (const auto& f : feet) {
      if (!f.in_contact) continue;
      const double rate2 = f.penetration_rate_m_per_s * f.penetration_rate_m_per_s;
      const double dashpot = s.law.damping_exponent == 0.0 ? 1.0 : std::pow(f.penetration_m / s.law.delta_ref_m, s.law.damping_exponent);
      num += s.law.damping_n_s_per_m * dashpot * rate2;
      den += rate2;
    }
  }
  return den > 0.0 ? num / den : s.law.damping_n_s_per_m;
}

double slow_friction_ratio_of(const ct::Scenario& s, double stick_below_m_per_s, double resolved_from_m_per_s, bool total_normal_column) {
  const auto n = static_cast<std::size_t>(std::floor(s.duration_s * s.sensor.rate_hz + 1e-9));
  const auto& law = s.law;
  const Eigen::Vector3d normal = s.plate.T_world_plate().linear().col(2);
  double num = 0.0, den = 0.0;
  std::vector<ct::FootContact> feet;
  for (std::size_t k = 0; k < n; ++k) {
    const ct::BodyState b = ct::true_state(s, static_cast<double>(k) / s.sensor.rate_hz);
    ct::plate_wrench(s.plate, s.tripod, law, b, &feet);
    for (const auto& f : feet) {
      if (!f.in_contact) continue;
      const Eigen::Vector3d v = b.v_world_m_per_s + b.w_world_rad_per_s.cross(f.point_world_m - b.T_world_body.translation());
      const double u = (v - normal.dot(v) * normal).norm();
      if (!(u > 0.0) || u < resolved_from_m_per_s || u > stick_below_m_per_s) continue;
      const double elastic = law.stiffness_n_per_m * law.delta_ref_m * std::pow(f.penetration_m / law.delta_ref_m, law.exponent);
      const double bound = law.friction_on_total_normal ? f.normal_n : elastic;
      const double column = total_normal_column ? f.normal_n : elastic;
      // The truth's viscous friction acts at every slip speed; hil's viscous column only on contacts
      // sliding above the declared threshold (their tangent is zero below it), so below it the slow
      // slip's term carries the viscous part too: c_v u, relative to μ as the ratio is.
      num += column * (bound * u / std::hypot(u, law.slip_regularisation_m_per_s) + law.viscous_n_s_per_m * u / law.mu);
      den += column * column;
    }
  }
  return den > 0.0 ? num / den : 1.0;
}

std::optional<double> truth_of(const std::string& name, const ct::Scenario& s, const Fit& f, double twist_step_m_per_s,
                               const std::string& form_taken) {
  const char* comp[6] = {"fx", "fy", "fz", "mx", "my", "mz"};
  // The gains neither reported nor fixed as unidentifiable are references: a gain is relative to its
  // group's (fx, fy and mz carry the friction, fz, mx and my the normal force; sensor_gain's
  // contact term has one in each), else to the other group's; a friction gain fixed as
  // unidentifiable is its group's reference.
  auto friction = [](int k) { return k == 0 || k == 1 || k == 5; };
  auto fixed = [&](int c) {
    for (const auto& u : f.unidentifiable)
      if (u.name == std::string("gain_") + comp[c]) return true;
    return false;
  };
  auto unlisted = [&](int c) {
    bool listed = fixed(c);
    for (const auto& q : f.reported) listed = listed || q.name == std::string("gain_") + comp[c];
    return !listed;
  };
  for (int c = 0; c < 6; ++c) {
    if (name == std::string("bias_") + comp[c]) return s.sensor.bias(c);
    if (name == std::string("gain_") + comp[c]) {
      int r = -1;
      for (int k = 0; k < 6; ++k)
        if (k != c && unlisted(k) && (r < 0 || (friction(k) == friction(c) && friction(r) != friction(c)))) r = k;
      if (r < 0) return std::nullopt;
      for (int k = 0; k < 6; ++k)
        if (k != c && fixed(k) && friction(k) && friction(c)) r = k;
      return (1.0 + s.sensor.gain(c)) / (1.0 + s.sensor.gain(r)) - 1.0;
    }
  }
  // The ADC's mean of n instants spread over the period before t - τ lags by τ + (n - 1) T / (2n)
  // (a symmetric FIR: that delay at every frequency, its gain within 1e-4 of 1 below 3 Hz). A
  // first-order filter before it adds its low-frequency group delay τ_f (τ_f / (1 + (ω τ_f)²) at ω:
  // within 2 % of τ_f below 1.5 Hz for τ_f <= 15 ms; no single delay is its truth at every ω).
  if (name == "time_offset_s") {
    const double n = s.sensor.adc_subsamples;
    return s.sensor.delay_s + (n - 1.0) / (2.0 * n * s.sensor.rate_hz) + s.sensor.filter_time_constant_s;
  }
  if (name == "viscous_n_s_per_m") return s.law.viscous_n_s_per_m;
  if (name == "damping_n_s_per_m") return s.law.damping_exponent == 0.0 ? s.law.damping_n_s_per_m : linear_damping_of(s);
  if (name == "stiffness_exponent") return s.law.exponent;
  // slow_slip's μ_s / μ: the truth's slow friction in hil's form over the slips the reported twist
  // resolves (slow_friction_ratio_of); a Stribeck law's is not one number.
  // With contact_damping in the model its column follows the model's total normal force.
  if (name == "slow_slip_mu_ratio") {
    auto of_damping = [](const std::string& param) { return param.rfind("damping_", 0) == 0; };  // D, μ_D D, τ_D
    bool damping = false;
    for (const auto& q : f.reported) damping = damping || of_damping(q.name);
    for (const auto& u : f.unidentifiable) damping = damping || of_damping(u.name);
    damping = damping && form_taken.rfind(ContactFamily::kSlowFrictionElasticForm, 0) != 0;
    return s.law.stribeck_speed_m_per_s > 0.0
               ? std::nullopt
               : std::optional<double>(slow_friction_ratio_of(s, kStickBelow_m_per_s, 0.5 * twist_step_m_per_s, damping));
  }
  // The truth's surface is at o_P, level in P: the rig's declared values are what may be off.
  if (name == kPlateHeight || name == kPlateTiltX || name == kPlateTiltY) return 0.0;
  return std::nullopt;
}

bool belongs_to(const std::string& param, const std::string& extension) {
  auto starts = [&](const char* p) { return param.rfind(p, 0) == 0; };
  if (extension == "sensor_bias") return starts("bias_");
  if (extension == "sensor_gain") return starts("gain_");
  if (extension == "time_offset") return param == "time_offset_s";
  if (extension == "viscous_friction") return param == "viscous_n_s_per_m";
  if (extension == "contact_damping") return param == "damping_n_s_per_m";
  if (extension == "nonlinear_stiffness") return param == "stiffness_exponent";
  if (extension == "robot_compliance") return starts("compliance_");
  if (extension == "geometric_offset") return param == kPlateHeight || param == kPlateTiltX || param == kPlateTiltY;
  if (extension == "slow_slip") return param == "slow_slip_mu_ratio";
  return false;
}

double joint_z(std::size_t m) {
  const double tail = 0.05 / static_cast<double>(std::max<std::size_t>(1, m));
  double lo = 0.0, hi = 10.0;  // erfc(z/√2) falls from 1 to 0 on [0, 10]
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > tail ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace hil::diagnose::test
