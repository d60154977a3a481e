#pragma once
// The re-created ACU experiment (examples/acu) for tests and benchmarks: the rig, the hidden truth
// and the trajectories, simulated as `hil contact simulate` does.
#include <string>

#include <hil/format/rig.hpp>
#include <hil/models/contact.hpp>

namespace hil::contact_id::test {

struct AcuRun {
  Scene scene;
  ContactModel nominal;
  ProblemOptions options;
  Eigen::VectorXd truth;
  std::vector<Measurement> data;
};

/// Simulates test "1a" or "2a" at the trajectory rate (1 kHz) and keeps every `decimate`th sample.
inline AcuRun acu_run(const std::string& test, int decimate = 20) {
  namespace c = hil::models;
  const std::string dir = std::string(HIL_SOURCE_DIR) + "/examples/acu/";
  const auto rig = format::load_rig(dir + "acu.yaml");
  AcuRun r;
  r.scene = c::scene_from_rig(rig);
  r.nominal = c::model_from_rig(rig);
  r.options.v_tm = r.nominal.v_tm;
  r.options.force_scale_n = rig.model.contact->force_scale_n;
  r.options.moment_scale_nm = rig.model.contact->moment_scale_nm;
  const auto truth = c::read_truth(dir + "truth_" + test + ".yaml", rig);
  r.truth = c::uncertainty_vector(r.scene, truth.geometric, "truth");
  const auto traj = c::read_trajectory(dir + "traj_" + test + ".csv");
  std::vector<Kinematics> kin;
  std::vector<double> t;
  for (std::size_t i = 0; i < traj.kin.size(); i += static_cast<std::size_t>(decimate)) {
    kin.push_back(traj.kin[i]);
    t.push_back(traj.t[i]);
  }
  const auto sim = simulate(r.scene, truth.model, r.truth, kin, truth.sensor);
  for (std::size_t i = 0; i < sim.size(); ++i) r.data.push_back({t[i], sim[i].kin, sim[i].w_fp});
  return r;
}

}  // namespace hil::contact_id::test
