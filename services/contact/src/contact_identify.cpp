#include <hil/services/contact_identify.hpp>
#include <hil/format/output.hpp>
#include <hil/error/error.hpp>
#include <hil/models/contact.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <hil/report/html.hpp>

namespace hil::services::contact {

namespace cid = hil::contact_id;

namespace {

constexpr double kZ95 = 1.959963984540054;

double parse_lambda(const std::string& s) {
  std::size_t pos = 0;
  double v = 0.0;
  try {
    v = std::stod(s, &pos);
  } catch (const std::exception&) {
    pos = 0;
  }
  if (pos != s.size() || !std::isfinite(v) || v < 0.0)
    throw std::runtime_error("--lambda: expected a number >= 0 or 'auto', got '" + s + "'");
  return v;
}

std::string unit_of(const cid::Uncertainty& u) { return u.kind == cid::Uncertainty::Kind::translation ? "m" : "rad"; }

nlohmann::json num_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

}  // namespace

std::vector<cid::Vector6d> model_plate_wrenches(const cid::ContactProblem& p, const Eigen::VectorXd& x, const Eigen::Vector2d& theta,
                                                std::vector<int>& counts) {
  Eigen::MatrixX2d A;
  p.regressor(x, A, &counts);
  Eigen::Vector2d th = theta;
  if (!std::isfinite(th[1])) th[1] = 0.0;  // μ not identifiable: all contacts stick, the column is zero
  const Eigen::VectorXd w = (A * th).cwiseQuotient(p.weights());
  std::vector<cid::Vector6d> out;
  for (std::size_t a = 0; a < p.used().size(); ++a) {
    const auto& m = p.data()[static_cast<std::size_t>(p.used()[a])];
    const Eigen::Isometry3d T = cid::body_pose(p.scene().bodies[0], m.kin.T_world_ee);
    out.push_back(cid::object1_to_plate(w.segment<6>(static_cast<Eigen::Index>(6 * a)), p.scene().T_world_fp, T));
  }
  return out;
}

cid::ContactProblem problem_from_run(const format::Run& run) {
  if (!run.rig) throw error::FormatError({run.dir, 0, 0, ""}, "no rig: pass --rig or put rig.yaml in the run folder");
  const auto& rig = *run.rig;
  if (!rig.model.contact) throw error::FormatError({rig.source, 0, 0, "model.contact"}, "the rig has no contact model");
  const auto scene = models::scene_from_rig(rig);
  const auto model = models::model_from_rig(rig);
  cid::ProblemOptions po;
  po.v_tm = model.v_tm;
  po.force_scale_n = rig.model.contact->force_scale_n;
  po.moment_scale_nm = rig.model.contact->moment_scale_nm;
  try {
    return cid::ContactProblem(scene, models::measurements(run.samples), po);
  } catch (const error::FormatError&) {
    throw;
  } catch (const std::exception& e) {
    throw std::runtime_error(run.dir + ": " + e.what());
  }
}

IdentifyResult identify(const cid::ContactProblem& p, const IdentifyOptions& o) {
  IdentifyResult r;
  const Eigen::VectorXd xd = p.scene().design();
  r.nominal = cid::global_estimate(p, xd);
  if (!r.nominal.note.empty()) r.notes.push_back(r.nominal.note);
  r.inst_nominal = cid::instantaneous(p, xd, 1);
  r.window_nominal = cid::instantaneous(p, xd, o.window);
  if (p.uncertainties() > 0) r.observability = cid::analyse_observability(p, xd);
  if (!o.geometric) return r;
  if (p.uncertainties() == 0) throw std::runtime_error("--geometric: the rig declares no geometric uncertainties (model.uncertainties)");
  cid::GeometricOptions g;
  g.solver = o.solver == "nm" ? cid::Solver::nelder_mead : cid::Solver::levenberg_marquardt;
  if (o.solver != "nm" && o.solver != "lm") throw std::runtime_error("--solver: expected lm or nm, got '" + o.solver + "'");
  g.jacobian = o.jacobian == "kaufman" ? cid::VpJacobian::kaufman : cid::VpJacobian::golub_pereyra;
  if (o.jacobian != "kaufman" && o.jacobian != "golub-pereyra")
    throw std::runtime_error("--jacobian: expected golub-pereyra or kaufman, got '" + o.jacobian + "'");
  g.fit.assign(static_cast<std::size_t>(p.uncertainties()), true);
  for (int j = 0; j < p.uncertainties(); ++j) {
    const auto& name = p.scene().uncertainties[static_cast<std::size_t>(j)].name;
    if (!p.touches(j)) {
      g.fit[static_cast<std::size_t>(j)] = false;
      r.notes.push_back("uncertainty '" + name +
                        "' is unobservable: its feature is never near a contact in this run; it stays at its design value");
    } else if (!o.include_weak && r.observability &&
               std::find(r.observability->weak.begin(), r.observability->weak.end(), name) != r.observability->weak.end()) {
      g.fit[static_cast<std::size_t>(j)] = false;
      r.notes.push_back("uncertainty '" + name +
                        "' is weakly observable (a prior std changes the regressor by < 1 %): not fitted, kept at its design value "
                        "(--include-weak fits it)");
    }
  }
  if (std::none_of(g.fit.begin(), g.fit.end(), [](bool b) { return b; }))
    throw std::runtime_error("--geometric: no geometric uncertainty is observable in this run (" +
                             std::string(o.include_weak ? "their features are never in contact"
                                                        : "never in contact or only weakly observable; --include-weak fits the weak ones") +
                             "): nothing to fit");
  const auto t0 = std::chrono::steady_clock::now();
  if (o.lambda == "auto") {
    // The L-curve is computed with the derivative-based solver (fast); the chosen λ is then solved
    // with the requested one.
    cid::GeometricOptions lc = g;
    lc.solver = cid::Solver::levenberg_marquardt;
    r.lcurve = cid::l_curve(p, lc, 1e-4, 1e3, o.lcurve_points);
    g.lambda = r.lcurve->lambda[r.lcurve->corner];
    const Eigen::VectorXd x0 = r.lcurve->x[r.lcurve->corner];
    r.geometric = cid::identify_geometry(p, g, g.solver == cid::Solver::levenberg_marquardt ? &x0 : nullptr);
  } else {
    g.lambda = parse_lambda(o.lambda);
    r.geometric = cid::identify_geometry(p, g);
  }
  r.seconds_geometric = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!r.geometric->theta.note.empty()) r.notes.push_back("after geometric identification: " + r.geometric->theta.note);
  r.inst_geometric = cid::instantaneous(p, r.geometric->x, 1);
  r.window_geometric = cid::instantaneous(p, r.geometric->x, o.window);
  return r;
}

void print(std::ostream& out, const cid::ContactProblem& p, const IdentifyResult& r) {
  const auto& sc = p.scene();
  out << fmt::format("contact identification: {} of {} samples in contact; weights F_max = {:.4g} N, M_max = {:.4g} N m\n", p.used().size(),
                     p.data().size(), p.force_scale(), p.moment_scale());
  auto theta = [&](const cid::LinearEstimate& e) {
    out << fmt::format("  K  = {:.5g} ± {:.3g} N/m   (95 %: [{:.5g}, {:.5g}])\n", e.K, e.K_std, e.K - kZ95 * e.K_std, e.K + kZ95 * e.K_std);
    if (e.mu_identifiable)
      out << fmt::format("  mu = {:.4f} ± {:.4f}      (95 %: [{:.4f}, {:.4f}])\n", e.mu, e.mu_std, e.mu - kZ95 * e.mu_std,
                         e.mu + kZ95 * e.mu_std);
    else out << "  mu: not identifiable\n";
    out << fmt::format("  rank {}, condition {:.3g}, mean relative force error {:.2f} %\n", e.rank, e.condition,
                       100.0 * e.relative_force_error);
  };
  out << "nominal geometry (x_u = x_u^d):\n";
  theta(r.nominal);
  if (r.observability) {
    const auto& o = *r.observability;
    out << "observability at x_u^d (Table 2: std of the sensitivity columns over std of the regressor columns):\n";
    out << fmt::format("  {:<18} {:>11} {:>11} {:>6}\n", "uncertainty", "column K", "column muK", "unit");
    for (int j = 0; j < p.uncertainties(); ++j) {
      const auto& u = sc.uncertainties[static_cast<std::size_t>(j)];
      out << fmt::format("  {:<18} {:>11.4g} {:>11.4g} {:>6}\n", u.name, o.ratio(j, 0), o.ratio(j, 1), "1/" + unit_of(u));
    }
    auto list = [&](const char* what, const std::vector<std::string>& v) {
      if (v.empty()) return;
      out << "  " << what << ":";
      for (const auto& s : v) out << " " << s << ";";
      out << "\n";
    };
    list("unobservable", o.unobservable);
    list("weakly observable", o.weak);
    if (!o.coupled.empty()) {
      out << "  coupled (|P1| and |P2| >= 0.85, observable only in combination):";
      for (const auto& [a, b] : o.coupled) out << " " << a << "~" << (b == "theta" ? "θ (absorbed by K, μK)" : b) << ";";
      out << "\n";
    }
    if (!o.projected_singular_values.empty())
      out << fmt::format("  projected sensitivity singular values (per prior std): max {:.3g}, min {:.3g}\n",
                         o.projected_singular_values.front(), o.projected_singular_values.back());
  }
  if (r.geometric) {
    const auto& g = *r.geometric;
    out << fmt::format("geometric identification (variable projection, lambda = {:.4g}{}; {} evaluations, {} Jacobians, {:.2f} s):\n",
                       g.lambda, r.lcurve ? " at the L-curve corner" : "", g.evaluations, g.jacobian_evaluations, r.seconds_geometric);
    for (int j = 0; j < p.uncertainties(); ++j) {
      const auto& u = sc.uncertainties[static_cast<std::size_t>(j)];
      if (!g.fitted[static_cast<std::size_t>(j)]) {
        out << fmt::format("  {:<18} {:>11.4g} {}   (not fitted, design value)\n", u.name, g.x[j], unit_of(u));
        continue;
      }
      out << fmt::format("  {:<18} {:>11.4g} ± {:.3g} {}   (95 %: [{:.4g}, {:.4g}])\n", u.name, g.x[j], g.x_std[j], unit_of(u),
                         g.x[j] - kZ95 * g.x_std[j], g.x[j] + kZ95 * g.x_std[j]);
    }
    theta(g.theta);
    out << fmt::format("mean relative force error: {:.2f} % nominal -> {:.2f} % with geometric identification\n",
                       100.0 * r.nominal.relative_force_error, 100.0 * g.theta.relative_force_error);
  }
  for (const auto& n : r.notes) out << "note: " << n << "\n";
}

nlohmann::json to_json(const cid::ContactProblem& p, const IdentifyResult& r) {
  using nlohmann::json;
  const auto& e = r.geometric ? r.geometric->theta : r.nominal;
  json j;
  format::tag_format(j, "contact_identification");
  j["K"] = num_or_null(e.K);
  j["K_std"] = num_or_null(e.K_std);
  j["mu"] = e.mu_identifiable ? num_or_null(e.mu) : json();
  j["mu_std"] = e.mu_identifiable ? num_or_null(e.mu_std) : json();
  j["mu_identifiable"] = e.mu_identifiable;
  j["rank"] = e.rank;
  j["condition"] = num_or_null(e.condition);
  j["relative_force_error"] = e.relative_force_error;
  j["relative_force_error_nominal"] = r.nominal.relative_force_error;
  j["samples"] = p.data().size();
  j["samples_in_contact"] = p.used().size();
  j["force_scale_n"] = p.force_scale();
  j["moment_scale_nm"] = p.moment_scale();
  j["nominal"] = {{"K", num_or_null(r.nominal.K)},
                  {"K_std", num_or_null(r.nominal.K_std)},
                  {"mu", r.nominal.mu_identifiable ? num_or_null(r.nominal.mu) : json()},
                  {"mu_std", r.nominal.mu_identifiable ? num_or_null(r.nominal.mu_std) : json()},
                  {"relative_force_error", r.nominal.relative_force_error}};
  j["geometric"] = json::object();
  j["geometric_std"] = json::object();
  j["lambda"] = json();
  if (r.geometric) {
    for (int k = 0; k < p.uncertainties(); ++k) {
      const auto& name = p.scene().uncertainties[static_cast<std::size_t>(k)].name;
      j["geometric"][name] = r.geometric->x[k];
      j["geometric_std"][name] = r.geometric->fitted[static_cast<std::size_t>(k)] ? json(r.geometric->x_std[k]) : json();
    }
    j["lambda"] = r.geometric->lambda;
    j["lambda_source"] = r.lcurve ? "l-curve corner" : "given";
    j["evaluations"] = r.geometric->evaluations;
    j["jacobian_evaluations"] = r.geometric->jacobian_evaluations;
  }
  if (r.lcurve) {
    j["l_curve"] = {{"lambda", r.lcurve->lambda},
                    {"force_cost", r.lcurve->force_cost},
                    {"geometric_cost", r.lcurve->geometric_cost},
                    {"corner", r.lcurve->corner}};
  }
  if (r.observability) {
    const auto& o = *r.observability;
    json t = json::object();
    for (int k = 0; k < p.uncertainties(); ++k)
      t[p.scene().uncertainties[static_cast<std::size_t>(k)].name] = {o.ratio(k, 0), o.ratio(k, 1)};
    json coupled = json::array();
    for (const auto& [a, b] : o.coupled) coupled.push_back({a, b});
    j["observability"] = {{"sensitivity_ratio", t}, {"unobservable", o.unobservable}, {"weak", o.weak}, {"coupled", coupled}};
  }
  j["notes"] = r.notes;
  return j;
}

void write_report(const std::string& dir, const std::string& run_name, const cid::ContactProblem& p, const IdentifyResult& r) {
  namespace rp = hil::report;
  std::filesystem::create_directories(dir);
  rp::Page page("Contact identification: " + run_name);
  std::vector<double> t;
  for (int k : p.used()) t.push_back(p.data()[static_cast<std::size_t>(k)].t_s);
  std::vector<int> n_nom, n_geo;
  const auto w_nom = model_plate_wrenches(p, p.scene().design(), r.nominal.theta, n_nom);
  std::vector<cid::Vector6d> w_geo;
  if (r.geometric) w_geo = model_plate_wrenches(p, r.geometric->x, r.geometric->theta.theta, n_geo);

  // The verdict: the identified parameters with intervals, the fit, and what to do next.
  const auto& best = r.geometric ? r.geometric->theta : r.nominal;
  const auto& sc = p.scene();
  {
    rp::Verdict v;
    v.kind = "identified";
    v.headline = fmt::format("K = {:.4g} N/m ± {:.2g}{}", best.K, kZ95 * best.K_std,
                             best.mu_identifiable ? fmt::format(", μ = {:.3f} ± {:.3f}", best.mu, kZ95 * best.mu_std)
                                                  : std::string(", μ not identifiable from this run"));
    if (r.geometric) v.headline += " with the geometry identified";
    v.facts.emplace_back("run", fmt::format("{}: {} of {} samples in contact", run_name, p.used().size(), p.data().size()));
    v.facts.emplace_back("force error", r.geometric
                                            ? fmt::format("{:.2f} % → {:.2f} % (mean relative; design geometry → identified)",
                                                          100 * r.nominal.relative_force_error, 100 * best.relative_force_error)
                                            : fmt::format("{:.2f} % (mean relative, design geometry)", 100 * best.relative_force_error));
    v.facts.emplace_back("conditioning", fmt::format("rank {}, condition {:.3g}", best.rank, best.condition));
    if (r.geometric) v.facts.emplace_back("λ", fmt::format("{:.3g}{}", r.geometric->lambda, r.lcurve ? " (L-curve corner)" : " (given)"));
    std::vector<std::string> unseen;
    if (r.observability) {
      for (const auto& u : r.observability->unobservable) unseen.push_back(u + " (unobservable)");
      for (const auto& u : r.observability->weak) unseen.push_back(u + " (weak)");
    }
    if (!unseen.empty()) v.facts.emplace_back("kept at design", fmt::format("{}", fmt::join(unseen, ", ")));
    const bool physical = best.K > 0 && (!best.mu_identifiable || best.mu >= 0);
    if (!physical) v.facts.emplace_back("physical validity", "violated: K must be > 0 and μ ≥ 0 — the model does not fit this run");
    v.next = !physical ? "check the rig's contact scene and the run's frames: a physically invalid estimate means the model's geometry "
                         "or the run's alignment is wrong."
             : !unseen.empty() ? "record motion that brings the unobserved features into contact, then identify again; run `hil diagnose` "
                                 "on this run to see what the contact model still misses."
                               : "run `hil diagnose` on this run to see what the contact model still misses.";
    page.verdict(v);
  }
  page.heading("Parameters");
  {
    std::vector<std::vector<std::string>> rows;
    std::vector<rp::Interval> forest;
    auto add = [&](const std::string& name, const std::string& unit, double v, double sd, double design, const std::string& state) {
      rows.push_back({name, fmt::format("{:.5g}", v), fmt::format("{:.5g} … {:.5g}", v - kZ95 * sd, v + kZ95 * sd), unit,
                      sd > 0 ? fmt::format("{:.1f}", std::abs(v - (std::isfinite(design) ? design : 0.0)) / sd) : "-", state});
      forest.push_back({name, unit, v, v - kZ95 * sd, v + kZ95 * sd, design});
    };
    add("K", "N/m", best.K, best.K_std, rp::kNoValue, best.K > 0 ? "✓ K > 0" : "✗ K ≤ 0");
    if (best.mu_identifiable) add("mu", "-", best.mu, best.mu_std, rp::kNoValue, best.mu >= 0 ? "✓ μ ≥ 0" : "✗ μ < 0");
    else rows.push_back({"mu", "-", "-", "-", "-", "✗ not identifiable"});
    if (r.geometric)
      for (int j = 0; j < p.uncertainties(); ++j) {
        const auto& u = sc.uncertainties[static_cast<std::size_t>(j)];
        const double design = sc.design()[j];
        if (r.geometric->fitted[static_cast<std::size_t>(j)])
          add(u.name, unit_of(u), r.geometric->x[j], r.geometric->x_std[j], design, "fitted");
        else rows.push_back({u.name, fmt::format("{:.5g}", r.geometric->x[j]), "-", unit_of(u), "-", "not fitted: design value"});
      }
    page.table({"parameter", "value", "95 % interval", "unit", "distance / std", "state"}, rows);
    page.paragraph("Intervals are 1.96 std. Geometric uncertainties are drawn against their design value (grey); K and μ have "
                   "no design value.");
    page.forest(forest, "Identified parameters: value and 95 % interval", "design");
  }

  const char* names[6] = {"fx", "fy", "fz", "mx", "my", "mz"};
  for (int group = 0; group < 2; ++group) {
    page.heading(group == 0 ? "Measured and reconstructed forces (force-plate frame)"
                            : "Measured and reconstructed moments (about the plate origin)");
    for (int c = 3 * group; c < 3 * group + 3; ++c) {
      std::vector<rp::Series> s;
      rp::Series meas{"measured", t, {}, "#444", true, false, 1.2};
      rp::Series nom{"nominal model", t, {}, "#d62728"};
      for (std::size_t a = 0; a < t.size(); ++a) {
        meas.y.push_back(p.data()[static_cast<std::size_t>(p.used()[a])].w_fp[c]);
        nom.y.push_back(w_nom[a][c]);
      }
      s.push_back(meas);
      s.push_back(nom);
      if (r.geometric) {
        rp::Series geo{"with geometry", t, {}, "#2ca02c"};
        for (std::size_t a = 0; a < t.size(); ++a) geo.y.push_back(w_geo[a][c]);
        s.push_back(geo);
      }
      page.plot(s, {std::string(names[c]), "t (s)", std::string(names[c]) + (group == 0 ? " (N)" : " (N m)")});
    }
  }
  page.heading("Number of contact points");
  {
    std::vector<rp::Series> s;
    rp::Series a{"nominal geometry", t, {}, "#d62728"};
    for (int v : n_nom) a.y.push_back(v);
    s.push_back(a);
    if (r.geometric) {
      rp::Series b{"identified geometry", t, {}, "#2ca02c", false, true};
      for (int v : n_geo) b.y.push_back(v);
      s.push_back(b);
    }
    page.plot(s, {"contact points", "t (s)", "contact points"});
  }
  auto inst_plots = [&](const std::vector<cid::InstantEstimate>& one, const std::vector<cid::InstantEstimate>& win,
                        const cid::LinearEstimate& glob, const std::string& label) {
    for (int which = 0; which < 2; ++which) {
      rp::Series pts{"instantaneous", {}, {}, "#9ecae1", true, false, 1.5};
      rp::Series line{"sliding window", {}, {}, "#1f77b4"};
      const double nan = std::numeric_limits<double>::quiet_NaN();
      for (const auto& e : one) {
        pts.x.push_back(e.t_s);
        pts.y.push_back(which == 0 ? (e.valid ? e.K : nan) : (e.mu_valid ? e.mu : nan));
      }
      for (const auto& e : win) {
        line.x.push_back(e.t_s);
        line.y.push_back(which == 0 ? (e.valid ? e.K : nan) : (e.mu_valid ? e.mu : nan));
      }
      const double gv = which == 0 ? glob.K : glob.mu;
      rp::Series g{"global", {t.front(), t.back()}, {gv, gv}, "#d62728", false, true};
      // Clip the instantaneous μ to a readable range.
      if (which == 1)
        for (auto& y : pts.y)
          if (std::isfinite(y) && (y < -1.0 || y > 2.0)) y = nan;
      page.plot({pts, line, g}, {(which == 0 ? "K " : "mu ") + label, "t (s)", which == 0 ? "K (N/m)" : "μ (-)"});
    }
  };
  page.heading("Instantaneous estimates, nominal geometry");
  inst_plots(r.inst_nominal, r.window_nominal, r.nominal, "(nominal geometry)");
  if (r.geometric) {
    page.heading("Instantaneous estimates, identified geometry");
    inst_plots(r.inst_geometric, r.window_geometric, r.geometric->theta, "(identified geometry)");
  }
  if (r.lcurve) {
    const auto& c = *r.lcurve;
    page.heading("L-curve");
    rp::PlotOptions o{"L-curve: geometric cost against force cost", "force cost (1/6L)|W(Y - Φθ)|²", "geometric cost (1/M)|x - x_d|²_W",
                      true, true};
    o.marks.push_back({c.force_cost[c.corner], c.geometric_cost[c.corner], fmt::format("λ = {:.3g}", c.lambda[c.corner])});
    page.plot({{"λ from 1e-4 to 1e3", c.force_cost, c.geometric_cost, "#1f77b4"}, {"", c.force_cost, c.geometric_cost, "#1f77b4", true}},
              o);
    rp::PlotOptions oc{"Curvature of the L-curve", "λ", "curvature", true, false};
    page.plot({{"curvature", c.lambda, c.curvature, "#ff7f0e"}}, oc);
  }
  if (r.observability) {
    const auto& o = *r.observability;
    page.heading("Observability (P1, P2: correlations of the normalised regressor and sensitivity columns)");
    std::vector<std::string> hdr{"", "Φ"};
    for (const auto& u : p.scene().uncertainties) hdr.push_back(u.name);
    for (int which = 0; which < 2; ++which) {
      const auto& P = which == 0 ? o.P1 : o.P2;
      std::vector<std::vector<std::string>> rows;
      for (Eigen::Index i = 0; i < P.rows(); ++i) {
        std::vector<std::string> row{hdr[static_cast<std::size_t>(i + 1)]};
        for (Eigen::Index k = 0; k < P.cols(); ++k) row.push_back(fmt::format("{:.2f}", P(i, k)));
        rows.push_back(row);
      }
      page.paragraph(which == 0 ? "P1 (stiffness column)" : "P2 (friction column)");
      page.table(hdr, rows);
    }
  }
  page.heading("Text summary");
  std::ostringstream summary;
  print(summary, p, r);
  page.text_download("The summary as `hil contact identify` prints it", "contact-identification-" + run_name + ".txt", summary.str());
  page.write((std::filesystem::path(dir) / "index.html").string());
  page.write_figures((std::filesystem::path(dir) / "figures").string());
}

}  // namespace hil::services::contact
