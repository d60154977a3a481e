// `hil contact simulate|identify|worker`: contact-parameter identification (issue 5).
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <thread>

#include "../commands.hpp"
#include "../output.hpp"
#include "hil/format/error.hpp"
#include "hil/format/run.hpp"
#include "hil/diagnose/contact_family.hpp"
#include "identify.hpp"
#include "hil/rig/contact.hpp"
#include "simulate.hpp"
#include "contact_worker.hpp"

namespace hil::cli {

namespace cid = hil::contact_id;
namespace fs = std::filesystem;

namespace {

/// The hidden truth of an injected simulation, for the test that checks the diagnosis.
nlohmann::json effects_json(const hil::diagnose::Effects& e, const cid::ContactModel& m, unsigned seed) {
  nlohmann::json j;
  tag_format(j, "hidden_effects");
  j["effects"] = e.names();
  j["effect_seed"] = seed;
  j["K"] = m.K;
  j["mu"] = m.mu;
  j["geometric"] = e.geometric;
  j["compliance"] = nlohmann::json::array();
  for (int r = 0; r < 6; ++r) {
    std::vector<double> row;
    for (int c = 0; c < 6; ++c) row.push_back(e.compliance(r, c));
    j["compliance"].push_back(row);
  }
  j["time_offset_s"] = e.time_offset_s;
  j["sensor_bias"] = std::vector<double>(e.sensor_bias.data(), e.sensor_bias.data() + 6);
  j["sensor_gain"] = std::vector<double>(e.sensor_gain.data(), e.sensor_gain.data() + 6);
  j["viscous_n_s_per_m"] = e.viscous_n_s_per_m;
  j["damping_n_s_per_m"] = e.damping_n_s_per_m;
  j["stiffness_exponent"] = e.stiffness_exponent;
  return j;
}

}  // namespace

int simulate_run(const SimulateArgs& a) {
  const auto rig = format::load_rig(a.rig);
  const auto scene = rig::scene_from_rig(rig);
  rig::Truth truth;
  if (!a.truth.empty()) {
    truth = rig::read_truth(a.truth, rig);
  } else {
    truth.model = rig::model_from_rig(rig);
  }
  auto& s = truth.sensor;
  if (a.force_resolution >= 0) s.force_resolution_n = a.force_resolution;
  if (a.moment_resolution >= 0) s.moment_resolution_nm = a.moment_resolution;
  if (a.position_resolution >= 0) s.position_resolution_m = a.position_resolution;
  if (a.velocity_resolution >= 0) s.velocity_resolution_m_per_s = a.velocity_resolution;
  if (a.force_noise >= 0) s.force_noise_n = a.force_noise;
  if (a.moment_noise >= 0) s.moment_noise_nm = a.moment_noise;
  if (a.seed >= 0) s.seed = static_cast<unsigned>(a.seed);
  if (a.decimate < 1) throw format::FormatError({"command line", 0, 0, "--decimate"}, "must be at least 1");
  const Eigen::VectorXd x_true = rig::uncertainty_vector(scene, truth.geometric, a.truth.empty() ? a.rig : a.truth);
  const auto traj = rig::read_trajectory(a.trajectory);
  std::vector<cid::SimulatedSample> sim;
  if (a.inject.empty()) {
    if (!a.truth_out.empty()) throw format::FormatError({"command line", 0, 0, "--truth-out"}, "needs --inject");
    sim = cid::simulate(scene, truth.model, x_true, traj.kin, s);
  } else {
    hil::diagnose::Effects e;
    e.geometric = truth.geometric;
    for (const auto& name : a.inject) hil::diagnose::draw_effect(name, a.effect_seed, scene, e);
    sim = hil::diagnose::simulate_with_effects(scene, truth.model, e, traj.t, traj.kin, s);
    if (!a.truth_out.empty()) write_json(a.truth_out, effects_json(e, truth.model, a.effect_seed));
  }

  fs::create_directories(a.out);
  format::SampleTable table;
  std::size_t in_contact = 0;
  for (std::size_t i = 0; i < sim.size(); i += static_cast<std::size_t>(a.decimate)) {
    format::Sample smp;
    smp.t_s = traj.t[i] - traj.t[0];
    smp.p_world_ee_m = sim[i].kin.T_world_ee.translation();
    smp.q_world_ee = Eigen::Quaterniond(sim[i].kin.T_world_ee.linear());
    smp.v_world_ee_m_per_s = sim[i].kin.v_world_ee;
    smp.w_world_ee_rad_per_s = sim[i].kin.w_world_ee;
    smp.f_fp_n = sim[i].w_fp.head<3>();
    smp.m_fp_nm = sim[i].w_fp.tail<3>();
    table.samples.push_back(smp);
    if (sim[i].contacts > 0) ++in_contact;
  }
  format::write_samples((fs::path(a.out) / "samples.csv").string(), table);
  const double rate = traj.t.size() > 1 ? static_cast<double>(traj.t.size() - 1) / (traj.t.back() - traj.t.front()) : 0.0;
  format::RunInfo info;
  info.rig = rig.name;
  info.start_time_utc = "2026-01-01T00:00:00.000Z";
  info.output_rate_hz = rate / a.decimate;
  info.sources.push_back({"simulation", "simulation", rate, "", {}});
  info.notes = fmt::format(
      "Simulated by `hil contact simulate` from {} ({} samples at {:.4g} Hz, decimated by {}), truth {}. Sensor: "
      "position resolution {} m, velocity resolution {} m/s, force resolution {} N (noise {} N), moment resolution {} N m "
      "(noise {} N m), seed {}.",
      a.trajectory, traj.t.size(), rate, a.decimate, a.truth.empty() ? "= the rig's nominal model" : a.truth,
      s.position_resolution_m, s.velocity_resolution_m_per_s, s.force_resolution_n, s.force_noise_n, s.moment_resolution_nm,
      s.moment_noise_nm, s.seed);
  if (!a.inject.empty()) info.notes += " Hidden effects injected (which ones is kept out of the run).";
  format::write_run_info((fs::path(a.out) / "run.yaml").string(), info);
  fs::copy_file(a.rig, fs::path(a.out) / "rig.yaml", fs::copy_options::overwrite_existing);
  human(is_stdout(a.truth_out)) << fmt::format("wrote run {}: {} samples at {:.4g} Hz, {} in contact (K = {:.4g} N/m, mu = {:.3g})\n", a.out,
                           table.samples.size(), info.output_rate_hz, in_contact, truth.model.K, truth.model.mu);
  return 0;
}

namespace {

struct IdentifyArgs {
  std::string run, rig, json, report;
  bool geometric = false;
  bool include_weak = false;
  std::string lambda = "auto", solver = "lm", jacobian = "golub-pereyra";
  int window = 25;
  int lcurve_points = 30;
};

int identify(const IdentifyArgs& a) {
  const auto run = format::load_run(a.run, a.rig);
  const auto problem = contact::problem_from_run(run);
  contact::IdentifyOptions o;
  o.geometric = a.geometric;
  o.lambda = a.lambda;
  o.solver = a.solver;
  o.jacobian = a.jacobian;
  o.window = a.window;
  o.lcurve_points = a.lcurve_points;
  o.include_weak = a.include_weak;
  const auto r = contact::identify(problem, o);
  auto& text = human(is_stdout(a.json));
  contact::print(text, problem, r);
  if (!a.json.empty()) write_json(a.json, contact::to_json(problem, r));
  if (!a.report.empty()) {
    contact::write_report(a.report, fs::path(a.run).filename().string(), problem, r);
    text << "report: " << (fs::path(a.report) / "index.html").string() << "\n";
  }
  return 0;
}

}  // namespace

void add_contact(CLI::App& app) {
  auto* contact = app.add_subcommand("contact", "Contact-parameter identification (stiffness, friction, geometry)");
  contact->require_subcommand(1);

  static SimulateArgs sa;
  auto* sim = contact->add_subcommand("simulate", "Simulate a run of the rig's contact scene along a trajectory");
  sim->add_option("--rig", sa.rig, "rig file (objects, frames, contact model)")->required();
  sim->add_option("--trajectory", sa.trajectory, "CSV: t,px,py,pz,qw,qx,qy,qz[,vx,vy,vz,wx,wy,wz] (ee in world)")->required();
  sim->add_option("--out", sa.out, "run folder to write")->required();
  sim->add_option("--truth", sa.truth, "YAML with the true K, mu, sensor model and geometric uncertainties");
  sim->add_option("--decimate", sa.decimate, "keep every Nth sample (e.g. 20: 1 kHz -> 50 Hz)")->capture_default_str()->check(CLI::Range(1, 1000000));
  sim->add_option("--force-resolution", sa.force_resolution, "N");
  sim->add_option("--moment-resolution", sa.moment_resolution, "N m");
  sim->add_option("--position-resolution", sa.position_resolution, "m");
  sim->add_option("--velocity-resolution", sa.velocity_resolution, "m/s");
  sim->add_option("--force-noise", sa.force_noise, "N (Gaussian std)");
  sim->add_option("--moment-noise", sa.moment_noise, "N m (Gaussian std)");
  sim->add_option("--seed", sa.seed, "noise seed");
  sim->add_option("--inject", sa.inject,
                  "hide an effect in the data (a diagnosis candidate: geometric_offset, robot_compliance, time_offset, "
                  "sensor_bias, sensor_gain, viscous_friction, contact_damping, nonlinear_stiffness); repeatable")
      ->delimiter(',')
      ->check(CLI::IsMember(hil::diagnose::contact_extensions()));
  sim->add_option("--effect-seed", sa.effect_seed, "seed of the injected effects' random magnitudes")->capture_default_str();
  sim->add_option("--truth-out", sa.truth_out, "write the injected effects (the hidden truth) as JSON (hil.hidden_effects; - for stdout)");
  sim->callback([] { set_action([] { return simulate_run(sa); }); });

  static IdentifyArgs ia;
  auto* id = contact->add_subcommand("identify", "Identify K and mu (and optionally the geometric uncertainties) from a run");
  id->add_option("RUN", ia.run, "run folder")->required();
  id->add_option("--rig", ia.rig, "rig file (default: the run's rig.yaml)");
  id->add_flag("--geometric", ia.geometric, "also identify the rig's geometric uncertainties (variable projection)");
  id->add_flag("--include-weak", ia.include_weak, "also fit the weakly observable uncertainties");
  id->add_option("--lambda", ia.lambda, "Tikhonov weight, or 'auto' for the L-curve corner")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& v) {
            if (v == "auto") return std::string();
            char* end = nullptr;
            const double x = std::strtod(v.c_str(), &end);
            return end != v.c_str() && *end == '\0' && std::isfinite(x) && x >= 0 ? std::string() : "expected a number >= 0 or 'auto', found '" + v + "'";
          },
          "NUMBER|auto"));
  id->add_option("--solver", ia.solver, "lm (Levenberg-Marquardt) or nm (Nelder-Mead)")->capture_default_str()->check(CLI::IsMember({"lm", "nm"}));
  id->add_option("--jacobian", ia.jacobian, "golub-pereyra or kaufman (lm only)")->capture_default_str()->check(CLI::IsMember({"golub-pereyra", "kaufman"}));
  id->add_option("--window", ia.window, "sliding window (samples) of the instantaneous estimates")->capture_default_str()->check(CLI::Range(1, 1000000));
  id->add_option("--lcurve-points", ia.lcurve_points, "values of lambda on the L-curve")->capture_default_str()->check(CLI::Range(3, 10000));
  id->add_option("--json", ia.json, "write the results as JSON (hil.contact_identification; - for stdout, the text then goes to stderr)");
  id->add_option("--report", ia.report, "write an HTML report into this folder");
  id->callback([] { set_action([] { return identify(ia); }); });

  add_contact_worker(*contact);
}

}  // namespace hil::cli
