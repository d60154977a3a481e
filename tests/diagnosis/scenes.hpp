#pragma once
// Scenes for the diagnosis tests: the re-created ACU experiment (examples/acu) and the press bench
// of the demo (examples/rigs/press_bench.yaml), simulated with hidden effects as
// `hil contact simulate --inject` does.
#include <set>
#include <string>

#include <hil/diagnose/contact_family.hpp>
#include <hil/diagnose/diagnose.hpp>
#include <hil/format/rig.hpp>
#include <hil/format/run.hpp>
#include <hil/models/contact.hpp>

namespace hil::diagnose::test {

struct SceneRun {
  cid::Scene scene;
  cid::ContactModel model;
  double force_scale_n = 0, moment_scale_nm = 0;
  std::vector<double> t;             ///< trajectory times
  std::vector<cid::Kinematics> kin;  ///< true kinematics
  cid::SensorModel sensor;
};

/// "acu_2a", "acu_1a" (1 kHz, decimated by `acu_step`: 20 gives the paper's 50 Hz) or "press_slide" (50 Hz).
inline SceneRun scene_run(const std::string& name, std::size_t acu_step = 20) {
  namespace c = hil::models;
  const std::string src = HIL_SOURCE_DIR;
  SceneRun r;
  const bool acu = name.rfind("acu_", 0) == 0;
  const auto rig = format::load_rig(acu ? src + "/examples/acu/acu.yaml" : src + "/examples/rigs/press_bench.yaml");
  r.scene = c::scene_from_rig(rig);
  r.model = c::model_from_rig(rig);
  r.force_scale_n = rig.model.contact->force_scale_n;
  r.moment_scale_nm = rig.model.contact->moment_scale_nm;
  const auto traj = c::read_trajectory(acu ? src + "/examples/acu/traj_" + name.substr(4) + ".csv"
                                           : src + "/examples/trajectories/press_slide.csv");
  const std::size_t step = acu ? acu_step : 1;
  for (std::size_t i = 0; i < traj.kin.size(); i += step) {
    r.t.push_back(traj.t[i]);
    r.kin.push_back(traj.kin[i]);
  }
  r.model.K = 1.8e5;
  r.model.mu = 0.2;
  // The paper's sensor (2 µm, 1.5 N) with noise; velocities at 2e-5 m/s (docs/diagnosis.md: at
  // the paper's 2e-4 m/s, against a 3e-4 m/s sticking threshold, samples flip between sticking and
  // sliding and put a floor under the nominal model's error).
  r.sensor.position_resolution_m = 2e-6;
  r.sensor.velocity_resolution_m_per_s = 2e-5;
  r.sensor.force_resolution_n = acu ? 1.5 : 0.1;
  r.sensor.moment_resolution_nm = acu ? 0.05 : 0.005;
  r.sensor.force_noise_n = acu ? 0.3 : 0.1;
  r.sensor.moment_noise_nm = acu ? 0.02 : 0.005;
  return r;
}

inline std::vector<cid::Measurement> measure(const SceneRun& r, const Effects& e, unsigned noise_seed, bool noise = true) {
  cid::SensorModel s = noise ? r.sensor : cid::SensorModel{};
  s.seed = noise_seed;
  const auto sim = simulate_with_effects(r.scene, r.model, e, r.t, r.kin, s);
  std::vector<cid::Measurement> m;
  for (std::size_t i = 0; i < sim.size(); ++i) m.push_back({r.t[i] - r.t[0], sim[i].kin, sim[i].w_fp});
  return m;
}

/// The contact data of `r` measured with `effect` hidden (drawn and measured with `seed`; empty: none).
inline ContactData hidden_contact_data(const SceneRun& r, const std::string& effect, unsigned seed) {
  Effects e;
  if (!effect.empty()) draw_effect(effect, seed, r.scene, e);
  return make_contact_data(r.scene, r.model.v_tm, measure(r, e, seed), r.force_scale_n, r.moment_scale_nm);
}

/// The family factory diagnose() takes, over `d` (which must outlive it).
inline ModelFactory contact_factory(const ContactData& d) {
  return [&d](const std::set<std::string>& x) { return std::make_unique<ContactFamily>(d, x); };
}

/// The run folder `hil diagnose` would read for these measurements (in memory): the rig of `rig_path`,
/// one sample per measurement, no joints.
inline format::Run as_run(const std::string& name, const std::string& rig_path, const std::vector<cid::Measurement>& m) {
  format::Run run;
  run.dir = name;
  run.rig = format::load_rig(rig_path);
  for (const auto& x : m) run.samples.samples.push_back(models::sample(x));
  run.samples.joints_rad.resize(static_cast<Eigen::Index>(run.samples.samples.size()), 0);
  return run;
}

/// Issue 29's lab-length run: the ACU 2a trajectory at 1 kHz looped to `samples` (its times
/// continuing), with a hidden `effect` drawn by `seed` (noise seed too), as a run folder.
inline format::Run looped_acu_run(std::size_t samples, const std::string& effect, unsigned seed) {
  auto r = scene_run("acu_2a", 1);
  const std::size_t leg = r.kin.size();
  const double period = r.t.back() - r.t.front() + (r.t[1] - r.t[0]);
  for (std::size_t i = leg; i < samples; ++i) {
    r.t.push_back(r.t[i % leg] + period * static_cast<double>(i / leg));
    r.kin.push_back(r.kin[i % leg]);
  }
  r.t.resize(samples);
  r.kin.resize(samples);
  Effects e;
  if (!effect.empty()) draw_effect(effect, seed, r.scene, e);
  return as_run("acu_2a_looped", std::string(HIL_SOURCE_DIR) + "/examples/acu/acu.yaml", measure(r, e, seed));
}

}  // namespace hil::diagnose::test
