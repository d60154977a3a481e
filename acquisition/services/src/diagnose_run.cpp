#include <hil/services/diagnose_run.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>

#include <hil/services/output.hpp>
#include <hil/format/error.hpp>
#include <hil/report/html.hpp>
#include <hil/rig/contact.hpp>
#include <hil/rig/stiffness.hpp>

namespace hil::services::diagnose {

namespace dg = hil::diagnose;
namespace cid = hil::contact_id;
namespace fs = std::filesystem;

namespace {

dg::Context contact_context(const dg::ContactData& d) {
  dg::Context ctx;
  const std::size_t n = d.obs.size();
  auto& s = ctx.signals;
  for (const char* k : {"speed", "acceleration", "interference", "penetration_rate", "slip_speed", "load", "time", "px",
                        "py", "pz", "vx", "vy", "vz"})
    s[k].resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const auto& kin = d.kin[k];
    const auto& cs = d.contacts[k];
    double delta = 0, rate = 0, slip = 0;
    bool sliding = false;
    for (const auto& c : cs) {
      delta += c.delta;
      rate += -cid::relative_velocity(d.scene, kin, c.point).dot(c.normal);
      slip = std::max(slip, c.slip_speed);
      sliding = sliding || !c.tangent.isZero();
    }
    ctx.state.push_back(cs.empty() ? "no contact"
                                   : fmt::format("{} contact{}, {}", cs.size(), cs.size() > 1 ? "s" : "", sliding ? "sliding" : "sticking"));
    s["speed"][k] = kin.v_world_ee.norm();
    const std::size_t a = k > 0 ? k - 1 : 0, b = k + 1 < n ? k + 1 : n - 1;
    s["acceleration"][k] = b > a ? (d.kin[b].v_world_ee - d.kin[a].v_world_ee).norm() / (d.obs.t_s[b] - d.obs.t_s[a]) : 0.0;
    s["interference"][k] = delta;
    s["penetration_rate"][k] = rate;
    s["slip_speed"][k] = slip;
    s["load"][k] = d.obs.y.row(static_cast<Eigen::Index>(k)).head<3>().norm();
    s["time"][k] = d.obs.t_s[k];
    for (int i = 0; i < 3; ++i) {
      s[std::string("p") + "xyz"[i]][k] = kin.T_world_ee.translation()[i];
      s[std::string("v") + "xyz"[i]][k] = kin.v_world_ee[i];
    }
  }
  return ctx;
}

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
std::string percent_cell(double fraction, const char* pattern) {
  return std::isfinite(fraction) ? fmt::format(fmt::runtime(pattern), 100 * fraction) : std::string("-");
}

std::string fmt_value(double v, double s, const std::string& unit) {
  return fmt::format("{:.4g} ± {:.2g}{}{}", v, 1.96 * s, unit.empty() ? "" : " ", unit);
}

const dg::Score& extended_score(const RunDiagnosis& r) { return r.result.extended ? *r.result.extended : r.result.nominal; }

nlohmann::json params_json(const dg::Fit& f, bool extension_only) {
  nlohmann::json p = nlohmann::json::object();
  for (const auto& q : f.reported) {
    if (extension_only && !q.extension) continue;
    p[q.name] = {{"value", q.value},
                 {"std", q.std},
                 {"std_asymptotic", q.std_asymptotic > 0 ? q.std_asymptotic : q.std},
                 {"std_folds", q.std_folds},
                 {"std_model_form", q.std_model_form},
                 {"unit", q.unit},
                 {"pnr", q.pnr()},
                 {"extension", q.extension}};
  }
  return p;
}

nlohmann::json unidentifiable_json(const dg::Fit& f) {
  nlohmann::json u = nlohmann::json::array();
  for (const auto& x : f.unidentifiable) u.push_back({{"name", x.name}, {"reason", x.reason}, {"collinear_with", x.collinear_with}});
  return u;
}

/// "gain_fx (collinear with muK), gain_fy (...)": the parameters fixed as not identifiable.
std::string unidentifiable_text(const dg::Fit& f) {
  std::vector<std::string> v;
  for (const auto& x : f.unidentifiable) v.push_back(x.reason.empty() ? x.name : x.name + " (" + x.reason + ")");
  return fmt::format("{}", fmt::join(v, ", "));
}

/// The extensions of the extended model (the cause and the second cause).
std::set<std::string> extended_set(const RunDiagnosis& r) {
  std::set<std::string> e;
  if (r.result.cause != "none") e.insert(r.result.cause);
  if (!r.result.second_cause.empty()) e.insert(r.result.second_cause);
  return e;
}

/// rest_change's events in the deflection model with the extensions `ext` (none without it). The
/// family locates them again on all samples: the search is deterministic, so they are those its
/// full fit used.
std::vector<dg::RestEvent> rest_events(const RunDiagnosis& r, std::set<std::string> ext) {
  if (!r.deflection || !ext.count("rest_change")) return {};
  return dg::DeflectionFamily(*r.deflection, std::move(ext)).events();
}

/// event_1_s ...: located, not fitted, so an interval (the samples around the change, or the χ²
/// profile of the split cost), not a standard deviation.
void add_events(nlohmann::json& params, const std::vector<dg::RestEvent>& events) {
  for (std::size_t e = 0; e < events.size(); ++e)
    params[fmt::format("event_{}_s", e + 1)] = {{"value", events[e].t_s},       {"lower", events[e].lower_s},
                                               {"upper", events[e].upper_s},   {"unit", "s"},
                                               {"first_sample", events[e].first_sample}, {"located", true}};
}

std::string events_text(const std::vector<dg::RestEvent>& events) {
  std::vector<std::string> v;
  for (std::size_t e = 0; e < events.size(); ++e)
    v.push_back(fmt::format("event_{}_s {:.2f} s ({:.2f} .. {:.2f})", e + 1, events[e].t_s, events[e].lower_s, events[e].upper_s));
  return v.empty() ? std::string("no event located") : fmt::format("{}", fmt::join(v, ", "));
}

}  // namespace

/// The --candidates asked for (all that apply when none), each checked against those that apply.
static std::vector<std::string> checked_candidates(const Options& o, const std::vector<std::string>& all) {
  for (const auto& c : o.candidates)
    if (std::find(all.begin(), all.end(), c) == all.end())
      throw format::FormatError({"command line", 0, 0, "--candidates"},
                                fmt::format("'{}' is not a candidate here (expected one of {})", c, fmt::join(all, ", ")));
  return o.candidates.empty() ? all : o.candidates;
}

/// Options::cv_offsets, its default resolved for these candidates.
static int cv_offsets(const Options& o, const std::vector<std::string>& candidates) {
  if (o.cv_offsets < 0) throw std::invalid_argument("diagnose: cv_offsets must be >= 0 (0: automatic), not " + std::to_string(o.cv_offsets));
  if (o.cv_offsets > 0) return o.cv_offsets;
  return std::find(candidates.begin(), candidates.end(), "rest_change") != candidates.end() ? 8 : 1;
}

RunDiagnosis diagnose_table(const std::string& table_path, const std::string& rig_path, const Options& o) {
  if (rig_path.empty()) throw format::FormatError({table_path, 0, 0, ""}, "a stiffness table needs --rig (the robot's rig file)");
  const calibration::VjmModel model(rig::load_robot(rig_path));
  const auto table = rig::read_stiffness_table(table_path, model.dof(), true);
  RunDiagnosis r;
  r.run_name = fs::path(table_path).filename().string();
  r.mode = "stiffness";
  const auto candidates = checked_candidates(o, dg::stiffness_extensions());
  dg::DiagnoseOptions dopt;
  dopt.cv.folds = o.folds;
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
    r.result = dg::diagnose([dp](const std::set<std::string>& e) { return std::make_unique<dg::StiffnessFamily>(*dp, e); },
                            candidates, r.obs(), r.context, dopt, o.progress);
  } catch (const std::exception& e) {
    throw std::runtime_error(table_path + ": " + e.what());
  }
  return r;
}

RunDiagnosis diagnose_run(const format::Run& run, const Options& o) {
  if (!run.rig) throw format::FormatError({run.dir, 0, 0, ""}, "no rig: pass --rig or put rig.yaml in the run folder");
  const auto& rig = *run.rig;
  RunDiagnosis r;
  r.run_name = fs::path(run.dir).filename().string();
  if (r.run_name.empty()) r.run_name = fs::path(run.dir).parent_path().filename().string();
  dg::DiagnoseOptions dopt;
  dopt.cv.folds = o.folds;
  dg::ModelFactory make;
  const auto candidates = checked_candidates(o, rig.model.contact ? dg::contact_extensions() : dg::deflection_extensions());
  dopt.cv.offsets = cv_offsets(o, candidates);
  if (dopt.cv.offsets > 1)
    r.notes.push_back(fmt::format("held-out errors are pooled over {} offsets of the {}-block grid (repeated blocked CV{}); "
                                  "the plotted held-out predictions are the unshifted grid's",
                                  dopt.cv.offsets, o.folds,
                                  o.cv_offsets > 0 ? "" : ": rest_change's events make a single grid's verdict depend on "
                                                          "where its block edges fall"));
  try {
    if (rig.model.contact) {
      r.mode = "contact";
      const auto scene = rig::scene_from_rig(rig);
      const auto model = rig::model_from_rig(rig);
      r.contact = std::make_unique<dg::ContactData>(dg::make_contact_data(
          scene, model.v_tm, rig::measurements(run.samples), rig.model.contact->force_scale_n, rig.model.contact->moment_scale_nm,
          o.damping_rates));
      r.context = contact_context(*r.contact);
      for (const auto& u : r.contact->unfit_uncertainties) r.notes.push_back("geometric_offset does not fit " + u);
      r.notes.push_back("contact_damping takes its " + r.contact->rate_source());
      const dg::ContactData* d = r.contact.get();
      make = [d](const std::set<std::string>& e) { return std::make_unique<dg::ContactFamily>(*d, e); };
    } else {
      r.mode = "deflection";
      std::vector<double> t;
      std::vector<cid::Kinematics> kin;
      std::vector<Eigen::Matrix<double, 6, 1>> w;
      for (const auto& m : rig::measurements(run.samples)) {
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
    r.result = dg::diagnose(make, candidates, r.obs(), r.context, dopt, o.progress);
  } catch (const format::FormatError&) {
    throw;
  } catch (const std::exception& e) {
    throw std::runtime_error(run.dir + ": " + e.what());
  }
  return r;
}

void print_summary(std::ostream& out, const RunDiagnosis& r) {
  const auto& d = r.result;
  const auto& obs = r.obs();
  const auto& ext = extended_score(r);
  const std::string what = r.mode == "contact" ? "wrench" : "deflection";
  if (r.mode == "stiffness")
    out << fmt::format("Diagnosis of {} ({} loaded configurations, stiffness table)\n", r.run_name, obs.size());
  else
    out << fmt::format("Diagnosis of {} ({} samples, {:.1f} s, {} model)\n", r.run_name, obs.size(),
                       obs.t_s.back() - obs.t_s.front(), r.mode);
  out << fmt::format("  nominal model:   held-out relative {} error {:.2f} %\n", what, 100 * d.nominal.cv_error);
  const auto& nr = d.nominal_residuals;
  out << fmt::format("  it gets wrong:   {} most (rms {:.3g} {}), ", obs.component[static_cast<std::size_t>(nr.worst_component)],
                     nr.rms(nr.worst_component), obs.unit[static_cast<std::size_t>(nr.worst_component)]);
  if (!nr.states.empty()) out << fmt::format("in state '{}' ({:.0f} % of the error), ", nr.states.front().label, 100 * nr.states.front().share);
  out << (nr.white ? "residual white" : "residual not white");
  if (!nr.correlations.empty())
    out << fmt::format(", follows {} ({:+.2f} on {})", nr.correlations.front().signal, nr.correlations.front().correlation,
                       nr.correlations.front().component);
  out << "\n";
  out << fmt::format("  cause:           {}{}\n", d.cause, d.cause == "none" ? "" : " — " + dg::describe_extension(d.cause));
  if (!d.second_cause.empty())
    out << fmt::format("  second cause:    {} — {}\n", d.second_cause, dg::describe_extension(d.second_cause));
  if (d.extended) {
    out << "    (value ± 95 % interval, i.e. 1.96 std, the wider of the asymptotic and the folds' spread,\n"
           "     with the model forms' shifts added; PNR = |value - nominal| / asymptotic std)\n";
    for (const auto& f : ext.model_forms)
      out << "    model form covered: " << f << "\n";
    for (const auto& q : ext.full.reported)
      if (q.extension)
        out << fmt::format("    {:<28} {}  (PNR {:.1f})\n", q.name, fmt_value(q.value, q.std, q.unit), q.pnr());
    if (!ext.full.unidentifiable.empty())
      out << fmt::format("    not identifiable from this run, fixed at nominal: {}\n", unidentifiable_text(ext.full));
    const auto events = rest_events(r, extended_set(r));
    for (std::size_t e = 0; e < events.size(); ++e)
      out << fmt::format("    {:<28} {:.2f} s  (located between {:.2f} and {:.2f} s)\n", fmt::format("event_{}_s", e + 1),
                         events[e].t_s, events[e].lower_s, events[e].upper_s);
    out << fmt::format("  extended model:  held-out relative {} error {:.2f} %  (gain {:.1f} %)\n", what, 100 * ext.cv_error,
                       d.gain_percent);
  }
  for (const auto& q : ext.full.reported)
    if (!q.extension && (q.name == "K" || q.name == "mu"))
      out << fmt::format("    {:<28} {}\n", q.name, fmt_value(q.value, q.std, q.unit));
  out << "  candidates (held-out error, gain, verdict):\n";
  for (const auto& c : d.candidates)
    out << fmt::format("    {:<20} {:>9} {:>9}  {}\n", c.name, percent_cell(c.score.cv_error, "{:.2f} %"),
                       percent_cell(c.gain_percent / 100, "{:+.1f} %"), c.verdict);
  for (const auto& c : d.candidates)
    if (c.name == "rest_change" && c.applicable && d.cause != c.name)  // as the cause, its events are listed above
      out << "  rest_change alone: " << events_text(rest_events(r, {c.name})) << "\n";
  for (const auto& c : d.second_step)
    if (c.name == "rest_change" && c.applicable)
      out << fmt::format("  {} + {:<10} {:>9} {:>9}  {}\n    {}\n", d.cause, c.name, percent_cell(c.score.cv_error, "{:.2f} %"),
                         percent_cell(c.gain_percent / 100, "{:+.1f} %"), c.verdict, events_text(rest_events(r, {d.cause, c.name})));
  for (const auto& n : r.notes) out << "  note: " << n << "\n";
  out << fmt::format("  ({:.1f} s)\n", d.seconds);
}

nlohmann::json to_json(const RunDiagnosis& r) {
  const auto& d = r.result;
  const auto& obs = r.obs();
  nlohmann::json j;
  tag_format(j, "diagnosis");
  j["run"] = r.run_name;
  j["mode"] = r.mode;
  j["samples"] = obs.size();
  j["nominal"] = {{"relative_error", d.nominal.cv_error},
                  {"train_relative_error", d.nominal.train_error},
                  {"parameters", params_json(d.nominal.full, false)}};
  auto res = [&](const dg::ResidualAnalysis& a) {
    nlohmann::json x;
    for (int c = 0; c < 6; ++c)
      x["rms"][obs.component[static_cast<std::size_t>(c)]] = {{"value", a.rms(c)}, {"unit", obs.unit[static_cast<std::size_t>(c)]},
                                                               {"relative", a.relative_rms(c)}};
    x["worst_component"] = obs.component[static_cast<std::size_t>(a.worst_component)];
    x["time_windows"] = nlohmann::json::array();
    for (std::size_t w = 0; w < a.window_share.size(); ++w)
      x["time_windows"].push_back({{"start_s", a.window_start_s[w]}, {"share", a.window_share[w]}});
    x["states"] = nlohmann::json::array();
    for (const auto& s : a.states)
      x["states"].push_back({{"state", s.label}, {"samples", s.samples}, {"relative_error", s.relative_error}, {"share", s.share}});
    x["whiteness"] = {{"ljung_box_q", a.ljung_box_q}, {"bound_99", a.ljung_box_bound}, {"white", a.white}};
    x["correlations"] = nlohmann::json::array();
    for (std::size_t i = 0; i < a.correlations.size() && i < 12; ++i) {
      const auto& c = a.correlations[i];
      x["correlations"].push_back({{"signal", c.signal}, {"component", c.component}, {"correlation", c.correlation}, {"lag", c.lag}});
    }
    return x;
  };
  j["nominal"]["residuals"] = res(d.nominal_residuals);
  if (d.cause == "none") {
    j["cause"] = {{"name", "none"}, {"parameters", nlohmann::json::object()}};
  } else {
    const auto& first = *std::find_if(d.candidates.begin(), d.candidates.end(), [&](const auto& c) { return c.name == d.cause; });
    j["cause"] = {{"name", d.cause}, {"description", dg::describe_extension(d.cause)}, {"parameters", params_json(first.score.full, true)}};
    add_events(j["cause"]["parameters"], rest_events(r, {d.cause}));
  }
  if (d.second_cause.empty()) {
    j["second_cause"] = nullptr;
  } else {
    j["second_cause"] = {{"name", d.second_cause}, {"description", dg::describe_extension(d.second_cause)}};
  }
  const auto& ext = extended_score(r);
  j["extended"] = {{"model", ext.model},
                   {"relative_error", ext.cv_error},
                   {"train_relative_error", ext.train_error},
                   {"parameters", params_json(ext.full, false)},
                   {"unidentifiable", unidentifiable_json(ext.full)},
                   {"model_forms", ext.model_forms},
                   {"residuals", res(d.extended_residuals)}};
  add_events(j["extended"]["parameters"], rest_events(r, extended_set(r)));
  j["gain_percent"] = d.gain_percent;
  auto table = [&](const std::vector<dg::CandidateResult>& v, bool second) {
    nlohmann::json t = nlohmann::json::array();
    for (const auto& c : v) {
      std::set<std::string> with{c.name};
      if (second) with.insert(d.cause);
      t.push_back({{"name", c.name},
                   {"relative_error", std::isfinite(c.score.cv_error) ? nlohmann::json(c.score.cv_error) : nlohmann::json(nullptr)},
                   {"scored_held_out", c.score.held_out()},
                   {"gain_percent", std::isfinite(c.gain_percent) ? nlohmann::json(c.gain_percent) : nlohmann::json(nullptr)},
                   {"z", std::isfinite(c.z) ? nlohmann::json(c.z) : nlohmann::json(nullptr)},
                   {"noise_variances", std::isfinite(c.noise_fraction) ? nlohmann::json(c.noise_fraction) : nlohmann::json(nullptr)},
                   {"effect_noise_variances",
                    std::isfinite(c.effect_fraction) ? nlohmann::json(c.effect_fraction) : nlohmann::json(nullptr)},
                   {"bic", c.score.bic},
                   {"aic", c.score.aic},
                   {"max_pnr", c.pnr},
                   {"supported", c.supported},
                   {"verdict", c.verdict},
                   {"parameters", params_json(c.score.full, true)},
                   {"unidentifiable", unidentifiable_json(c.score.full)}});
      if (c.applicable) add_events(t.back()["parameters"], rest_events(r, with));
    }
    return t;
  };
  j["candidates"] = table(d.candidates, false);
  j["second_step"] = table(d.second_step, true);
  j["nominal"]["bic"] = d.nominal.bic;
  j["notes"] = r.notes;
  j["seconds"] = d.seconds;
  return j;
}

void write_report(const std::string& dir, const RunDiagnosis& r) {
  namespace rp = hil::report;
  const auto& d = r.result;
  const auto& obs = r.obs();
  const auto& ext = extended_score(r);
  fs::create_directories(dir);
  rp::Page page("Diagnosis: " + r.run_name);
  std::ostringstream summary;
  print_summary(summary, r);
  page.heading("Summary");
  page.preformatted(summary.str());
  page.heading("Measured, nominal and extended (held-out predictions)");
  page.paragraph("Each time block is predicted by the model fitted on the other blocks (blocked cross-validation).");
  // The components in order of the nominal model's relative error.
  std::vector<int> order{0, 1, 2, 3, 4, 5};
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return d.nominal_residuals.relative_rms(a) > d.nominal_residuals.relative_rms(b);
  });
  for (int c : order) {
    std::vector<double> m(obs.size()), nom(obs.size()), ex(obs.size());
    for (std::size_t k = 0; k < obs.size(); ++k) {
      const auto i = static_cast<Eigen::Index>(k);
      m[k] = obs.y(i, c);
      nom[k] = d.nominal.cv_prediction(i, c);
      ex[k] = ext.cv_prediction(i, c);
    }
    const auto& name = obs.component[static_cast<std::size_t>(c)];
    page.plot({{"measured", obs.t_s, m, "#444444"}, {"nominal", obs.t_s, nom, "#d62728", false, true}, {ext.model, obs.t_s, ex, "#1f77b4"}},
              {name, "t (s)", obs.unit[static_cast<std::size_t>(c)]});
  }
  page.heading("Residuals over time");
  for (int c : {order[0], order[1]}) {
    std::vector<double> rn(obs.size()), re(obs.size());
    for (std::size_t k = 0; k < obs.size(); ++k) {
      const auto i = static_cast<Eigen::Index>(k);
      rn[k] = obs.y(i, c) - d.nominal.cv_prediction(i, c);
      re[k] = obs.y(i, c) - ext.cv_prediction(i, c);
    }
    const auto& name = obs.component[static_cast<std::size_t>(c)];
    page.plot({{"nominal", obs.t_s, rn, "#d62728"}, {ext.model, obs.t_s, re, "#1f77b4"}},
              {"residual " + name, "t (s)", obs.unit[static_cast<std::size_t>(c)]});
  }
  page.heading("Where the nominal model is wrong");
  {
    std::vector<std::vector<std::string>> rows;
    for (int c = 0; c < 6; ++c)
      rows.push_back({obs.component[static_cast<std::size_t>(c)],
                      fmt::format("{:.4g} {}", d.nominal_residuals.rms(c), obs.unit[static_cast<std::size_t>(c)]),
                      fmt::format("{:.2f} %", 100 * d.nominal_residuals.relative_rms(c)),
                      fmt::format("{:.4g} {}", d.extended_residuals.rms(c), obs.unit[static_cast<std::size_t>(c)])});
    page.table({"component", "nominal rms", "nominal relative", "extended rms"}, rows);
    rows.clear();
    for (const auto& s : d.nominal_residuals.states)
      rows.push_back({s.label, std::to_string(s.samples), fmt::format("{:.2f} %", 100 * s.relative_error), fmt::format("{:.0f} %", 100 * s.share)});
    if (!rows.empty()) page.table({"state", "samples", "relative error", "share of the error"}, rows);
    rows.clear();
    for (std::size_t i = 0; i < d.nominal_residuals.correlations.size() && i < 10; ++i) {
      const auto& c = d.nominal_residuals.correlations[i];
      rows.push_back({c.signal, c.component, fmt::format("{:+.3f}", c.correlation), std::to_string(c.lag)});
    }
    page.table({"signal", "residual", "correlation", "lag (samples)"}, rows);
    page.paragraph(fmt::format("Ljung-Box Q (20 lags) of the {} residual: {:.1f} against a 99 % bound of {:.1f}: {}.",
                               obs.component[static_cast<std::size_t>(d.nominal_residuals.worst_component)],
                               d.nominal_residuals.ljung_box_q, d.nominal_residuals.ljung_box_bound,
                               d.nominal_residuals.white ? "white" : "not white (structure left to explain)"));
    std::vector<double> lag, ac_n, ac_e;
    for (std::size_t i = 0; i < d.nominal_residuals.autocorrelation.size(); ++i) {
      lag.push_back(static_cast<double>(i));
      ac_n.push_back(d.nominal_residuals.autocorrelation[i]);
      ac_e.push_back(i < d.extended_residuals.autocorrelation.size() ? d.extended_residuals.autocorrelation[i] : 0.0);
    }
    page.plot({{"nominal", lag, ac_n, "#d62728", true}, {ext.model, lag, ac_e, "#1f77b4", true}},
              {"residual autocorrelation (worst component)", "lag (samples)", "-"});
  }
  page.heading("Candidate ranking");
  {
    std::vector<std::vector<std::string>> rows;
    rows.push_back({"nominal", fmt::format("{:.3f} %", 100 * d.nominal.cv_error), "", "", fmt::format("{:.0f}", d.nominal.bic), "", "reference"});
    for (const auto& c : d.candidates)
      rows.push_back({c.name, percent_cell(c.score.cv_error, "{:.3f} %"), percent_cell(c.gain_percent / 100, "{:+.1f} %"),
                      std::isfinite(c.z) ? fmt::format("{:.1f}", c.z) : "-", fmt::format("{:.0f}", c.score.bic), fmt::format("{:.1f}", c.pnr),
                      c.verdict});
    page.table({"candidate", "held-out error", "gain", "z", "BIC", "max PNR", "verdict"}, rows);
    std::vector<double> x, y;
    for (std::size_t i = 0; i < d.candidates.size(); ++i) {
      if (!std::isfinite(d.candidates[i].score.cv_error)) continue;
      x.push_back(static_cast<double>(i + 1));
      y.push_back(d.candidates[i].gain_percent);
    }
    page.plot({{"held-out gain by rank", x, y, "#2ca02c", true}}, {"held-out gain of each candidate (rank order)", "rank", "%"});
    if (!d.second_step.empty()) {
      rows.clear();
      for (const auto& c : d.second_step)
        rows.push_back({d.cause + " + " + c.name, percent_cell(c.score.cv_error, "{:.3f} %"), percent_cell(c.gain_percent / 100, "{:+.1f} %"),
                        std::isfinite(c.z) ? fmt::format("{:.1f}", c.z) : "-", c.verdict});
      page.heading("Second step (greedy forward selection)", 3);
      page.table({"model", "held-out error", "gain over the cause", "z", "verdict"}, rows);
    }
  }
  page.heading("Extended model parameters");
  {
    std::vector<std::vector<std::string>> rows;
    for (const auto& q : ext.full.reported)
      rows.push_back({q.name, fmt::format("{:.5g}", q.value), fmt::format("{:.2g}", q.std), q.unit, fmt::format("{:.1f}", q.pnr()),
                      q.extension ? "extension" : "nominal"});
    page.table({"parameter", "value", "std", "unit", "PNR", ""}, rows);
    if (!ext.full.unidentifiable.empty())
      page.paragraph("Not identifiable from this run (fixed at their nominal value, not estimated): " + unidentifiable_text(ext.full));
    const auto events = rest_events(r, extended_set(r));
    if (!events.empty()) {
      rows.clear();
      for (std::size_t e = 0; e < events.size(); ++e)
        rows.push_back({fmt::format("event_{}_s", e + 1), fmt::format("{:.2f}", events[e].t_s), fmt::format("{:.2f}", events[e].lower_s),
                        fmt::format("{:.2f}", events[e].upper_s)});
      page.heading("Located rest-pose changes (rest_change)", 3);
      page.paragraph("Located by a change-point search, not fitted: the interval is where the change can be (the samples "
                     "around it, widened by the split cost's 95 % profile), not a standard deviation.");
      page.table({"event", "time (s)", "from (s)", "to (s)"}, rows);
    }
  }
  for (const auto& n : r.notes) page.paragraph("Note: " + n);
  page.write((fs::path(dir) / "index.html").string());
  page.write_figures((fs::path(dir) / "figures").string());
}

}  // namespace hil::services::diagnose
