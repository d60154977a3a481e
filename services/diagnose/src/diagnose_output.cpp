#include <hil/services/diagnose_output.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <fstream>
#include <set>

#include <hil/error/error.hpp>
#include <hil/format/output.hpp>
#include <hil/models/stiffness_model.hpp>
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
                 {"std_sandwich", q.std_sandwich},
                 {"sandwich", q.sandwich},
                 {"sandwich_dof", q.sandwich_dof},
                 {"model_based", q.model_based},
                 {"std_components", q.std_components},
                 {"components_disagree", q.components_disagree},
                 {"errors_in_variables", q.errors_in_variables},
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

/// Whether a verdict names a candidate (not "none", not "unexplained").
bool names_a_cause(const std::string& cause) { return cause != "none" && cause != "unexplained"; }

/// The extensions of the extended model (the cause and the second cause).
std::set<std::string> extended_set(const RunDiagnosis& r) {
  std::set<std::string> e;
  if (names_a_cause(r.result.cause)) e.insert(r.result.cause);
  if (!r.result.second_cause.empty()) e.insert(r.result.second_cause);
  return e;
}

/// "stable: the same causes under all 9 settings" or "UNSTABLE: rest_change + ... under 4 of 9; ...".
std::string stability_text(const RunDiagnosis& r) {
  if (r.stable()) return fmt::format("stable: the same verdict under all {} settings", r.stability.size());
  std::map<std::string, int> seen;
  for (const auto& s : r.stability) {
    std::set<std::string> named{s.cause, s.second_cause};
    named.erase("");
    ++seen[s.error.empty() ? fmt::format("{}", fmt::join(named, " + ")) : "not diagnosed"];
  }
  std::vector<std::string> parts;
  for (const auto& [v, k] : seen) parts.push_back(fmt::format("{} under {} of {}", v, k, r.stability.size()));
  return fmt::format("UNSTABLE, the verdict changes with them: {}", fmt::join(parts, "; "));
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

std::string one_event_text(const dg::Reported& q) {
  if (q.model_based)
    return fmt::format("  one event's worth (ν {:.1f}): the model's std, which the folds and the component groups do not contradict",
                       q.sandwich_dof);
  if (!q.components_disagree.empty())
    return fmt::format("  one event's worth (ν {:.1f}), but {}: the interval reaches across theirs", q.sandwich_dof, q.components_disagree);
  return "";
}

void print_summary(std::ostream& out, const RunDiagnosis& r) {
  const auto& d = r.result;
  const auto& obs = r.obs();
  const auto& ext = extended_score(r);
  const std::string what = r.mode == "contact" ? "wrench" : "deflection";
  if (r.mode == "stiffness") out << fmt::format("Diagnosis of {} ({} loaded configurations, stiffness table)\n", r.run_name, obs.size());
  else
    out << fmt::format("Diagnosis of {} ({} samples{}, {:.1f} s, {} model)\n", r.run_name, obs.size(),
                       r.every > 1 ? fmt::format(", one in {} of {}", r.every, r.samples_in_run) : "", obs.t_s.back() - obs.t_s.front(),
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
  if (d.cause == "unexplained")
    for (const auto& f : nr.structure) out << "    structure:     " << f.text << "\n";
  if (!d.second_cause.empty()) out << fmt::format("  second cause:    {} — {}\n", d.second_cause, dg::describe_extension(d.second_cause));
  for (const auto& c : d.confounded)
    out << fmt::format("  confounded:      {} or {}: {}\n    to separate them: {}\n", c.cause, c.rival, c.evidence, c.experiment);
  if (d.extended) {
    // The std rules are the engine's (docs/diagnosis.md, "Intervals"); this line names them.
    out << "    (value ± 95 % interval, i.e. 1.96 std: the block sandwich's where every fold agrees with it,\n"
           "     the model's where one event carries the value and no fold contradicts it, else the wider of\n"
           "     the asymptotic std and the folds' spread; the model forms' shifts added.\n"
           "     PNR = |value - nominal| / asymptotic std)\n";
    for (const auto& f : ext.model_forms) out << "    model form covered: " << f << "\n";
    for (const auto& f : ext.model_forms_rejected) out << "    model form rejected by the run: " << f << "\n";
    if (!ext.model_form_taken.empty())
      out << (ext.model_form_weights.empty() ? "    values of the model form the run prefers: " : "    the model form the run prefers: ")
          << ext.model_form_taken << "\n";
    // One weight a line: the forms' assumptions are long, and the summary keeps its lines short.
    if (!ext.model_form_weights.empty()) {
      out << "    values averaged over the model forms, weighted by the run's likelihoods:\n";
      for (const auto& w : ext.model_form_weights) out << "      " << w << "\n";
    }
    // A refused correction reads "<variable>: not corrected, <why>" (engine.cpp).
    for (const auto& v : ext.errors_in_variables)
      out << (v.find(": not corrected") != std::string::npos ? "    errors in the variables: " : "    values corrected for the errors in: ")
          << v << "\n";
    for (const auto& q : ext.full.reported)
      if (q.extension)
        out << fmt::format("    {:<28} {}  (PNR {:.1f}){}\n", q.name, fmt_value(q.value, q.std, q.unit), q.pnr(), one_event_text(q));
    if (!ext.full.unidentifiable.empty())
      out << fmt::format("    not identifiable from this run, fixed at nominal: {}\n", unidentifiable_text(ext.full));
    for (const auto& e : located_events(r, extended_set(r)))
      out << fmt::format("    {:<28} {:.2f} s  (located between {:.2f} and {:.2f} s)\n", e.name, e.t_s, e.lower_s, e.upper_s);
    out << fmt::format("  extended model:  held-out relative {} error {:.2f} %  (gain {:.1f} %)\n", what, 100 * ext.cv_error,
                       d.gain_percent);
    // The same check on what the named model leaves (issue 32): a cause may stand in for part of
    // an effect outside the library.
    for (const auto& f : d.extended_residuals.structure) out << "    left unexplained: " << f.text << "\n";
  }
  // The nominal model's readings, and slow_slip's μ_s / μ, which its note tells the reader to read.
  for (const auto& q : ext.full.reported)
    if (!q.extension && (q.name == "K" || q.name == "mu" || q.name == "slow_slip_mu_ratio"))
      out << fmt::format("    {:<28} {}{}\n", q.name, fmt_value(q.value, q.std, q.unit), one_event_text(q));
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
  if (!r.windows.empty()) {
    out << fmt::format("  over time ({} windows):\n", r.windows.size());
    for (const auto& w : r.windows) {
      out << fmt::format("    {:>7.1f} - {:<7.1f} s {:>6} samples  ", w.start_s, w.end_s, w.samples);
      if (!w.error.empty()) out << "not diagnosed: " << w.error << "\n";
      else if (!names_a_cause(w.cause)) out << fmt::format("{:<22} {:.2f} %\n", w.cause, 100 * w.nominal_error);
      else
        out << fmt::format("{:<22} {:.2f} % -> {:.2f} % (gain {:.1f} %)\n", w.cause + (w.second_cause.empty() ? "" : "+" + w.second_cause),
                           100 * w.nominal_error, 100 * w.extended_error, w.gain_percent);
    }
  }
  if (!r.stability.empty()) {
    out << fmt::format("  verdict across cross-validation settings ({}):\n", stability_text(r));
    out << "    folds  offsets  verdict                                   gain\n";
    for (const auto& s : r.stability)
      out << fmt::format("    {:>5}  {:>7}  {:<40}  {}\n", s.folds, s.cv_offsets,
                         s.error.empty() ? s.cause + (s.second_cause.empty() ? "" : " + " + s.second_cause) : "not diagnosed: " + s.error,
                         s.error.empty() && names_a_cause(s.cause) ? fmt::format("{:.1f} %", s.gain_percent) : "-");
  }
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
  if (r.mode != "stiffness") j["samples_in_run"] = r.samples_in_run, j["every"] = r.every;
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
      x["correlations"].push_back(
          {{"signal", c.signal}, {"component", c.component}, {"correlation", c.correlation}, {"lag", c.lag}, {"explained", c.explained}});
    }
    x["excess_variance"] = a.excess_variance;
    x["trends"] = nlohmann::json::array();
    for (const auto& c : a.trends)
      x["trends"].push_back({{"component", c.component}, {"correlation", c.correlation}, {"explained", c.explained}});
    x["structure"] = nlohmann::json::array();
    for (const auto& f : a.structure) x["structure"].push_back({{"kind", f.kind}, {"text", f.text}, {"size", f.size}});
    return x;
  };
  j["nominal"]["residuals"] = res(d.nominal_residuals);
  if (d.cause == "none") {
    j["cause"] = {{"name", "none"}, {"parameters", nlohmann::json::object()}};
  } else if (d.cause == "unexplained") {
    j["cause"] = {{"name", "unexplained"}, {"description", dg::describe_extension(d.cause)}, {"parameters", nlohmann::json::object()}};
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
                   {"model_forms_rejected", ext.model_forms_rejected},
                   {"model_form_taken", ext.model_form_taken.empty() ? nlohmann::json() : nlohmann::json(ext.model_form_taken)},
                   {"model_form_weights", ext.model_form_weights},
                   {"errors_in_variables", ext.errors_in_variables},
                   {"residuals", res(d.extended_residuals)}};
  add_events(j["extended"]["parameters"], located_events(r, extended_set(r)));
  j["gain_percent"] = d.gain_percent;
  if (r.stability.empty()) {
    j["stability"] = nullptr;
  } else {
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& s : r.stability)
      rows.push_back({{"folds", s.folds},
                      {"cv_offsets", s.cv_offsets},
                      {"cause", s.error.empty() ? nlohmann::json(s.cause) : nlohmann::json(nullptr)},
                      {"second_cause", s.second_cause.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.second_cause)},
                      {"gain_percent", std::isfinite(s.gain_percent) ? nlohmann::json(s.gain_percent) : nlohmann::json(nullptr)},
                      {"error", s.error.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.error)}});
    j["stability"] = {{"stable", r.stable()}, {"summary", stability_text(r)}, {"rows", rows}};
  }
  j["confounded"] = nlohmann::json::array();
  for (const auto& c : d.confounded)
    j["confounded"].push_back({{"cause", c.cause},
                               {"rival", c.rival},
                               {"cause_gain_percent", c.cause_gain_percent},
                               {"rival_gain_percent", c.rival_gain_percent},
                               {"z", c.z},
                               {"cosine", c.cosine},
                               {"evidence", c.evidence},
                               {"experiment", c.experiment}});
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
                   {"effect_noise_variances_in_sample",
                    std::isfinite(c.effect_fraction_in_sample) ? nlohmann::json(c.effect_fraction_in_sample) : nlohmann::json(nullptr)},
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
  if (!r.windows.empty()) {
    auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
    auto str = [](const std::string& v) { return v.empty() ? nlohmann::json(nullptr) : nlohmann::json(v); };
    j["windows"] = nlohmann::json::array();
    for (const auto& w : r.windows)
      j["windows"].push_back({{"start_s", w.start_s},
                              {"end_s", w.end_s},
                              {"samples", w.samples},
                              {"cause", str(w.cause)},
                              {"second_cause", str(w.second_cause)},
                              {"relative_error", num(w.nominal_error)},
                              {"extended_relative_error", num(w.extended_error)},
                              {"gain_percent", num(w.gain_percent)},
                              {"white", w.error.empty() ? nlohmann::json(w.white) : nlohmann::json(nullptr)},
                              {"error", str(w.error)}});
  }
  j["notes"] = r.notes;
  j["seconds"] = d.seconds;
  return j;
}

TruthValues read_truth(const std::string& path, const RunDiagnosis& r) {
  const nlohmann::json j = models::load_json(path);
  if (!j.is_object() || !j.contains("format") || j["format"] != "hil.hidden_effects")
    throw error::FormatError({path, 0, 0, "format"}, "not a hidden-effects file (hil contact simulate --truth-out writes one)");
  TruthValues t;
  const auto& comp = r.obs().component;
  for (const auto& [key, v] : j.items()) {
    if (v.is_number() && key != "format_version" && key != "effect_seed") t[key] = v.get<double>();
    // Per-channel effects as six numbers, reported per component (bias_fx, gain_mz).
    if (v.is_array() && v.size() == comp.size() && (key == "sensor_bias" || key == "sensor_gain"))
      for (std::size_t c = 0; c < comp.size(); ++c)
        if (v[c].is_number()) t[(key == "sensor_bias" ? "bias_" : "gain_") + comp[c]] = v[c].get<double>();
  }
  if (j.contains("geometric") && j["geometric"].is_object())
    for (const auto& [key, v] : j["geometric"].items())
      if (v.is_number()) t[key] = v.get<double>();
  return t;
}

namespace {

constexpr double kZ95 = 1.96;

/// The held-out gain's 95 % interval (percent) from the paired z of the per-sample squared-error
/// reduction: the reduction of the mean squared error g2 = 1 - (1 - g)² has standard error g2 / z;
/// its interval maps back through g = 1 - sqrt(1 - g2). NaN when z is not known.
std::pair<double, double> gain_interval(double gain_percent, double z) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!std::isfinite(z) || !std::isfinite(gain_percent) || z == 0.0) return {nan, nan};
  const double g = gain_percent / 100, g2 = 1 - (1 - g) * (1 - g), se = std::abs(g2 / z);
  auto back = [](double x) { return 100 * (1 - std::sqrt(std::max(0.0, 1 - std::min(x, 1.0)))); };
  return {back(g2 - kZ95 * se), back(g2 + kZ95 * se)};
}

/// Held-out blocks (the unshifted grid) in which `b` predicts better than `a`, and their number.
std::pair<int, int> blocks_won(const dg::Observations& obs, const dg::Score& a, const dg::Score& b, int folds) {
  int won = 0, n = 0;
  if (a.cv_prediction.rows() != static_cast<Eigen::Index>(obs.size()) || b.cv_prediction.rows() != a.cv_prediction.rows()) return {0, 0};
  for (const auto& block : dg::time_blocks(obs.size(), folds)) {
    if (block.empty()) continue;
    ++n;
    won += dg::relative_error(obs, b.cv_prediction, block) < dg::relative_error(obs, a.cv_prediction, block) ? 1 : 0;
  }
  return {won, n};
}

/// The held-out gain of `b` over `a` on each offset of the repeated CV's grid (offset 0 first).
std::vector<double> grid_gains(const dg::Observations& obs, const dg::Score& a, const dg::Score& b) {
  std::vector<int> all(obs.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  std::vector<double> g;
  if (a.cv_prediction.size() == 0 || b.cv_prediction.size() == 0) return g;
  g.push_back(100 * (1 - dg::relative_error(obs, b.cv_prediction, all) / dg::relative_error(obs, a.cv_prediction, all)));
  for (std::size_t i = 0; i < a.cv_shifted.size() && i < b.cv_shifted.size(); ++i)
    g.push_back(100 * (1 - dg::relative_error(obs, b.cv_shifted[i], all) / dg::relative_error(obs, a.cv_shifted[i], all)));
  return g;
}

/// The unit of a context signal (contact_context, deflection_context, the stiffness table's).
std::string signal_unit(const std::string& s) {
  static const std::map<std::string, std::string> u{{"speed", "m/s"},      {"acceleration", "m/s²"},
                                                    {"interference", "m"}, {"penetration_rate", "m/s"},
                                                    {"slip_speed", "m/s"}, {"load", "N"},
                                                    {"time", "s"},         {"px", "m"},
                                                    {"py", "m"},           {"pz", "m"},
                                                    {"vx", "m/s"},         {"vy", "m/s"},
                                                    {"vz", "m/s"}};
  if (const auto it = u.find(s); it != u.end()) return it->second;
  if (s.rfind("load_f", 0) == 0) return "N";
  if (s.rfind("load_m", 0) == 0) return "N m";
  if (s.size() >= 2 && s[0] == 'q' && std::isdigit(static_cast<unsigned char>(s[1]))) return "rad";
  return "";
}

std::string with_unit(const std::string& name, const std::string& unit) { return unit.empty() ? name : name + " (" + unit + ")"; }

int component_index(const dg::Observations& obs, const std::string& name) {
  for (std::size_t c = 0; c < obs.component.size(); ++c)
    if (obs.component[c] == name) return static_cast<int>(c);
  return -1;
}

/// "sensor_bias from 16.0 s (2 of 4 windows); none in 2; 1 not diagnosed": each window's verdict
/// in order of first appearance.
std::string windows_text(const std::vector<WindowVerdict>& windows) {
  std::vector<std::string> order;
  std::map<std::string, std::pair<double, int>> seen;  // label -> first start, count
  for (const auto& w : windows) {
    const std::string label = w.error.empty() ? w.cause + (w.second_cause.empty() ? "" : "+" + w.second_cause) : "not diagnosed";
    if (!seen.count(label)) order.push_back(label), seen[label] = {w.start_s, 0};
    ++seen[label].second;
  }
  std::vector<std::string> parts;
  for (const auto& l : order) {
    const auto [t, k] = seen[l];
    if (l == "none" || l == "unexplained" || l == "not diagnosed") parts.push_back(fmt::format("{} in {}", l, k));
    else parts.push_back(fmt::format("{} from {:.1f} s ({} of {} windows)", l, t, k, windows.size()));
  }
  return fmt::format("{}", fmt::join(parts, "; "));
}

/// The verdict block: what was found, how sure, what to do next.
report::Verdict make_verdict(const RunDiagnosis& r) {
  const auto& d = r.result;
  const auto& obs = r.obs();
  const auto& ext = extended_score(r);
  const std::string what = r.mode == "contact" ? "wrench" : "deflection";
  report::Verdict v;
  const auto& nr = d.nominal_residuals;
  if (names_a_cause(d.cause)) {
    v.kind = "cause";
    v.headline = "Named cause: " + d.cause + " — " + dg::describe_extension(d.cause) +
                 (d.second_cause.empty() ? "" : "; second cause: " + d.second_cause + " — " + dg::describe_extension(d.second_cause));
    for (const auto& c : d.confounded) v.headline += "; confounded with " + c.rival + " on this run (either may be the cause)";
  } else if (d.cause == "unexplained") {
    v.kind = "unexplained";
    v.headline = "Unexplained: no candidate explains it, yet the nominal residual has structure that the candidates tried do not name — " +
                 nr.structure_text();
  } else {
    v.kind = "none";
    v.headline = "No cause: the nominal model is within the measurement noise on this run";
  }
  const double span = obs.size() > 1 ? obs.t_s.back() - obs.t_s.front() : 0.0;
  v.facts.emplace_back("run", r.mode == "stiffness"
                                  ? fmt::format("{}: {} loaded configurations, stiffness table", r.run_name, obs.size())
                                  : fmt::format("{}: {} samples over {:.1f} s, {} model", r.run_name, obs.size(), span, r.mode));
  if (d.extended) {
    const double z = dg::paired_z(obs, d.nominal, ext);
    const auto [lo, hi] = gain_interval(d.gain_percent, z);
    v.facts.emplace_back("held-out error", fmt::format("{:.2f} % → {:.2f} % (relative {} error, nominal → {})", 100 * d.nominal.cv_error,
                                                       100 * ext.cv_error, what, ext.model));
    v.facts.emplace_back("gain", std::isfinite(lo)
                                     ? fmt::format("{:.1f} % (95 %: {:.1f} … {:.1f} %, paired z {:.1f})", d.gain_percent, lo, hi, z)
                                     : fmt::format("{:.1f} %", d.gain_percent));
    const auto [won, blocks] = blocks_won(obs, d.nominal, ext, r.folds);
    const auto g = grid_gains(obs, d.nominal, ext);
    std::string stab = fmt::format("better in {} of {} held-out blocks", won, blocks);
    if (g.size() > 1)
      stab += fmt::format("; over {} offsets of the CV grid the gain is {:.1f} … {:.1f} %", g.size(), *std::min_element(g.begin(), g.end()),
                          *std::max_element(g.begin(), g.end()));
    else stab += "; one CV grid (--cv-offsets N repeats it over N offsets)";
    v.facts.emplace_back("stability", stab);
  } else {
    v.facts.emplace_back("held-out error", fmt::format("{:.2f} % relative {} error; the noise alone ≈ {:.2f} %", 100 * d.nominal.cv_error,
                                                       what, 100 * d.noise_relative));
    const auto best = std::find_if(d.candidates.begin(), d.candidates.end(), [](const auto& c) { return std::isfinite(c.score.cv_error); });
    if (best != d.candidates.end())
      v.facts.emplace_back("best candidate", fmt::format("{}: gain {:+.1f} % — {}", best->name, best->gain_percent, best->verdict));
  }
  const auto& after = d.extended ? d.extended_residuals : nr;
  v.facts.emplace_back(d.extended ? "residual after" : "residual",
                       fmt::format("{} (Q {:.0f} against {:.0f}){}", after.white ? "white" : "not white", after.ljung_box_q,
                                   after.ljung_box_bound,
                                   after.correlations.empty()
                                       ? std::string()
                                       : fmt::format("; follows {} most (r = {:+.2f})", after.correlations.front().signal,
                                                     after.correlations.front().correlation)));
  if (after.structured()) v.facts.emplace_back(d.extended ? "left unexplained" : "structure", after.structure_text());
  if (!ext.full.unidentifiable.empty()) v.facts.emplace_back("not identifiable", unidentifiable_text(ext.full));
  if (!r.windows.empty()) v.facts.emplace_back("over time", windows_text(r.windows));
  if (!r.stability.empty()) v.facts.emplace_back("stability", stability_text(r));
  // What to do next.
  if (v.kind == "cause") {
    const auto cause = std::find_if(d.candidates.begin(), d.candidates.end(), [&](const auto& c) { return c.name == d.cause; });
    const auto [clo, chi] = cause != d.candidates.end() ? gain_interval(cause->gain_percent, cause->z) : std::pair{0.0, 0.0};
    std::string rival;
    for (const auto& c : d.candidates) {
      if (c.name == d.cause || !c.supported || !std::isfinite(c.gain_percent)) continue;
      const auto [lo, hi] = gain_interval(c.gain_percent, c.z);
      if (std::isfinite(hi) && std::isfinite(clo) && hi >= clo && lo <= chi) {
        rival = c.name;
        break;
      }
    }
    if (!d.confounded.empty())
      v.next = fmt::format("{} and {} explain this run about equally ({}): to separate them, record {} before acting on either.", d.cause,
                           d.confounded.front().rival, d.confounded.front().evidence, d.confounded.front().experiment);
    else if (!rival.empty())
      v.next = fmt::format("{} and {} explain this run about equally (their gains' intervals overlap): record a run whose motion "
                           "excites them differently before acting on {}.",
                           d.cause, rival, d.cause);
    else
      v.next = fmt::format("re-identify with the nominal model extended by {} (its parameters below), or remove the cause at the rig, "
                           "then diagnose again{}.",
                           d.cause, d.extended_residuals.structured() ? "" : ": the residual should stay unstructured");
    if (d.extended_residuals.structured())
      v.next += " The extended model leaves structure (" + d.extended_residuals.structure_text() +
                "): the cause may stand in for part of an effect outside the library; look there before acting on it.";
  } else if (const auto w = std::find_if(r.windows.begin(), r.windows.end(),
                                         [](const WindowVerdict& x) { return x.error.empty() && names_a_cause(x.cause); });
             w != r.windows.end()) {
    v.next = fmt::format("the windows name {} from {:.1f} s: a cause that appears during the run, which a model for the whole run "
                         "cannot hold — find what changed there, then diagnose the parts before and after it apart.",
                         w->cause, w->start_s);
  } else if (v.kind == "unexplained") {
    v.next = nr.structure.empty() ? "look for an effect outside the candidates tried, or record a run that excites one effect at a time."
                                  : "look for an effect outside the candidates tried behind the strongest structure (" +
                                        nr.structure.front().text + "), or record a run that excites it alone.";
  } else {
    v.next = "nothing to change: keep the nominal model for this rig.";
  }
  return v;
}

}  // namespace

void write_report(const std::string& dir, const RunDiagnosis& r, const TruthValues& truth) {
  namespace rp = hil::report;
  const auto& d = r.result;
  const auto& obs = r.obs();
  const auto& ext = extended_score(r);
  const std::size_t n = obs.size();
  fs::create_directories(dir);
  rp::Page page("Diagnosis: " + r.run_name);
  page.verdict(make_verdict(r));
  auto comp = [&](int c) { return obs.component[static_cast<std::size_t>(c)]; };
  auto unit = [&](int c) { return obs.unit[static_cast<std::size_t>(c)]; };
  auto residual = [&](const dg::Score& s, int c) {
    std::vector<double> v(n);
    for (std::size_t k = 0; k < n; ++k) {
      const auto i = static_cast<Eigen::Index>(k);
      v[k] = s.cv_prediction.rows() == static_cast<Eigen::Index>(n) ? obs.y(i, c) - s.cv_prediction(i, c) : std::nan("");
    }
    return v;
  };

  if (!r.windows.empty()) {
    page.heading(fmt::format("Over time ({} windows)", r.windows.size()));
    page.paragraph("Each window diagnosed on its own, with the same candidates and folds: where a cause appears, drifts or goes.");
    std::vector<rp::Span> spans;
    std::vector<double> mid, en, ee;
    std::vector<std::vector<std::string>> rows;
    for (const auto& w : r.windows) {
      const bool ok = w.error.empty();
      const std::string label = ok ? w.cause + (w.second_cause.empty() ? "" : "+" + w.second_cause) : "not diagnosed";
      spans.push_back({w.start_s, w.end_s, label,
                       !ok                       ? w.error
                       : !names_a_cause(w.cause) ? fmt::format("{:.2f} %", 100 * w.nominal_error)
                                                 : fmt::format("gain {:.0f} %", w.gain_percent)});
      mid.push_back(0.5 * (w.start_s + w.end_s));
      en.push_back(100 * w.nominal_error), ee.push_back(100 * w.extended_error);
      rows.push_back({fmt::format("{:.1f} – {:.1f}", w.start_s, w.end_s), std::to_string(w.samples), label,
                      ok ? fmt::format("{:.3f} %", 100 * w.nominal_error) : "-", ok ? fmt::format("{:.3f} %", 100 * w.extended_error) : "-",
                      ok && names_a_cause(w.cause) ? fmt::format("{:+.1f} %", w.gain_percent) : "-",
                      ok ? (w.white ? "white" : "not white") : "-", w.error});
    }
    rp::PlotOptions to("Verdict per window", "t (s)", "");
    to.wide = true;
    to.width = 1440;
    page.timeline(spans, to);
    page.plot({{"nominal", mid, en, "#d62728", true, false, 4.0}, {"with the window's cause", mid, ee, "#1f77b4", true, false, 4.0}},
              {"Held-out error per window", "window centre, t (s)", "relative error (%)"});
    page.table({"window (s)", "samples", "verdict", "nominal error", "extended error", "gain", "nominal residual", "why not diagnosed"},
               rows);
  }

  page.heading("Candidates");
  page.paragraph("Each candidate extends the nominal model; each is fitted and scored on held-out time blocks (blocked "
                 "cross-validation). Intervals are 95 %, from the paired z of the per-sample error reduction.");
  {
    std::vector<std::vector<std::string>> rows;
    std::vector<std::size_t> em;
    rows.push_back({"nominal", fmt::format("{:.3f} %", 100 * d.nominal.cv_error), "", "", "", "", "", "reference"});
    rp::Bars bars;
    bars.series = {"held-out error"};
    bars.colors = {"#1f77b4"};
    bars.value.resize(1), bars.lower.resize(1), bars.upper.resize(1);
    bars.groups.push_back("nominal");
    bars.value[0].push_back(100 * d.nominal.cv_error);
    bars.lower[0].push_back(std::nan("")), bars.upper[0].push_back(std::nan(""));
    for (const auto& c : d.candidates) {
      const auto [lo, hi] = gain_interval(c.gain_percent, c.z);
      if (c.name == d.cause) em.push_back(rows.size());
      rows.push_back({c.name, percent_cell(c.score.cv_error, "{:.3f} %"), percent_cell(c.gain_percent / 100, "{:+.1f} %"),
                      std::isfinite(lo) ? fmt::format("{:+.1f} … {:+.1f} %", lo, hi) : "-",
                      std::isfinite(c.z) ? fmt::format("{:.1f}", c.z) : "-", fmt::format("{:.1f}", c.pnr),
                      std::isfinite(c.noise_fraction) ? fmt::format("{:.2f}", c.noise_fraction) : "-", c.verdict});
      bars.groups.push_back(c.name);
      const double e = 100 * c.score.cv_error;
      bars.value[0].push_back(std::isfinite(c.score.cv_error) ? e : std::nan(""));
      // The error's interval from the gain's: e = e_nominal (1 - gain).
      bars.lower[0].push_back(std::isfinite(hi) ? 100 * d.nominal.cv_error * (1 - hi / 100) : std::nan(""));
      bars.upper[0].push_back(std::isfinite(lo) ? 100 * d.nominal.cv_error * (1 - lo / 100) : std::nan(""));
    }
    page.table({"candidate", "held-out error", "gain", "gain, 95 %", "z", "max PNR", "size (noise variances)", "verdict"}, rows, em);
    rp::PlotOptions bo("Held-out error of each candidate (95 % interval)", "held-out relative error (%)", "");
    page.bars(bars, bo);
    if (!d.second_step.empty()) {
      rows.clear();
      em.clear();
      for (const auto& c : d.second_step) {
        if (c.name == d.second_cause) em.push_back(rows.size());
        rows.push_back({d.cause + " + " + c.name, percent_cell(c.score.cv_error, "{:.3f} %"),
                        percent_cell(c.gain_percent / 100, "{:+.1f} %"), std::isfinite(c.z) ? fmt::format("{:.1f}", c.z) : "-", c.verdict});
      }
      page.heading("Second step (greedy forward selection)", 3);
      page.table({"model", "held-out error", "gain over the cause", "z", "verdict"}, rows, em);
    }
  }

  page.heading(d.extended ? "Parameters of the extended model (" + ext.model + ")" : "Parameters of the nominal model");
  {
    std::vector<std::vector<std::string>> rows;
    std::vector<rp::Interval> forest;
    bool any_truth = false;
    for (const auto& q : ext.full.reported) {
      const double lo = q.value - kZ95 * q.std, hi = q.value + kZ95 * q.std;
      const auto t = truth.find(q.name);
      rows.push_back({q.name, fmt::format("{:.5g}", q.value), fmt::format("{:.5g} … {:.5g}", lo, hi), q.unit,
                      fmt::format("{:.1f}", q.pnr()), q.pnr() >= 5 ? "✓ (PNR ≥ 5)" : "weak (PNR < 5)",
                      q.extension ? "extension" : "nominal", t != truth.end() ? fmt::format("{:.5g}", t->second) : ""});
      // An extension's nominal value is "no effect": worth a tick; a nominal parameter's is not.
      rp::Interval iv{q.name, q.unit, q.value, lo, hi, q.extension ? q.nominal : rp::kNoValue, t != truth.end() ? t->second : rp::kNoValue};
      any_truth = any_truth || t != truth.end();
      forest.push_back(iv);
    }
    for (const auto& u : ext.full.unidentifiable)
      rows.push_back({u.name, "fixed", "-", "", "-", "✗ not identifiable" + (u.reason.empty() ? std::string() : ": " + u.reason), "", ""});
    std::vector<std::string> header{"parameter", "value", "95 % interval", "unit", "PNR", "identifiable", "part"};
    if (any_truth) header.push_back("truth");
    else
      for (auto& row : rows) row.pop_back();
    page.table(header, rows);
    page.paragraph("The interval is 1.96 std, the wider of the asymptotic and the folds' spread, with the model forms' shifts added; "
                   "PNR = |value − nominal| / asymptotic std." +
                   std::string(any_truth ? " The truth is the hidden-effects file's (--truth); the diagnosis did not read it." : ""));
    page.forest(forest, "Parameters: value and 95 % interval", "nominal");
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

  const auto& nr = d.nominal_residuals;
  const int worst = nr.worst_component;
  const bool table_rows = r.mode == "stiffness";
  const std::string xname = table_rows ? "configuration (row)" : "t (s)";
  std::vector<double> xs = obs.t_s;
  if (table_rows)
    for (std::size_t k = 0; k < n; ++k) xs[k] = static_cast<double>(k + 1);
  page.heading("Residual structure (nominal model, held out)");
  page.paragraph(fmt::format("What the verdict rests on: the nominal model's held-out residual of {} (its worst component), where in "
                             "time and in which state it sits, whether it is white, and what it follows.",
                             comp(worst)));
  {
    const auto rn = residual(d.nominal, worst);
    std::vector<rp::Series> by_state;
    if (!r.context.state.empty() && r.context.state.size() == n) {
      std::vector<std::string> labels;
      for (const auto& s : nr.states) labels.push_back(s.label);
      for (std::size_t i = 0; i < labels.size() && i < 7; ++i) {
        rp::Series sr(labels[i], {}, {}, "", true, false, 1.3);
        for (std::size_t k = 0; k < n; ++k)
          if (r.context.state[k] == labels[i]) sr.x.push_back(xs[k]), sr.y.push_back(rn[k]);
        by_state.push_back(std::move(sr));
      }
    } else {
      by_state.push_back(rp::Series("nominal residual", xs, rn, "#d62728", table_rows));
    }
    rp::PlotOptions o("Residual of " + comp(worst) + (by_state.size() > 1 ? " over time, by state" : ""), xname,
                      with_unit(comp(worst), unit(worst)));
    o.wide = true;
    o.width = 1440;  // drawn at about the page's width: text at its size
    o.height = 320;
    page.plot(by_state, o);
    std::vector<double> lag, ac_n, ac_e, hi, lo;
    const double bound = kZ95 / std::sqrt(static_cast<double>(std::max<std::size_t>(n, 1)));
    for (std::size_t i = 0; i < nr.autocorrelation.size(); ++i) {
      lag.push_back(static_cast<double>(i));
      ac_n.push_back(nr.autocorrelation[i]);
      ac_e.push_back(i < d.extended_residuals.autocorrelation.size() ? d.extended_residuals.autocorrelation[i] : std::nan(""));
      hi.push_back(bound), lo.push_back(-bound);
    }
    std::vector<rp::Series> ac{{"nominal", lag, ac_n, "#d62728", true, false, 3.0}};
    if (d.extended) ac.push_back({ext.model, lag, ac_e, "#1f77b4", true, false, 3.0});
    ac.push_back({"±1.96/√N (white)", lag, hi, "#888888", false, true});
    ac.push_back({"", lag, lo, "#888888", false, true});
    page.plot(ac,
              {fmt::format("Autocorrelation of the {} residual (Q {:.0f}, bound {:.0f})", comp(worst), nr.ljung_box_q, nr.ljung_box_bound),
               "lag (samples)", "autocorrelation"});
    // The residual against the two signals it follows most (distinct signals).
    std::vector<const dg::ResidualAnalysis::Correlation*> top;
    for (const auto& c : nr.correlations) {
      if (top.size() == 2) break;
      if (std::any_of(top.begin(), top.end(), [&](const auto* t) { return t->signal == c.signal; })) continue;
      if (r.context.signals.count(c.signal) && component_index(obs, c.component) >= 0) top.push_back(&c);
    }
    for (const auto* c : top) {
      const int ci = component_index(obs, c->component);
      const auto& sig = r.context.signals.at(c->signal);
      const auto rc = residual(d.nominal, ci);
      if (sig.size() != n) continue;
      page.plot({{"held-out residual", sig, rc, "#9467bd", true, false, 1.5}},
                {fmt::format("Residual of {} against {} (r = {:+.2f}, lag {})", c->component, c->signal, c->correlation, c->lag),
                 with_unit(c->signal, signal_unit(c->signal)), with_unit(c->component, unit(ci))});
    }
    std::vector<std::vector<std::string>> rows;
    for (int c = 0; c < 6; ++c)
      rows.push_back({comp(c), fmt::format("{:.4g} {}", nr.rms(c), unit(c)), fmt::format("{:.2f} %", 100 * nr.relative_rms(c)),
                      fmt::format("{:.4g} {}", d.extended_residuals.rms(c), unit(c))});
    page.heading("Per component", 3);
    page.table({"component", "nominal rms", "nominal relative", d.extended ? "extended rms" : "rms"}, rows,
               {static_cast<std::size_t>(worst)});
    rows.clear();
    for (const auto& s : nr.states)
      rows.push_back({s.label, std::to_string(s.samples), fmt::format("{:.2f} %", 100 * s.relative_error),
                      fmt::format("{:.0f} %", 100 * s.share)});
    if (!rows.empty()) {
      page.heading("Per state", 3);
      page.table({"state", "samples", "relative error", "share of the error"}, rows);
    }
    rows.clear();
    for (std::size_t i = 0; i < nr.correlations.size() && i < 10; ++i) {
      const auto& c = nr.correlations[i];
      rows.push_back({c.signal, c.component, fmt::format("{:+.3f}", c.correlation), std::to_string(c.lag)});
    }
    if (!rows.empty()) {
      page.heading("Correlations with the run's signals", 3);
      page.table({"signal", "residual", "correlation", "lag (samples)"}, rows);
    }
  }

  if (table_rows) {
    // A calibration engineer's view: each configuration's residual vector, before and after.
    page.heading("Residual vectors per configuration");
    const auto nominal_res = [&](int c) { return residual(d.nominal, c); };
    const auto ext_res = [&](int c) { return residual(ext, c); };
    std::array<std::vector<double>, 3> pn{nominal_res(0), nominal_res(1), nominal_res(2)}, pe{ext_res(0), ext_res(1), ext_res(2)};
    std::array<std::vector<double>, 3> rn{nominal_res(3), nominal_res(4), nominal_res(5)}, re{ext_res(3), ext_res(4), ext_res(5)};
    auto norm = [](const std::array<std::vector<double>, 3>& v, std::size_t k) {
      return std::sqrt(v[0][k] * v[0][k] + v[1][k] * v[1][k] + v[2][k] * v[2][k]);
    };
    // The residual's length per configuration, before and after, and the translation vectors'
    // ends in two planes (a target plot: the cloud shrinks when the model improves).
    std::vector<double> idx(n), tn(n), te(n), rnn(n), ree(n);
    for (std::size_t k = 0; k < n; ++k) {
      idx[k] = static_cast<double>(k + 1);
      tn[k] = 1e3 * norm(pn, k), te[k] = 1e3 * norm(pe, k), rnn[k] = 1e3 * norm(rn, k), ree[k] = 1e3 * norm(re, k);
    }
    auto mm = [](const std::vector<double>& v) {
      std::vector<double> o(v.size());
      for (std::size_t k = 0; k < v.size(); ++k) o[k] = 1e3 * v[k];
      return o;
    };
    const std::string after = d.extended ? ext.model : "nominal";
    page.paragraph("Held-out residuals (measured − predicted deflection, each configuration predicted by the fit without its block), "
                   "before (nominal) and after (" +
                   after + ").");
    page.plot({{"nominal", idx, tn, "#d62728", true, false, 2.5}, {after, idx, te, "#1f77b4", true, false, 2.5}},
              {"Translation residual per configuration", "configuration (row)", "|Δp| (mm)"});
    page.plot({{"nominal", idx, rnn, "#d62728", true, false, 2.5}, {after, idx, ree, "#1f77b4", true, false, 2.5}},
              {"Rotation residual per configuration", "configuration (row)", "|Δr| (mrad)"});
    page.plot({{"nominal", mm(pn[0]), mm(pn[1]), "#d62728", true, false, 2.5}, {after, mm(pe[0]), mm(pe[1]), "#1f77b4", true, false, 2.5}},
              {"Translation residual vectors, x-y plane", "Δx (mm)", "Δy (mm)"});
    page.plot({{"nominal", mm(pn[0]), mm(pn[2]), "#d62728", true, false, 2.5}, {after, mm(pe[0]), mm(pe[2]), "#1f77b4", true, false, 2.5}},
              {"Translation residual vectors, x-z plane", "Δx (mm)", "Δz (mm)"});
    // The worst configurations as a table (every one is in the figures' CSV files).
    std::vector<std::size_t> worst_rows(n);
    for (std::size_t k = 0; k < n; ++k) worst_rows[k] = k;
    std::sort(worst_rows.begin(), worst_rows.end(), [&](std::size_t a, std::size_t b) { return tn[a] > tn[b]; });
    worst_rows.resize(std::min<std::size_t>(n, 15));
    std::vector<std::vector<std::string>> rows;
    for (std::size_t k : worst_rows)
      rows.push_back({std::to_string(k + 1), fmt::format("{:+.3f}, {:+.3f}, {:+.3f}", 1e3 * pn[0][k], 1e3 * pn[1][k], 1e3 * pn[2][k]),
                      fmt::format("{:.3f}", tn[k]),
                      fmt::format("{:+.3f}, {:+.3f}, {:+.3f}", 1e3 * pe[0][k], 1e3 * pe[1][k], 1e3 * pe[2][k]),
                      fmt::format("{:.3f}", te[k]), fmt::format("{:.3f}", rnn[k]), fmt::format("{:.3f}", ree[k])});
    page.heading(fmt::format("The {} configurations with the largest nominal residual", worst_rows.size()), 3);
    page.table({"configuration", "nominal Δp (mm)", "|Δp|", after + " Δp (mm)", "|Δp|", "nominal |Δr| (mrad)", after + " |Δr| (mrad)"},
               rows);
  }

  page.heading("Measured and predicted");
  page.paragraph("Each time block is predicted by the model fitted on the other blocks (blocked cross-validation); components "
                 "in order of the nominal model's relative error.");
  std::vector<int> order{0, 1, 2, 3, 4, 5};
  std::sort(order.begin(), order.end(), [&](int a, int b) { return nr.relative_rms(a) > nr.relative_rms(b); });
  for (int c : order) {
    std::vector<double> m(n), nom(n), ex(n);
    for (std::size_t k = 0; k < n; ++k) {
      const auto i = static_cast<Eigen::Index>(k);
      m[k] = obs.y(i, c);
      nom[k] = d.nominal.cv_prediction(i, c);
      ex[k] = ext.cv_prediction(i, c);
    }
    std::vector<rp::Series> s{{"measured", xs, m, "#444444", table_rows}, {"nominal", xs, nom, "#d62728", table_rows, !table_rows}};
    if (d.extended) s.push_back({ext.model, xs, ex, "#1f77b4", table_rows});
    page.plot(s, {comp(c), xname, with_unit(comp(c), unit(c))});
  }
  if (!r.notes.empty()) {
    page.heading("Notes");
    for (const auto& note : r.notes) page.paragraph(note);
  }
  page.heading("Text summary");
  std::ostringstream summary;
  print_summary(summary, r);
  page.text_download("The summary as `hil diagnose` prints it", "diagnosis-" + r.run_name + ".txt", summary.str());
  page.write((fs::path(dir) / "index.html").string());
  page.write_figures((fs::path(dir) / "figures").string());
}

}  // namespace hil::services::diagnose
