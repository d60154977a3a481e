#include <hil/services/diagnose_run.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <stdexcept>

#include <hil/format/output.hpp>
#include <hil/error/error.hpp>
#include <hil/report/html.hpp>
#include <hil/models/contact.hpp>
#include <hil/models/stiffness.hpp>

namespace hil::services::diagnose {

namespace dg = hil::diagnose;
namespace cid = hil::contact_id;
namespace fs = std::filesystem;

namespace {

dg::Context deflection_context(const dg::DeflectionData& d) {
  dg::Context ctx;
  const char* names[6] = {"load_fx", "load_fy", "load_fz", "load_mx", "load_my", "load_mz"};
  for (int c = 0; c < 6; ++c) {
    auto& v = ctx.signals[names[c]];
    v.assign(d.load.col(c).data(), d.load.col(c).data() + d.load.rows());
  }
  ctx.signals["speed"] = d.speed_m_per_s;
  ctx.signals["time"] = d.obs.t_s;
  return ctx;
}

/// A fraction as a percentage with `pattern`, "-" when not computed (a candidate screened before
/// its held-out scoring).
}  // namespace

/// The --candidates asked for (all that apply when none), each checked against those that apply.
static std::vector<std::string> checked_candidates(const Options& o, const std::vector<std::string>& all) {
  for (const auto& c : o.candidates)
    if (std::find(all.begin(), all.end(), c) == all.end())
      throw error::FormatError({"command line", 0, 0, "--candidates"},
                               fmt::format("'{}' is not a candidate here (expected one of {})", c, fmt::join(all, ", ")));
  return o.candidates.empty() ? all : o.candidates;
}

/// Options::cv_offsets, its default resolved for these candidates (the most any of them asks for).
static int cv_offsets(const Options& o, const std::vector<std::string>& candidates) {
  if (o.cv_offsets < 0)
    throw std::invalid_argument("diagnose: cv_offsets must be >= 0 (0: automatic), not " + std::to_string(o.cv_offsets));
  if (o.cv_offsets > 0) return o.cv_offsets;
  return dg::default_cv_offsets(candidates);
}

/// Why the candidates asked for repeated CV (Effect::cv_offsets_reason), "" when none did.
static std::string cv_offsets_reasons(const std::vector<std::string>& candidates) {
  std::vector<std::string> why;
  for (const auto& c : candidates)
    if (const dg::Effect* e = dg::find_effect(c); e && e->cv_offsets() > 1 && !e->cv_offsets_reason().empty())
      why.push_back(e->cv_offsets_reason());
  return fmt::format("{}", fmt::join(why, "; "));
}

RunDiagnosis diagnose_table(const std::string& table_path, const std::string& rig_path, const Options& o) {
  if (rig_path.empty()) throw error::FormatError({table_path, 0, 0, ""}, "a stiffness table needs --rig (the robot's rig file)");
  const calibration::VjmModel model(models::load_robot(rig_path));
  const auto table = models::read_stiffness_table(table_path, model.dof(), true);
  RunDiagnosis r;
  r.run_name = fs::path(table_path).filename().string();
  r.mode = "stiffness";
  r.folds = o.folds;
  const auto candidates = checked_candidates(o, dg::stiffness_extensions());
  dg::DiagnoseOptions dopt;
  dopt.cv.folds = o.folds;
  dopt.cv.threads = o.threads;
  dopt.model_threads = o.threads == 1 ? 1 : 2;
  dopt.progress_detail = o.progress_detail;
  dopt.cv.offsets = cv_offsets(o, candidates);
  try {
    r.stiffness = std::make_unique<dg::StiffnessData>(dg::make_stiffness_data(model, table.rows));
    const auto& d = *r.stiffness;
    static const char* wn[6] = {"fx", "fy", "fz", "mx", "my", "mz"};
    for (int c = 0; c < 6; ++c) {
      std::vector<double> v;
      for (const auto& w : d.load) v.push_back(w(c));
      r.context.signals[std::string("load_") + wn[c]] = v;
    }
    for (int j = 0; j < model.dof(); ++j) {
      std::vector<double> v;
      for (const auto& m : table.rows) v.push_back(m.q_rad(j));
      r.context.signals["q" + std::to_string(j + 1)] = v;
    }
    r.notes.push_back("stiffness table: the rows stand for time (blocked folds hold out neighbouring rows, i.e. whole "
                      "configurations); nominal model: joint compliances only, rigid links");
    const dg::StiffnessData* dp = r.stiffness.get();
    r.make = [dp](const std::set<std::string>& e) { return std::make_unique<dg::StiffnessFamily>(*dp, e); };
    r.result = dg::diagnose(r.make, candidates, r.obs(), r.context, dopt, o.progress);
  } catch (const std::exception& e) {
    throw std::runtime_error(table_path + ": " + e.what());
  }
  return r;
}

RunDiagnosis diagnose_run(const format::Run& full_run, const Options& o) {
  if (!full_run.rig) throw error::FormatError({full_run.dir, 0, 0, ""}, "no rig: pass --rig or put rig.yaml in the run folder");
  const auto& rig = *full_run.rig;
  RunDiagnosis r;
  if (o.max_samples > 0 && o.max_samples < 20 * static_cast<std::size_t>(std::max(1, o.folds)))
    throw error::FormatError({"command line", 0, 0, "--max-samples"},
                             fmt::format("{} leaves fewer than 20 samples per fold of the {}: 0 (every sample) or at least {}",
                                         o.max_samples, o.folds, 20 * o.folds));
  r.samples_in_run = full_run.samples.size();
  std::optional<format::Run> thinned;
  if (o.max_samples > 0 && r.samples_in_run > o.max_samples) {
    r.every = (r.samples_in_run + o.max_samples - 1) / o.max_samples;
    thinned = every_nth(full_run, r.every);
    const auto& s = full_run.samples.samples;
    const double rate_hz = static_cast<double>(s.size() - 1) / (s.back().t_s - s.front().t_s);
    r.notes.push_back(fmt::format("diagnosed on one sample in {} of the run's {} ({} samples, {:.3g} Hz of {:.4g} Hz; at most {} "
                                  "by --max-samples, 0 for all): the intervals are those of the samples diagnosed",
                                  r.every, r.samples_in_run, thinned->samples.size(), rate_hz / static_cast<double>(r.every), rate_hz,
                                  o.max_samples));
  }
  const format::Run& run = thinned ? *thinned : full_run;
  r.folds = o.folds;
  r.run_name = fs::path(run.dir).filename().string();
  if (r.run_name.empty()) r.run_name = fs::path(run.dir).parent_path().filename().string();
  dg::DiagnoseOptions dopt;
  dopt.cv.folds = o.folds;
  dopt.cv.threads = o.threads;
  dopt.model_threads = o.threads == 1 ? 1 : 2;
  dopt.progress_detail = o.progress_detail;
  dg::ModelFactory make;
  const auto candidates = checked_candidates(o, rig.model.contact ? dg::contact_extensions() : dg::deflection_extensions());
  dopt.cv.offsets = cv_offsets(o, candidates);
  if (dopt.cv.offsets > 1)
    r.notes.push_back(fmt::format("held-out errors are pooled over {} offsets of the {}-block grid (repeated blocked CV{}); "
                                  "the plotted held-out predictions are the unshifted grid's",
                                  dopt.cv.offsets, o.folds,
                                  o.cv_offsets > 0 || cv_offsets_reasons(candidates).empty() ? "" : ": " + cv_offsets_reasons(candidates)));
  try {
    if (rig.model.contact) {
      r.mode = "contact";
      const auto scene = models::scene_from_rig(rig);
      const auto model = models::model_from_rig(rig);
      r.contact = std::make_unique<dg::ContactData>(dg::make_contact_data(scene, model.v_tm, models::measurements(run.samples),
                                                                          rig.model.contact->force_scale_n,
                                                                          rig.model.contact->moment_scale_nm, o.damping_rates));
      if (rig.devices.force_plate) r.contact->plate_gain_tolerance = rig.devices.force_plate->gain_tolerance;
      r.context = dg::contact_context(*r.contact);
      for (const auto& u : r.contact->unfit_uncertainties) r.notes.push_back("geometric_offset does not fit " + u);
      r.notes.push_back("contact_damping takes its " + r.contact->rate_source());
      // What the candidates' values are relative to on this run (a candidate the run cannot have
      // says so in its verdict instead).
      for (const auto& c : candidates) try {
          for (auto& n : dg::ContactFamily(*r.contact, {c}).notes()) r.notes.push_back(std::move(n));
        } catch (const std::runtime_error&) {
          // not applicable to this run: its verdict says why
        }
      const dg::ContactData* d = r.contact.get();
      make = [d](const std::set<std::string>& e) { return std::make_unique<dg::ContactFamily>(*d, e); };
    } else {
      r.mode = "deflection";
      std::vector<double> t;
      std::vector<cid::Kinematics> kin;
      std::vector<Eigen::Matrix<double, 6, 1>> w;
      for (const auto& m : models::measurements(run.samples)) {
        t.push_back(m.t_s);
        kin.push_back(m.kin);
        w.push_back(m.w_fp);
      }
      const Eigen::Isometry3d T_fp = rig.frame("force_plate") ? rig.T_world("force_plate") : Eigen::Isometry3d::Identity();
      r.deflection = std::make_unique<dg::DeflectionData>(dg::make_deflection_data(t, kin, w, T_fp));
      r.context = deflection_context(*r.deflection);
      r.notes.push_back("the rig has no contact model: the diagnosis explains the ee's motion from its rest pose "
                        "(rigid nominal model) by the load the force plate measures");
      const dg::DeflectionData* d = r.deflection.get();
      make = [d](const std::set<std::string>& e) { return std::make_unique<dg::DeflectionFamily>(*d, e); };
    }
    r.make = make;
    r.result = dg::diagnose(make, candidates, r.obs(), r.context, dopt, o.progress);
  } catch (const error::FormatError&) {
    throw;
  } catch (const std::exception& e) {
    throw std::runtime_error(run.dir + ": " + e.what());
  }
  return r;
}

namespace {

/// The samples of `run` that `keep(k)` keeps, the rest of the run as it is.
template <class Keep>
format::Run subset(const format::Run& run, Keep&& keep) {
  format::Run w;
  w.dir = run.dir;
  w.info = run.info;
  w.rig = run.rig;
  w.samples.file = run.samples.file;
  w.samples.extra_columns = run.samples.extra_columns;
  std::vector<Eigen::Index> rows;
  for (std::size_t k = 0; k < run.samples.size(); ++k) {
    if (!keep(k)) continue;
    w.samples.samples.push_back(run.samples.samples[k]);
    if (k < run.samples.line.size()) w.samples.line.push_back(run.samples.line[k]);
    rows.push_back(static_cast<Eigen::Index>(k));
  }
  w.samples.joints_rad.resize(static_cast<Eigen::Index>(rows.size()), run.samples.joints_rad.cols());
  for (std::size_t i = 0; i < rows.size() && run.samples.joints_rad.cols() > 0; ++i)
    w.samples.joints_rad.row(static_cast<Eigen::Index>(i)) = run.samples.joints_rad.row(rows[i]);
  return w;
}

/// The samples of `run` with t in [t0, t1).
format::Run slice(const format::Run& run, double t0, double t1) {
  return subset(run, [&](std::size_t k) {
    const double t = run.samples.samples[k].t_s;
    return t >= t0 && t < t1;
  });
}

}  // namespace

format::Run every_nth(const format::Run& run, std::size_t every) {
  if (every == 0) throw std::invalid_argument("every_nth: every must be >= 1");
  return subset(run, [every](std::size_t k) { return k % every == 0; });
}

std::vector<WindowVerdict> diagnose_windows(const format::Run& run, double window_s, const Options& o) {
  if (!(window_s > 0)) throw std::invalid_argument("diagnose: the window must be > 0 s, not " + std::to_string(window_s));
  std::vector<WindowVerdict> out;
  if (run.samples.size() == 0) return out;
  const double t_first = run.samples.samples.front().t_s, t_last = run.samples.samples.back().t_s;
  // Window edges; a tail shorter than half a window joins the last window.
  std::vector<double> edges{t_first};
  while (edges.back() + window_s < t_last) edges.push_back(edges.back() + window_s);
  if (edges.size() > 1 && t_last - edges.back() < 0.5 * window_s) edges.pop_back();
  edges.push_back(std::nextafter(t_last, std::numeric_limits<double>::infinity()));
  Options wo = o;
  wo.progress = {};
  for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
    WindowVerdict v;
    v.start_s = edges[i];
    v.end_s = std::min(edges[i + 1], t_last);
    const auto part = slice(run, edges[i], edges[i + 1]);
    v.samples = part.samples.size();
    if (o.progress)
      o.progress(static_cast<int>(i + 1), static_cast<int>(edges.size() - 1), fmt::format("window {:.1f}-{:.1f} s", v.start_s, v.end_s));
    try {
      if (v.samples < 20 * static_cast<std::size_t>(o.folds))
        throw std::runtime_error(fmt::format("{} samples: too few for {} folds", v.samples, o.folds));
      const auto d = diagnose_run(part, wo);
      v.cause = d.result.cause;
      v.second_cause = d.result.second_cause;
      v.nominal_error = d.result.nominal.cv_error;
      v.extended_error = d.result.extended ? d.result.extended->cv_error : d.result.nominal.cv_error;
      v.gain_percent = d.result.gain_percent;
      v.white = d.result.nominal_residuals.white;
    } catch (const std::exception& e) {
      // A window without contact or with too little data is reported, not fatal: the others stand.
      v.error = e.what();
      if (const auto at = v.error.find(run.dir + ": "); at == 0) v.error = v.error.substr(run.dir.size() + 2);
    }
    out.push_back(std::move(v));
  }
  return out;
}

std::vector<StabilityRow> verdict_stability(const format::Run& run, const Options& o, const std::vector<std::pair<int, int>>& grid) {
  if (grid.empty()) throw std::invalid_argument("diagnose: the stability grid is empty");
  for (const auto& [folds, offsets] : grid)
    if (folds < kMinFolds || folds > kMaxFolds || offsets < 1 || offsets > kMaxCvOffsets)
      throw std::invalid_argument(fmt::format("diagnose: stability setting {}:{} needs {}-{} folds and 1-{} offsets", folds, offsets,
                                              kMinFolds, kMaxFolds, kMaxCvOffsets));
  std::vector<StabilityRow> out;
  Options so = o;
  so.progress = {};
  for (std::size_t i = 0; i < grid.size(); ++i) {
    StabilityRow row;
    row.folds = grid[i].first;
    row.cv_offsets = grid[i].second;
    if (o.progress)
      o.progress(static_cast<int>(i + 1), static_cast<int>(grid.size()),
                 fmt::format("{} folds, {} grid offsets", row.folds, row.cv_offsets));
    so.folds = row.folds;
    so.cv_offsets = row.cv_offsets;
    try {
      const auto d = diagnose_run(run, so);
      row.cause = d.result.cause;
      row.second_cause = d.result.second_cause;
      row.gain_percent = d.result.gain_percent;
    } catch (const std::exception& e) {
      row.error = e.what();
    }
    out.push_back(std::move(row));
  }
  return out;
}

bool RunDiagnosis::stable() const {
  const std::set<std::string> named{result.cause, result.second_cause};
  for (const auto& r : stability)
    if (!r.error.empty() || std::set<std::string>{r.cause, r.second_cause} != named) return false;
  return true;
}

}  // namespace hil::services::diagnose
