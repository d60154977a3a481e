#include <hil/services/diagnose_output.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>

#include <hil/format/output.hpp>
#include <hil/report/html.hpp>

// The outputs of a run's diagnosis (text summary, JSON, HTML report), apart from its set-up
// (diagnose_run.cpp): what is written changes without touching how the run is diagnosed.
namespace hil::services::diagnose {

namespace dg = hil::diagnose;
namespace fs = std::filesystem;

namespace {

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

/// Whether an effect of `ext` locates events from the data (Effect::locates_events).
bool locates_events(const std::set<std::string>& ext) {
  return std::any_of(ext.begin(), ext.end(), [](const std::string& e) {
    const dg::Effect* x = dg::find_effect(e);
    return x && x->locates_events();
  });
}

/// The events the model with the extensions `ext` locates (none when no effect of it locates any).
/// The family locates them again on all samples: the search is deterministic, so they are those its
/// full fit used.
std::vector<dg::LocatedEvent> located_events(const RunDiagnosis& r, const std::set<std::string>& ext) {
  if (!r.make || !locates_events(ext)) return {};
  return r.make(ext)->located_events();
}

/// event_1_s ...: located, not fitted, so an interval (the samples around the change, or the χ²
/// profile of the split cost), not a standard deviation.
void add_events(nlohmann::json& params, const std::vector<dg::LocatedEvent>& events) {
  for (const auto& e : events)
    params[e.name] = {{"value", e.t_s}, {"lower", e.lower_s}, {"upper", e.upper_s}, {"unit", "s"}, {"first_sample", e.first_sample},
                      {"located", true}};
}

std::string events_text(const std::vector<dg::LocatedEvent>& events) {
  std::vector<std::string> v;
  for (const auto& e : events) v.push_back(fmt::format("{} {:.2f} s ({:.2f} .. {:.2f})", e.name, e.t_s, e.lower_s, e.upper_s));
  return v.empty() ? std::string("no event located") : fmt::format("{}", fmt::join(v, ", "));
}

}  // namespace

void print_summary(std::ostream& out, const RunDiagnosis& r) {
  const auto& d = r.result;
  const auto& obs = r.obs();
  const auto& ext = extended_score(r);
  const std::string what = r.mode == "contact" ? "wrench" : "deflection";
  if (r.mode == "stiffness") out << fmt::format("Diagnosis of {} ({} loaded configurations, stiffness table)\n", r.run_name, obs.size());
  else
    out << fmt::format("Diagnosis of {} ({} samples, {:.1f} s, {} model)\n", r.run_name, obs.size(), obs.t_s.back() - obs.t_s.front(),
                       r.mode);
  out << fmt::format("  nominal model:   held-out relative {} error {:.2f} %\n", what, 100 * d.nominal.cv_error);
  const auto& nr = d.nominal_residuals;
  out << fmt::format("  it gets wrong:   {} most (rms {:.3g} {}), ", obs.component[static_cast<std::size_t>(nr.worst_component)],
                     nr.rms(nr.worst_component), obs.unit[static_cast<std::size_t>(nr.worst_component)]);
  if (!nr.states.empty())
    out << fmt::format("in state '{}' ({:.0f} % of the error), ", nr.states.front().label, 100 * nr.states.front().share);
  out << (nr.white ? "residual white" : "residual not white");
  if (!nr.correlations.empty())
    out << fmt::format(", follows {} ({:+.2f} on {})", nr.correlations.front().signal, nr.correlations.front().correlation,
                       nr.correlations.front().component);
  out << "\n";
  out << fmt::format("  cause:           {}{}\n", d.cause, d.cause == "none" ? "" : " — " + dg::describe_extension(d.cause));
  if (!d.second_cause.empty()) out << fmt::format("  second cause:    {} — {}\n", d.second_cause, dg::describe_extension(d.second_cause));
  if (d.extended) {
    out << "    (value ± 95 % interval, i.e. 1.96 std, the wider of the asymptotic and the folds' spread,\n"
           "     with the model forms' shifts added; PNR = |value - nominal| / asymptotic std)\n";
    for (const auto& f : ext.model_forms) out << "    model form covered: " << f << "\n";
    for (const auto& q : ext.full.reported)
      if (q.extension) out << fmt::format("    {:<28} {}  (PNR {:.1f})\n", q.name, fmt_value(q.value, q.std, q.unit), q.pnr());
    if (!ext.full.unidentifiable.empty())
      out << fmt::format("    not identifiable from this run, fixed at nominal: {}\n", unidentifiable_text(ext.full));
    for (const auto& e : located_events(r, extended_set(r)))
      out << fmt::format("    {:<28} {:.2f} s  (located between {:.2f} and {:.2f} s)\n", e.name, e.t_s, e.lower_s, e.upper_s);
    out << fmt::format("  extended model:  held-out relative {} error {:.2f} %  (gain {:.1f} %)\n", what, 100 * ext.cv_error,
                       d.gain_percent);
  }
  for (const auto& q : ext.full.reported)
    if (!q.extension && (q.name == "K" || q.name == "mu")) out << fmt::format("    {:<28} {}\n", q.name, fmt_value(q.value, q.std, q.unit));
  out << "  candidates (held-out error, gain, verdict):\n";
  for (const auto& c : d.candidates)
    out << fmt::format("    {:<20} {:>9} {:>9}  {}\n", c.name, percent_cell(c.score.cv_error, "{:.2f} %"),
                       percent_cell(c.gain_percent / 100, "{:+.1f} %"), c.verdict);
  for (const auto& c : d.candidates)
    if (locates_events({c.name}) && c.applicable && d.cause != c.name)  // as the cause, its events are listed above
      out << "  " << c.name << " alone: " << events_text(located_events(r, {c.name})) << "\n";
  for (const auto& c : d.second_step)
    if (locates_events({c.name}) && c.applicable)
      out << fmt::format("  {} + {:<10} {:>9} {:>9}  {}\n    {}\n", d.cause, c.name, percent_cell(c.score.cv_error, "{:.2f} %"),
                         percent_cell(c.gain_percent / 100, "{:+.1f} %"), c.verdict, events_text(located_events(r, {d.cause, c.name})));
  for (const auto& n : r.notes) out << "  note: " << n << "\n";
  out << fmt::format("  ({:.1f} s)\n", d.seconds);
}

nlohmann::json to_json(const RunDiagnosis& r) {
  const auto& d = r.result;
  const auto& obs = r.obs();
  nlohmann::json j;
  format::tag_format(j, "diagnosis");
  j["run"] = r.run_name;
  j["mode"] = r.mode;
  j["samples"] = obs.size();
  j["nominal"] = {{"relative_error", d.nominal.cv_error},
                  {"train_relative_error", d.nominal.train_error},
                  {"parameters", params_json(d.nominal.full, false)}};
  auto res = [&](const dg::ResidualAnalysis& a) {
    nlohmann::json x;
    for (int c = 0; c < 6; ++c)
      x["rms"][obs.component[static_cast<std::size_t>(c)]] = {{"value", a.rms(c)},
                                                              {"unit", obs.unit[static_cast<std::size_t>(c)]},
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
    add_events(j["cause"]["parameters"], located_events(r, {d.cause}));
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
  add_events(j["extended"]["parameters"], located_events(r, extended_set(r)));
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
      if (c.applicable) add_events(t.back()["parameters"], located_events(r, with));
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
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return d.nominal_residuals.relative_rms(a) > d.nominal_residuals.relative_rms(b); });
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
      rows.push_back({s.label, std::to_string(s.samples), fmt::format("{:.2f} %", 100 * s.relative_error),
                      fmt::format("{:.0f} %", 100 * s.share)});
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
    rows.push_back({"nominal", fmt::format("{:.3f} %", 100 * d.nominal.cv_error), "", "", fmt::format("{:.0f}", d.nominal.bic), "",
                    "reference"});
    for (const auto& c : d.candidates)
      rows.push_back({c.name, percent_cell(c.score.cv_error, "{:.3f} %"), percent_cell(c.gain_percent / 100, "{:+.1f} %"),
                      std::isfinite(c.z) ? fmt::format("{:.1f}", c.z) : "-", fmt::format("{:.0f}", c.score.bic),
                      fmt::format("{:.1f}", c.pnr), c.verdict});
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
        rows.push_back({d.cause + " + " + c.name, percent_cell(c.score.cv_error, "{:.3f} %"),
                        percent_cell(c.gain_percent / 100, "{:+.1f} %"), std::isfinite(c.z) ? fmt::format("{:.1f}", c.z) : "-", c.verdict});
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
    const auto ext_set = extended_set(r);
    const auto events = located_events(r, ext_set);
    if (!events.empty()) {
      rows.clear();
      for (const auto& e : events)
        rows.push_back({e.name, fmt::format("{:.2f}", e.t_s), fmt::format("{:.2f}", e.lower_s), fmt::format("{:.2f}", e.upper_s)});
      std::vector<std::string> locating;
      for (const auto& e : ext_set)
        if (locates_events({e})) locating.push_back(e);
      page.heading(fmt::format("Located events ({})", fmt::join(locating, ", ")), 3);
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
