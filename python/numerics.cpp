// identify_contact / diagnose / identify_stiffness: the numerics behind `hil contact identify`,
// `hil diagnose` and `hil stiffness identify`, on the same inputs, returning the commands' JSON
// (built by the commands' own to_json) as dicts, plus arrays a plot needs. The GIL is released
// while C++ computes. Docs: docs/python.md.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>  // paths as str or os.PathLike

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "bindings.hpp"
#include "convert.hpp"
#include <hil/calibration/reduction.hpp>
#include <hil/error/error.hpp>
#include <hil/format/run.hpp>
#include <hil/services/contact_identify.hpp>
#include <hil/models/contact.hpp>
#include <hil/services/diagnose_output.hpp>
#include <hil/services/diagnose_run.hpp>
#include <hil/services/point_calibration.hpp>
#include <hil/models/stiffness.hpp>
#include <hil/models/stiffness_model.hpp>

namespace hil::python {

namespace cid = hil::contact_id;

namespace {

constexpr double kZ95 = 1.959963984540054;  // two-sided 95 % of the normal distribution

/// value ± 1.96 std, or None when either is missing (null in the command's JSON).
py::object interval95(const py::dict& d, const char* value, const char* std_dev) {
  if (d[value].is_none() || d[std_dev].is_none()) return py::none();
  const double v = d[value].cast<double>(), s = d[std_dev].cast<double>();
  return py::make_tuple(v - kZ95 * s, v + kZ95 * s);
}

/// Per used sample: the measured plate wrench, the model's (Φ θ at geometry x, mapped to the plate
/// frame) and their difference, N and N m, force-plate frame; with the contact counts.
struct Fit {
  std::vector<double> t;
  std::vector<int> sample, contacts;
  std::vector<cid::Vector6d> measured_fp, model_fp;
};

Fit fit_arrays(const cid::ContactProblem& p, const Eigen::VectorXd& x, const cid::LinearEstimate& e) {
  Fit f;
  f.model_fp = services::contact::model_plate_wrenches(p, x, e.theta, f.contacts);  // as the command's report draws it
  for (const int k : p.used()) {
    const auto& m = p.data()[static_cast<std::size_t>(k)];
    f.t.push_back(m.t_s);
    f.sample.push_back(k);
    f.measured_fp.push_back(m.w_fp);
  }
  return f;
}

py::dict fit_dict(const Fit& f) {
  const auto n = f.t.size();
  auto rows6 = [&](auto get) { return matrix(n, 6, get); };
  py::dict d;
  d["t"] = array(f.t);
  d["sample"] = py::array_t<int>(static_cast<py::ssize_t>(n), f.sample.data());
  d["contacts"] = py::array_t<int>(static_cast<py::ssize_t>(n), f.contacts.data());
  d["measured_fp"] = rows6([&](std::size_t i, std::size_t c) { return f.measured_fp[i][static_cast<Eigen::Index>(c)]; });
  d["model_fp"] = rows6([&](std::size_t i, std::size_t c) { return f.model_fp[i][static_cast<Eigen::Index>(c)]; });
  d["residual_fp"] = rows6([&](std::size_t i, std::size_t c) {
    const auto k = static_cast<Eigen::Index>(c);
    return f.measured_fp[i][k] - f.model_fp[i][k];
  });
  return d;
}

/// Instantaneous (window 1) or sliding-window estimates; NaN where not estimated.
py::dict instant_dict(const std::vector<cid::InstantEstimate>& v) {
  py::dict d;
  d["t"] = column(v.size(), [&](std::size_t i) { return v[i].t_s; });
  d["K"] = column(v.size(), [&](std::size_t i) { return v[i].valid ? v[i].K : NAN; });
  d["mu"] = column(v.size(), [&](std::size_t i) { return v[i].mu_valid ? v[i].mu : NAN; });
  d["contacts"] = column(v.size(), [&](std::size_t i) { return static_cast<double>(v[i].contacts); });
  return d;
}

py::dict identify_contact(const Path& run_path, const Path& rig, bool geometric, const std::string& lambda, const std::string& solver,
                          const std::string& jacobian, int window, int lcurve_points, bool include_weak) {
  // Checked here, with the keyword's name, whether or not geometric= makes them used.
  if (solver != "lm" && solver != "nm") throw py::value_error("solver: expected 'lm' or 'nm', got '" + solver + "'");
  if (jacobian != "golub-pereyra" && jacobian != "kaufman")
    throw py::value_error("jacobian: expected 'golub-pereyra' or 'kaufman', got '" + jacobian + "'");
  if (lambda != "auto") {
    char* end = nullptr;
    const double x = std::strtod(lambda.c_str(), &end);
    if (end == lambda.c_str() || *end != '\0' || !std::isfinite(x) || x < 0)
      throw py::value_error("lambda_: expected a number >= 0 (as text) or 'auto', got '" + lambda + "'");
  }
  if (window < 1) throw py::value_error("window: expected >= 1 used samples, got " + std::to_string(window));
  if (lcurve_points < 3) throw py::value_error("lcurve_points: expected >= 3, got " + std::to_string(lcurve_points));
  nlohmann::json j;
  Fit fit;
  std::vector<cid::InstantEstimate> inst, win;
  {
    py::gil_scoped_release free;
    const auto run = format::load_run(run_path.string(), rig.string());
    const auto problem = services::contact::problem_from_run(run);
    services::contact::IdentifyOptions o;
    o.geometric = geometric;
    o.lambda = lambda;
    o.solver = solver;
    o.jacobian = jacobian;
    o.window = window;
    o.lcurve_points = lcurve_points;
    o.include_weak = include_weak;
    const auto r = services::contact::identify(problem, o);
    j = services::contact::to_json(problem, r);
    // The final estimate: with the identified geometry when it was fitted, else the nominal one.
    if (r.geometric) {
      fit = fit_arrays(problem, r.geometric->x, r.geometric->theta);
      inst = r.inst_geometric;
      win = r.window_geometric;
    } else {
      fit = fit_arrays(problem, problem.scene().design(), r.nominal);
      inst = r.inst_nominal;
      win = r.window_nominal;
    }
  }
  py::dict d = to_python(j);
  d["K_ci95"] = interval95(d, "K", "K_std");
  d["mu_ci95"] = interval95(d, "mu", "mu_std");
  d["fit"] = fit_dict(fit);
  d["instantaneous"] = instant_dict(inst);
  d["window"] = instant_dict(win);
  return d;
}

/// Thrown out of the progress hook to stop a diagnosis for a pending Python exception (Ctrl-C, or
/// the callback's own). Not a std::exception, so that the command's catch-alls let it through.
struct StopForPython {};

py::dict diagnose(const Path& path, const Path& rig, const std::vector<std::string>& candidates, int folds, const py::object& progress,
                  int cv_offsets) {
  if (folds < 2) throw py::value_error("folds: must be at least 2, got " + std::to_string(folds));
  if (cv_offsets < 0 || cv_offsets > 64)
    throw py::value_error("cv_offsets: must be 0 (automatic) to 64, got " + std::to_string(cv_offsets));
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    throw py::type_error("progress: expected a callable (step, total, what) or None");
  nlohmann::json j;
  std::exception_ptr python_error;
  try {
    py::gil_scoped_release free;
    services::diagnose::Options o;
    o.candidates = candidates;
    o.folds = folds;
    o.cv_offsets = cv_offsets;
    // Between steps, with the GIL: Ctrl-C (signals reach Python only while it runs) and the callback.
    o.progress = [&](int step, int total, const std::string& what) {
      py::gil_scoped_acquire hold;
      try {
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();
        if (!progress.is_none()) progress(step, total, what);
      } catch (const py::error_already_set&) {
        python_error = std::current_exception();
        throw StopForPython{};
      }
    };
    // A file is a stiffness-experiment table, a folder a run (as `hil diagnose`).
    const auto r = std::filesystem::is_regular_file(path)
                       ? services::diagnose::diagnose_table(path.string(), rig.string(), o)
                       : services::diagnose::diagnose_run(format::load_run(path.string(), rig.string()), o);
    j = services::diagnose::to_json(r);
  } catch (const StopForPython&) {
    std::rethrow_exception(python_error);  // the GIL is held again: raise the Python exception
  } catch (const error::FormatError& e) {
    // The services name the CLI's flag; a Python caller gave the keyword.
    if (e.where().field == "--candidates") throw py::value_error("candidates: " + e.message());
    throw;
  }
  return to_python(j);
}

py::dict identify_stiffness(const Path& table_path, const Path& rig, double noise_pos_m, double noise_rot_rad, double neglect_below) {
  if (!(noise_pos_m >= 0.0) || !(noise_rot_rad >= 0.0))
    throw py::value_error("noise_pos_m, noise_rot_rad: expected >= 0 (0: estimated from the residuals)");
  if (!(neglect_below >= 0.0)) throw py::value_error("neglect_below: expected >= 0 (0: M6 off)");
  nlohmann::json j;
  {
    py::gil_scoped_release free;
    const calibration::VjmModel model(models::load_robot(rig.string()));
    const auto table = models::read_stiffness_table(table_path.string(), model.dof(), true);
    calibration::PipelineOptions o;  // the defaults of `hil stiffness identify`
    o.neglect_below = neglect_below;
    const auto r = calibration::calibrate(model, table.rows, {noise_pos_m, noise_rot_rad}, o);
    j = models::result_to_json(model, r);
  }
  return to_python(j);
}

py::dict calibrate(const Path& run, const Path& rig, const std::vector<std::string>& candidates, int folds,
                   const std::vector<std::string>& bending_links, bool orientation) {
  if (folds < 0) throw py::value_error("folds: expected >= 0 (0: one posture at a time)");
  services::point_calibration::Options o;
  if (!candidates.empty()) {
    o.candidates.clear();
    for (const auto& c : candidates) {
      try {
        o.candidates.push_back(calibration::point_candidate_from_string(c));
      } catch (const std::invalid_argument& e) {
        throw py::value_error(std::string("candidates: ") + e.what());
      }
    }
  }
  o.folds = folds;
  o.bending_links = bending_links;
  o.orientation = orientation;
  nlohmann::json j;
  {
    py::gil_scoped_release free;
    j = services::point_calibration::to_json(services::point_calibration::run(run.string(), rig.string(), o));
  }
  return to_python(j);
}

/// The rig's contact scene along a trajectory file (as `hil contact simulate` without --inject),
/// as arrays: what the model predicts, and what a sensor would measure.
py::dict simulate_contact(const Path& rig_path, const Path& trajectory, const py::object& K, const py::object& mu,
                          const std::map<std::string, double>& geometric, const cid::SensorModel& sensor) {
  std::vector<double> t;
  std::vector<cid::SimulatedSample> sim;
  cid::ContactModel model;
  {
    const bool has_K = !K.is_none(), has_mu = !mu.is_none();
    const double K_value = has_K ? K.cast<double>() : 0.0, mu_value = has_mu ? mu.cast<double>() : 0.0;
    py::gil_scoped_release free;
    const auto rig = format::load_rig(rig_path.string());
    const auto scene = models::scene_from_rig(rig);
    model = models::model_from_rig(rig);
    if (has_K) model.K = K_value;
    if (has_mu) model.mu = mu_value;
    try {
      model.check();
    } catch (const std::invalid_argument& e) {
      throw py::value_error(std::string("K, mu: ") + e.what());
    }
    Eigen::VectorXd x_true;
    try {
      x_true = models::uncertainty_vector(scene, geometric, "geometric");
    } catch (const std::runtime_error& e) {
      throw py::value_error(e.what());  // "geometric: unknown geometric uncertainty ..."
    }
    auto traj = models::read_trajectory(trajectory.string());
    sim = cid::simulate(scene, model, x_true, traj.kin, sensor);
    t = std::move(traj.t);
  }
  const auto n = sim.size();
  auto rows = [&](auto get) { return matrix(n, 3, get); };
  py::dict d;
  d["t"] = column(n, [&](std::size_t i) { return t[i] - t[0]; });  // from the first sample, as a run
  d["p"] = rows([&](std::size_t i, std::size_t c) { return sim[i].kin.T_world_ee.translation()[static_cast<Eigen::Index>(c)]; });
  d["q"] = matrix(n, 4, [&](std::size_t i, std::size_t c) {
    const Eigen::Quaterniond q(sim[i].kin.T_world_ee.linear());
    return c == 0 ? q.w() : q.vec()[static_cast<Eigen::Index>(c - 1)];
  });
  d["v"] = rows([&](std::size_t i, std::size_t c) { return sim[i].kin.v_world_ee[static_cast<Eigen::Index>(c)]; });
  d["w"] = rows([&](std::size_t i, std::size_t c) { return sim[i].kin.w_world_ee[static_cast<Eigen::Index>(c)]; });
  d["f"] = rows([&](std::size_t i, std::size_t c) { return sim[i].w_fp[static_cast<Eigen::Index>(c)]; });
  d["m"] = rows([&](std::size_t i, std::size_t c) { return sim[i].w_fp[static_cast<Eigen::Index>(c + 3)]; });
  d["f_true"] = rows([&](std::size_t i, std::size_t c) { return sim[i].w_fp_true[static_cast<Eigen::Index>(c)]; });
  d["m_true"] = rows([&](std::size_t i, std::size_t c) { return sim[i].w_fp_true[static_cast<Eigen::Index>(c + 3)]; });
  d["contacts"] = column(n, [&](std::size_t i) { return static_cast<double>(sim[i].contacts); });
  d["K"] = model.K;
  d["mu"] = model.mu;
  return d;
}

}  // namespace

void add_numerics(py::module_& m) {
  m.def("identify_contact", &identify_contact, py::arg("run"), py::arg("rig") = "", py::arg("geometric") = false,
        py::arg("lambda_") = "auto", py::arg("solver") = "lm", py::arg("jacobian") = "golub-pereyra", py::arg("window") = 25,
        py::arg("lcurve_points") = 30, py::arg("include_weak") = false,
        "Contact stiffness K (N/m) and friction mu of a run against its rig, as `hil contact identify --json`, "
        "plus K_ci95 / mu_ci95 (95 % intervals), fit (measured, model and residual plate wrench per sample in "
        "contact), instantaneous and window estimates.");
  m.def("diagnose", &diagnose, py::arg("path"), py::arg("rig") = "", py::arg("candidates") = std::vector<std::string>{},
        py::arg("folds") = 5, py::arg("progress") = py::none(), py::arg("cv_offsets") = 0,
        "The diagnosis of a run folder (or of a stiffness table with rig=), as `hil diagnose --json`: cause, "
        "second_cause, candidates with held-out gain, the extended model's parameters with intervals. "
        "progress(step, total, what) is called before each step; Ctrl-C stops between steps. cv_offsets: "
        "offsets of the block grid the cross-validation is repeated over (0: 8 with rest_change, else 1).");
  m.def(
      "simulate_contact",
      [](const Path& rig, const Path& trajectory, const py::object& K, const py::object& mu, const std::map<std::string, double>& geometric,
         double position_resolution_m, double velocity_resolution_m_per_s, double force_resolution_n, double moment_resolution_nm,
         double force_noise_n, double moment_noise_nm, unsigned seed) {
        const double v[] = {position_resolution_m, velocity_resolution_m_per_s, force_resolution_n, moment_resolution_nm, force_noise_n,
                            moment_noise_nm};
        for (double x : v)
          if (!(x >= 0.0) || !std::isfinite(x)) throw py::value_error("sensor resolutions and noise: expected finite values >= 0");
        return simulate_contact(rig, trajectory, K, mu, geometric,
                                {position_resolution_m, velocity_resolution_m_per_s, force_resolution_n, moment_resolution_nm,
                                 force_noise_n, moment_noise_nm, seed});
      },
      py::arg("rig"), py::arg("trajectory"), py::arg("K") = py::none(), py::arg("mu") = py::none(),
      py::arg("geometric") = std::map<std::string, double>{}, py::arg("position_resolution_m") = 0.0,
      py::arg("velocity_resolution_m_per_s") = 0.0, py::arg("force_resolution_n") = 0.0, py::arg("moment_resolution_nm") = 0.0,
      py::arg("force_noise_n") = 0.0, py::arg("moment_noise_nm") = 0.0, py::arg("seed") = 1u,
      "The rig's contact scene along a trajectory CSV (t, px..qz[, vx..wz]), as `hil contact simulate`: the "
      "read_samples arrays as a sensor measures them (f, m quantised and noisy), f_true, m_true, contacts, K, mu. "
      "K and mu default to the rig's model; geometric: uncertainty name -> true value (m or rad).");
  m.def("identify_stiffness", &identify_stiffness, py::arg("table"), py::arg("rig"), py::arg("noise_pos_m") = 0.0,
        py::arg("noise_rot_rad") = 0.0, py::arg("neglect_below") = 2.0,
        "Elastostatic calibration of the rig's robot from a stiffness-experiment table, as "
        "`hil stiffness identify --json`: kept parameters with std, ci95 and PNR, reduction, ranks, residuals.");
  m.def("calibrate", &calibrate, py::arg("run"), py::arg("rig"), py::arg("candidates") = std::vector<std::string>{}, py::arg("folds") = 0,
        py::arg("bending_links") = std::vector<std::string>{}, py::arg("orientation") = false,
        "A calibration run (static postures, measured points) against the rig's robot, as `hil calibrate --json`: what the "
        "postures determine per model, the rigid fit with its station frames and tool point, every candidate's held-out error, "
        "the named cause and its fit. bending_links: the URDF links link_bending may bend (default: every link spanning 0.2 m "
        "or more); orientation: fit the run's measured orientations too.");
}

}  // namespace hil::python
