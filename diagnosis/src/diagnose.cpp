#include <hil/diagnose/diagnose.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include <Eigen/QR>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <hil/diagnose/effect.hpp>
#include <hil/parallel/run_tasks.hpp>

namespace hil::diagnose {

namespace {

Eigen::VectorXd per_sample_sq(const Observations& obs, const Eigen::MatrixXd& pred) {
  Eigen::VectorXd e(static_cast<Eigen::Index>(obs.size()));
  for (Eigen::Index k = 0; k < e.size(); ++k) e(k) = ((obs.y.row(k) - pred.row(k)).transpose().cwiseProduct(obs.weight)).squaredNorm();
  return e;
}

double corr(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::VectorXd x = a.array() - a.mean(), y = b.array() - b.mean();
  const double d = std::sqrt(x.squaredNorm() * y.squaredNorm());
  return d > 0 ? x.dot(y) / d : 0.0;
}

}  // namespace

double noise_level(const Observations& obs, const Eigen::MatrixXd& prediction) {
  const Eigen::Index n = static_cast<Eigen::Index>(obs.size());
  if (n < 3) return 0.0;
  const Eigen::MatrixXd r = (obs.y - prediction) * obs.weight.asDiagonal();
  const Eigen::MatrixXd d = r.bottomRows(n - 1) - r.topRows(n - 1);
  return std::sqrt(d.squaredNorm() / (2.0 * 6.0 * static_cast<double>(n - 1)));
}

namespace {

/// Newey-West z of the mean of a per-sample loss difference (autocorrelation-robust).
double newey_west_z(const Eigen::VectorXd& d) {
  const Eigen::Index n = d.size();
  if (n < 3) return 0.0;
  const double mean = d.mean();
  const Eigen::VectorXd c = d.array() - mean;
  const int L = static_cast<int>(std::ceil(4.0 * std::pow(static_cast<double>(n) / 100.0, 2.0 / 9.0)));
  double lrv = c.squaredNorm() / static_cast<double>(n);
  for (int l = 1; l <= L && l < n; ++l) {
    const double g = c.head(n - l).dot(c.tail(n - l)) / static_cast<double>(n);
    lrv += 2.0 * (1.0 - l / (L + 1.0)) * g;
  }
  if (!(lrv > 0)) return mean > 0 ? 1e300 : 0.0;
  return mean / std::sqrt(lrv / static_cast<double>(n));
}

/// Per sample, the weighted error norm of a score's held-out predictions, averaged over the grid
/// offsets of repeated blocked CV.
Eigen::VectorXd held_out_norm(const Observations& obs, const Score& s) {
  Eigen::VectorXd e = per_sample_sq(obs, s.cv_prediction).cwiseSqrt();
  for (const auto& p : s.cv_shifted) e += per_sample_sq(obs, p).cwiseSqrt();
  return e / static_cast<double>(1 + s.cv_shifted.size());
}

}  // namespace

double paired_z(const Observations& obs, const Eigen::MatrixXd& reference, const Eigen::MatrixXd& candidate) {
  // Loss: the per-sample weighted error norm (not its square), so that a few large residuals
  // (e.g. a sliding sample measured as sticking) do not decide the comparison alone.
  return newey_west_z(per_sample_sq(obs, reference).cwiseSqrt() - per_sample_sq(obs, candidate).cwiseSqrt());
}

double paired_z(const Observations& obs, const Score& reference, const Score& candidate) {
  if (reference.cv_shifted.size() != candidate.cv_shifted.size())
    throw std::invalid_argument("paired_z: the scores were held out on " + std::to_string(1 + reference.cv_shifted.size()) + " and " +
                                std::to_string(1 + candidate.cv_shifted.size()) + " grid offsets");
  return newey_west_z(held_out_norm(obs, reference) - held_out_norm(obs, candidate));
}

namespace {

/// The step a component's values are quantised to (0: not quantised): the smallest gap between its
/// distinct values, when the values repeat (fewer distinct values than half the samples) and every
/// value is a multiple of it.
double quantisation_step(const Eigen::VectorXd& y) {
  std::vector<double> v(y.data(), y.data() + y.size());
  std::sort(v.begin(), v.end());
  const double scale = std::max(std::abs(v.front()), std::abs(v.back()));
  if (!(scale > 0) || !std::isfinite(scale)) return 0.0;
  const double same = 1e-9 * scale;
  double step = std::numeric_limits<double>::infinity();
  std::size_t distinct = 1;
  for (std::size_t i = 1; i < v.size(); ++i)
    if (v[i] - v[i - 1] > same) {
      ++distinct;
      step = std::min(step, v[i] - v[i - 1]);
    }
  if (!std::isfinite(step) || 2 * distinct > v.size()) return 0.0;
  for (double x : v)
    if (std::abs(x / step - std::round(x / step)) > 1e-6) return 0.0;
  return step;
}

/// ResidualAnalysis' structure (issue 32, item 3): per component the residual's white noise by von
/// Neumann's first differences, the variance beyond it, the trend with time, and the findings above
/// the thresholds. `r` is the residual in physical units, a.correlations already computed.
void structure(const Observations& obs, const Eigen::MatrixXd& r, ResidualAnalysis& a, const StructureOptions& so) {
  const Eigen::Index n = r.rows();
  if (n < 3) return;
  const double root_n = std::sqrt(static_cast<double>(n));
  Eigen::Matrix<double, 6, 1> noise2, centred2;
  double pooled_mse = 0.0, pooled_noise = 0.0;
  for (int c = 0; c < 6; ++c) {
    const Eigen::VectorXd rc = r.col(c);
    const double mse = rc.squaredNorm() / static_cast<double>(n);  // a constant offset is structure too
    // The white floor: the first differences' noise, plus the quantisation's q²/12. A step much
    // coarser than the noise (the ACU plate's 1.5 N against 0.3 N) makes an error that follows the
    // signal slowly, which the differences do not see: structure of the sensor, not of the model.
    a.quantisation(c) = quantisation_step(obs.y.col(c));
    noise2(c) = (rc.tail(n - 1) - rc.head(n - 1)).squaredNorm() / (2.0 * static_cast<double>(n - 1)) +
                a.quantisation(c) * a.quantisation(c) / 12.0;
    centred2(c) = (rc.array() - rc.mean()).matrix().squaredNorm() / static_cast<double>(n);
    a.excess(c) = noise2(c) > 0 ? mse / noise2(c) - 1.0 : 0.0;
    const double w2 = obs.weight(c) * obs.weight(c);
    pooled_mse += w2 * mse;
    pooled_noise += w2 * noise2(c);
  }
  a.excess_variance = pooled_noise > 0 ? pooled_mse / pooled_noise - 1.0 : 0.0;
  auto explained = [&](int c, double rho) { return noise2(c) > 0 ? rho * rho * centred2(c) / noise2(c) : 0.0; };
  auto index = [&](const std::string& name) {
    for (int c = 0; c < 6; ++c)
      if (obs.component[static_cast<std::size_t>(c)] == name) return c;
    return 0;
  };
  for (auto& k : a.correlations) k.explained = explained(index(k.component), k.correlation);
  // Trends: each component against time, lag 0.
  Eigen::VectorXd t(n);
  for (Eigen::Index k = 0; k < n; ++k) t(k) = obs.t_s[static_cast<std::size_t>(k)];
  for (int c = 0; c < 6; ++c) {
    const double rho = corr(r.col(c), t);
    a.trends.push_back({"time", obs.component[static_cast<std::size_t>(c)], rho, 0, explained(c, rho)});
  }
  std::sort(a.trends.begin(), a.trends.end(), [](const auto& x, const auto& y) { return x.explained > y.explained; });

  auto& out = a.structure;
  if (a.excess_variance >= so.max_excess && a.excess_variance * root_n >= so.min_z) {
    std::vector<std::pair<double, int>> worst;
    for (int c = 0; c < 6; ++c) worst.push_back({a.excess(c), c});
    std::sort(worst.rbegin(), worst.rend());
    std::vector<std::string> parts;
    for (std::size_t i = 0; i < 2; ++i)
      parts.push_back(fmt::format("{} {:.2f}", obs.component[static_cast<std::size_t>(worst[i].second)], worst[i].first));
    out.push_back({"not white",
                   fmt::format("not white: {:.2f} noise variances beyond its white noise ({}; Ljung-Box Q {:.0f}, bound {:.0f})",
                               a.excess_variance, fmt::join(parts, ", "), a.ljung_box_q, a.ljung_box_bound),
                   a.excess_variance});
  }
  auto significant = [&](const ResidualAnalysis::Correlation& k) {
    return k.explained >= so.max_explained && std::abs(k.correlation) * root_n >= so.min_z;
  };
  // The strongest correlation of each signal (a signal correlating with several components is
  // named once, by its largest share), the four largest.
  std::vector<ResidualAnalysis::Correlation> best;
  for (const auto& k : a.correlations) {
    if (!significant(k)) continue;
    auto it = std::find_if(best.begin(), best.end(), [&](const auto& b) { return b.signal == k.signal; });
    if (it == best.end()) best.push_back(k);
    else if (k.explained > it->explained) *it = k;
  }
  std::sort(best.begin(), best.end(), [](const auto& x, const auto& y) { return x.explained > y.explained; });
  if (best.size() > 4) best.resize(4);
  for (const auto& k : best)
    out.push_back({"correlates",
                   fmt::format("{} correlates with {} (r = {:.2f}, lag {}): {:.2f} noise variances of {}", k.component, k.signal,
                               k.correlation, k.lag, k.explained, k.component),
                   k.explained});
  for (const auto& k : a.trends)
    if (significant(k))
      out.push_back({"trend",
                     fmt::format("{} trends with time (r = {:.2f}): {:.2f} noise variances of {}; a drift?", k.component, k.correlation,
                                 k.explained, k.component),
                     k.explained});
  std::stable_sort(out.begin(), out.end(), [](const auto& x, const auto& y) { return x.size > y.size; });
}

}  // namespace

std::string ResidualAnalysis::structure_text() const {
  std::vector<std::string> parts;
  for (const auto& f : structure) parts.push_back(f.text);
  return fmt::format("{}", fmt::join(parts, "; "));
}

ResidualAnalysis analyse_residuals(const Observations& obs, const Eigen::MatrixXd& pred, const Context& ctx, const StructureOptions& so) {
  ResidualAnalysis a;
  const Eigen::Index n = static_cast<Eigen::Index>(obs.size());
  const Eigen::MatrixXd r = obs.y - pred;
  for (int c = 0; c < 6; ++c) {
    a.rms(c) = std::sqrt(r.col(c).squaredNorm() / static_cast<double>(n));
    a.relative_rms(c) = obs.weight(c) * a.rms(c);
  }
  a.relative_rms.maxCoeff(&a.worst_component);
  const Eigen::VectorXd e = per_sample_sq(obs, pred);
  const double total = std::max(e.sum(), 1e-300);
  const double t0 = obs.t_s.front(), t1 = obs.t_s.back();
  a.window_start_s.resize(10);
  a.window_share.assign(10, 0.0);
  for (int w = 0; w < 10; ++w) a.window_start_s[static_cast<std::size_t>(w)] = t0 + (t1 - t0) * w / 10.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const int w = std::min(9, static_cast<int>(10.0 * (obs.t_s[static_cast<std::size_t>(k)] - t0) / std::max(t1 - t0, 1e-300)));
    a.window_share[static_cast<std::size_t>(w)] += e(k) / total;
  }
  if (ctx.state.size() == obs.size()) {
    std::map<std::string, std::pair<int, double>> st;
    for (Eigen::Index k = 0; k < n; ++k) {
      auto& s = st[ctx.state[static_cast<std::size_t>(k)]];
      ++s.first;
      s.second += e(k);
    }
    for (const auto& [label, v] : st) a.states.push_back({label, v.first, std::sqrt(v.second / (6.0 * v.first)), v.second / total});
    std::sort(a.states.begin(), a.states.end(), [](const auto& x, const auto& y) { return x.share > y.share; });
  }
  // Whiteness of the worst component (weighted residual).
  const Eigen::VectorXd rw = r.col(a.worst_component).array() - r.col(a.worst_component).mean();
  const double v0 = rw.squaredNorm();
  const int H = static_cast<int>(std::min<Eigen::Index>(20, n / 4));
  a.autocorrelation.push_back(1.0);
  double q = 0.0;
  for (int h = 1; h <= H; ++h) {
    const double rho = v0 > 0 ? rw.head(n - h).dot(rw.tail(n - h)) / v0 : 0.0;
    a.autocorrelation.push_back(rho);
    q += rho * rho / static_cast<double>(n - h);
  }
  a.ljung_box_q = static_cast<double>(n) * (static_cast<double>(n) + 2.0) * q;
  // 99 % quantile of chi-square with H dof (Wilson-Hilferty).
  const double z = 2.326, hh = std::max(1, H);
  a.ljung_box_bound = hh * std::pow(1.0 - 2.0 / (9.0 * hh) + z * std::sqrt(2.0 / (9.0 * hh)), 3.0);
  a.white = a.ljung_box_q < a.ljung_box_bound;
  // Cross-correlation with the candidate signals and with the other stream's components.
  for (const auto& [name, s] : ctx.signals) {
    if (s.size() != obs.size() || name == "time") continue;  // time: a trend, measured in structure()
    const Eigen::Map<const Eigen::VectorXd> sig(s.data(), n);
    if (!sig.allFinite()) continue;
    for (int c = 0; c < 6; ++c) {
      ResidualAnalysis::Correlation best{name, obs.component[static_cast<std::size_t>(c)], 0.0, 0};
      for (int lag = -10; lag <= 10; ++lag) {
        const Eigen::Index m = n - std::abs(lag);
        if (m < 10) continue;
        const Eigen::VectorXd rs = lag >= 0 ? r.col(c).tail(m) : r.col(c).head(m);
        const Eigen::VectorXd ss = lag >= 0 ? sig.head(m) : sig.tail(m);
        const double cc = corr(rs, ss);
        if (std::abs(cc) > std::abs(best.correlation)) {
          best.correlation = cc;
          best.lag = lag;
        }
      }
      a.correlations.push_back(best);
    }
  }
  std::sort(a.correlations.begin(), a.correlations.end(),
            [](const auto& x, const auto& y) { return std::abs(x.correlation) > std::abs(y.correlation); });
  structure(obs, r, a, so);
  return a;
}

namespace {

/// The largest parameter-to-noise ratio among the extension parameters `s` adds to `ref` (in the
/// second step, those of the added candidate, not the cause's, which are identifiable already).
double added_pnr(const Score& s, const Score& ref) {
  std::set<std::string> had;
  for (const auto& q : ref.full.reported)
    if (q.extension) had.insert(q.name);
  double best = 0.0;
  for (const auto& q : s.full.reported)
    if (q.extension && !had.count(q.name)) best = std::max(best, q.pnr());
  return best;
}

/// The criteria that need no held-out data (the full fit's BIC, PNR, physical validity and gain on
/// the samples it was fitted to): why `s` cannot be supported against `ref` whatever its held-out
/// error (empty: it may be).
std::string fails_without_held_out(const Score& s, const Score& ref, const DiagnoseOptions& o) {
  std::vector<std::string> why;
  if (!(s.bic < ref.bic)) why.push_back("BIC not lower");
  // A fit lowers the error on its own samples by more than it lowers it on held-out ones (by the
  // optimism of the parameters it adds), so a candidate that gains less than half the held-out
  // gain required on the samples it was fitted to is not scored on held-out data. The BIC and PNR
  // grow with the sample count and pass ever smaller effects; this does not, which keeps the
  // held-out scoring (most of the cost) from growing faster than the run (issue 29).
  const double in_sample_gain = ref.train_error > 0 ? 1.0 - s.train_error / ref.train_error : 0.0;
  if (in_sample_gain < 0.5 * o.min_gain)
    why.push_back(fmt::format("in-sample gain {:.2f} % < {:.0f} % (half the held-out gain required)", 100 * in_sample_gain,
                              50 * o.min_gain));
  if (!s.full.invalid.empty()) why.push_back("not physical: " + s.full.invalid);
  if (const double pnr = added_pnr(s, ref); pnr < o.min_pnr)
    why.push_back(fmt::format("parameters not practically identifiable (PNR {:.1f} < {:.0f})", pnr, o.min_pnr));
  return fmt::format("{}", fmt::join(why, "; "));
}

/// CandidateResult::effect_fraction_in_sample of the fit `f` of `m`: the parameters of `m` that
/// are extensions and not among `cause_params` are the added candidate's.
double effect_fraction(const ModelFamily& m, const Fit& f, const std::set<std::string>& cause_params, const Observations& obs,
                       double noise) {
  const auto lin = m.linear();
  const auto nl = m.nonlinear();
  auto added = [&](const Param& p) { return p.extension && !cause_params.count(p.name); };
  Eigen::VectorXd phi = f.phi;
  for (std::size_t j = 0; j < nl.size() && static_cast<Eigen::Index>(j) < phi.size(); ++j)
    if (added(nl[j])) phi(static_cast<Eigen::Index>(j)) = 0.0;
  Eigen::MatrixXd A_fit, A_off;
  m.design(f.phi, A_fit);
  m.design(phi, A_off);
  Eigen::VectorXd w(A_fit.rows());
  for (Eigen::Index r = 0; r < w.size(); ++r) w(r) = obs.weight(r % 6);
  Eigen::VectorXd y(A_fit.rows());
  for (Eigen::Index k = 0; k < obs.y.rows(); ++k)
    for (int c = 0; c < 6; ++c) y(6 * k + c) = obs.y(k, c);
  // The added candidate's θ at 0, the cause's as fitted, the nominal model's re-solved (QR).
  Eigen::VectorXd theta = f.theta;
  std::vector<Eigen::Index> nominal;
  for (std::size_t j = 0; j < lin.size(); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    if (!lin[j].extension) {
      nominal.push_back(i);
      theta(i) = 0.0;
    } else if (added(lin[j])) {
      theta(i) = 0.0;
    }
  }
  if (!nominal.empty()) {
    Eigen::MatrixXd An(A_off.rows(), static_cast<Eigen::Index>(nominal.size()));
    for (std::size_t j = 0; j < nominal.size(); ++j) An.col(static_cast<Eigen::Index>(j)) = w.cwiseProduct(A_off.col(nominal[j]));
    const Eigen::VectorXd rhs = w.cwiseProduct(y - A_off * theta);
    const Eigen::VectorXd x = An.colPivHouseholderQr().solve(rhs);
    for (std::size_t j = 0; j < nominal.size(); ++j) theta(nominal[j]) = x(static_cast<Eigen::Index>(j));
  }
  const Eigen::VectorXd change = w.cwiseProduct(A_fit * f.theta - A_off * theta);
  const double mean_sq = change.squaredNorm() / static_cast<double>(std::max<Eigen::Index>(1, change.size()));
  return noise > 0 ? mean_sq / (noise * noise) : 1e300;
}

void judge(CandidateResult& c, const Score& ref, double noise, const Observations& obs, const DiagnoseOptions& o) {
  c.pnr = added_pnr(c.score, ref);
  if (!c.score.held_out()) {
    // Screened after the full fit: the folds were not run (they could not change the verdict).
    c.gain_percent = std::numeric_limits<double>::quiet_NaN();
    c.noise_fraction = std::numeric_limits<double>::quiet_NaN();
    c.z = std::numeric_limits<double>::quiet_NaN();
    c.supported = false;
    c.verdict = c.score.screened + " (not scored on held-out data)";
    return;
  }
  c.gain_percent = ref.cv_error > 0 ? 100.0 * (1.0 - c.score.cv_error / ref.cv_error) : 0.0;
  c.noise_fraction = noise > 0 ? (ref.cv_error * ref.cv_error - c.score.cv_error * c.score.cv_error) / (noise * noise) : 1e300;
  c.z = paired_z(obs, ref, c.score);
  std::vector<std::string> why;
  if (c.gain_percent < 100.0 * o.min_gain)
    why.push_back(fmt::format("held-out gain {:.2f} % < {:.0f} %", c.gain_percent, 100 * o.min_gain));
  if (c.z < o.min_z) why.push_back(fmt::format("not consistent (z = {:.1f} < {:.0f})", c.z, o.min_z));
  const bool joint = !std::isnan(c.effect_fraction);
  const double size = joint ? std::max(c.noise_fraction, c.effect_fraction) : c.noise_fraction;
  if (size < o.min_noise_fraction)
    why.push_back(joint ? fmt::format("below the noise (explains {:.2f} of the noise variance held out, its held-out effect in the joint "
                                      "model {:.2f}; < {:.2f})",
                                      c.noise_fraction, c.effect_fraction, o.min_noise_fraction)
                        : fmt::format("below the noise (explains {:.2f} of the noise variance < {:.2f})", c.noise_fraction,
                                      o.min_noise_fraction));
  if (const auto rest = fails_without_held_out(c.score, ref, o); !rest.empty()) why.push_back(rest);
  c.supported = why.empty();
  c.verdict = c.supported ? fmt::format("supported: held-out gain {:.1f} %, z = {:.1f}, PNR {:.1f}, {:.2f} noise variances{}",
                                        c.gain_percent, c.z, c.pnr, c.noise_fraction,
                                        joint ? fmt::format(" (its held-out effect in the joint model {:.2f})", c.effect_fraction) : "")
                          : fmt::format("{}", fmt::join(why, "; "));
}

void rank(std::vector<CandidateResult>& v) {
  // Supported first, then those scored on held-out data by their error, then the screened ones.
  auto key = [](const CandidateResult& c) { return c.score.held_out() ? c.score.cv_error : std::numeric_limits<double>::infinity(); };
  std::stable_sort(v.begin(), v.end(), [&](const auto& a, const auto& b) {
    if (a.supported != b.supported) return a.supported;
    return key(a) < key(b);
  });
}

/// The first step's candidates the cause cannot be told from (Diagnosis::confounded): scored on
/// held-out data with a gain of their own, not the second cause, their held-out errors within the
/// paired test's reach of the cause's, their effects on the prediction nearly collinear.
std::vector<Confounded> confounded_with(const Diagnosis& d, const Observations& obs, const ConfoundingOptions& co) {
  std::vector<Confounded> out;
  const auto cause = std::find_if(d.candidates.begin(), d.candidates.end(), [&](const auto& c) { return c.name == d.cause; });
  if (cause == d.candidates.end() || !cause->score.held_out()) return out;
  const Eigen::VectorXd w = obs.weight;
  auto effect = [&](const Score& s) { return ((s.cv_prediction - d.nominal.cv_prediction) * w.asDiagonal()).eval(); };
  const Eigen::MatrixXd e_cause = effect(cause->score);
  auto evidence = [](const CandidateResult& c) {
    std::vector<std::string> params;
    for (const auto& q : c.score.full.reported)
      if (q.extension) params.push_back(fmt::format("{} {:.4g} ± {:.2g}", q.name, q.value, 1.96 * q.std));
    return fmt::format("{}: gain {:.1f} %, z {:.1f}{}{}", c.name, c.gain_percent, c.z, params.empty() ? "" : ", ", fmt::join(params, ", "));
  };
  for (const auto& r : d.candidates) {
    if (r.name == d.cause || r.name == d.second_cause || !r.applicable || !r.score.held_out() || !(r.gain_percent > 0.0)) continue;
    const Eigen::MatrixXd e_rival = effect(r.score);
    const double nn = e_cause.norm() * e_rival.norm();
    const double cosine = nn > 0 ? (e_cause.array() * e_rival.array()).sum() / nn : 0.0;
    const double z = paired_z(obs, r.score, cause->score);
    if (std::abs(z) >= co.max_z || cosine < co.min_cosine) continue;
    out.push_back({d.cause, r.name, cause->gain_percent, r.gain_percent, z, cosine,
                   fmt::format("{}; {}; their held-out errors differ by z = {:.1f} and their effects are collinear (cosine {:.2f})",
                               evidence(*cause), evidence(r), z, cosine),
                   separating_experiment(d.cause, r.name)});
  }
  return out;
}

}  // namespace

Diagnosis diagnose(const ModelFactory& make, const std::vector<std::string>& candidates, const Observations& obs, const Context& ctx,
                   const DiagnoseOptions& o, const Progress& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  Diagnosis d;
  const int total = 1 + static_cast<int>(candidates.size()) + o.second_candidates;
  // Progress, shared by the models scored side by side: the steps started (announced in step
  // order), those finished and, for each running one, its name and the fraction of its tasks done.
  std::mutex told;
  std::condition_variable turn;
  int announced = 0, finished = 0;
  std::map<int, std::pair<std::string, double>> running;
  std::atomic<bool> stop{false};
  // The progress line for step `my`: its model and fold, the time so far, a rough estimate of what
  // is left (the steps, each counted as an equal share: screened candidates cost little, so it runs
  // high early on) and the other models running beside it. Called with `told` held.
  auto line = [&](int my, int done, int tasks) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    double fraction = finished;
    for (const auto& [step, r] : running) fraction += r.second;
    fraction /= total;
    std::string s = running.at(my).first;
    if (tasks > 0) s += fmt::format(", fold {} of {}", std::min(done + 1, tasks), tasks);
    s += fmt::format("; {:.0f} s", elapsed);
    if (fraction > 0.05) s += fmt::format(", ~{:.0f} s left", elapsed / fraction * (1.0 - fraction));
    std::vector<std::string> beside;
    for (const auto& [step, r] : running)
      if (step != my) beside.push_back(r.first);
    if (!beside.empty()) s += fmt::format("; beside it: {}", fmt::join(beside, ", "));
    progress(my, total, s);
  };
  // Scores the models of steps first+1 .. first+whats.size() side by side (DiagnoseOptions::
  // model_threads), each as body(i, its CV options). Results go to each step's own slot, so the
  // outcome is the serial one; a step's failure that is not the model's (a progress callback
  // stopping the run) stops the steps not yet started and is rethrown.
  auto run_steps = [&](int first, const std::vector<std::string>& whats, const auto& body) {
    const std::size_t n = whats.size();
    const std::size_t workers = parallel::worker_count(n, o.model_threads);
    parallel::run_tasks(n, workers, [&](std::size_t i, std::size_t) {
      const int my = first + 1 + static_cast<int>(i);
      try {
        {
          std::unique_lock lock(told);
          // Announced in step order: the step before this one was taken first and is announced
          // without waiting for anything but its own predecessor.
          turn.wait(lock, [&] { return announced == my - 1 || stop; });
          if (stop) return;
          running[my] = {whats[i], 0.0};
          if (progress && o.progress_detail) line(my, 0, 0);
          else if (progress) progress(my, total, whats[i]);
          // Only after the callback returned: one that throws lets no later step start.
          announced = my;
          turn.notify_all();
        }
        CvOptions cv = o.cv;
        if (progress && o.progress_detail)
          cv.on_task = [&, my](int done, int tasks) {
            std::lock_guard lock(told);
            running[my].second = tasks > 0 ? static_cast<double>(done) / tasks : 0.0;
            line(my, done, tasks);
          };
        body(i, cv);
        std::lock_guard lock(told);
        running.erase(my);
        ++finished;
      } catch (...) {
        std::lock_guard lock(told);
        stop = true;
        turn.notify_all();
        throw;
      }
    });
  };
  run_steps(0, {"nominal"}, [&](std::size_t, const CvOptions& cv) { d.nominal = score(*make({}), obs, cv); });
  d.nominal_residuals = analyse_residuals(obs, d.nominal.cv_prediction, ctx, o.structure);
  d.noise_relative = noise_level(obs, d.nominal.cv_prediction);
  // A candidate whose full fit already fails a criterion that needs no held-out data is not scored
  // on held-out data: the folds cost most of a fit's time and could not change its verdict.
  auto screened_against = [&](const Score& ref, CvOptions screened) {
    screened.screen = [&ref, &o](const Score& s) { return fails_without_held_out(s, ref, o); };
    return screened;
  };
  d.candidates.resize(candidates.size());
  run_steps(1, candidates, [&](std::size_t i, const CvOptions& cv) {
    CandidateResult& r = d.candidates[i];
    r.name = candidates[i];
    try {
      r.score = score(*make({r.name}), obs, screened_against(d.nominal, cv));
    } catch (const std::exception& e) {
      r.score.model = r.name;
      r.score.cv_error = std::numeric_limits<double>::infinity();
      r.applicable = false;
      r.verdict = std::string("not applicable: ") + e.what();
    }
  });
  // The noise is the least any model leaves in its held-out residual's differences: those are the
  // noise's plus the model's own misfit's, and a nominal model that misses an event by a sample (a
  // friction turn at a kink under a delay) leaves spikes that would count as noise (issue 32: 2.1 %
  // against 0.35 % on moves with an 8 ms delay, which hid the delay). Spikes no model predicts stay
  // in: leaving out every isolated spike (a robust estimate, tried) made the noise of the ACU's
  // clean runs 0.21 % instead of 0.71 %, and their contact switches, which no candidate models,
  // then passed nonlinear_stiffness as 2.3 noise variances.
  for (const auto& r : d.candidates)
    if (r.applicable && r.score.held_out()) d.noise_relative = std::min(d.noise_relative, noise_level(obs, r.score.cv_prediction));
  for (auto& r : d.candidates)
    if (r.applicable) judge(r, d.nominal, d.noise_relative, obs, o);
  int step = 1 + static_cast<int>(candidates.size());
  rank(d.candidates);
  if (!d.candidates.empty() && d.candidates.front().supported) {
    const auto& first = d.candidates.front();
    d.cause = first.name;
    d.extended = first.score;
    // Greedy forward selection: the best remaining single candidates, each added to the cause.
    std::set<std::string> cause_params;
    {
      const auto cause_model = make({d.cause});
      for (const auto& p : cause_model->linear()) cause_params.insert(p.name);
      for (const auto& p : cause_model->nonlinear()) cause_params.insert(p.name);
    }
    // Every other candidate, not only those that helped alone: an extension may only matter
    // together with the cause (a delay of a compliance's load, say).
    std::vector<std::string> added, whats;
    for (const auto& c : d.candidates)
      if (c.name != d.cause && c.applicable && static_cast<int>(added.size()) < o.second_candidates) {
        added.push_back(c.name);
        whats.push_back(d.cause + " + " + c.name);
      }
    d.second_step.resize(added.size());
    run_steps(step, whats, [&](std::size_t i, const CvOptions& cv) {
      CandidateResult& r = d.second_step[i];
      r.name = added[i];
      try {
        const auto model = make({d.cause, r.name});
        CvOptions sized = screened_against(first.score, cv);
        for (const auto& p : model->linear())
          if (p.extension && !cause_params.count(p.name)) sized.effect_of.insert(p.name);
        for (const auto& p : model->nonlinear())
          if (p.extension && !cause_params.count(p.name)) sized.effect_of.insert(p.name);
        r.score = score(*model, obs, sized, &first.score);
        if (r.score.held_out()) {
          const double noise2 = d.noise_relative * d.noise_relative;
          r.effect_fraction = noise2 > 0 ? r.score.held_out_effect / noise2 : 1e300;
          r.effect_fraction_in_sample = effect_fraction(*model, r.score.full, cause_params, obs, d.noise_relative);
        }
        judge(r, first.score, d.noise_relative, obs, o);
      } catch (const std::exception& e) {
        r.score.cv_error = std::numeric_limits<double>::infinity();
        r.applicable = false;
        r.verdict = std::string("not applicable: ") + e.what();
      }
    });
    step += static_cast<int>(added.size());
    rank(d.second_step);
    if (!d.second_step.empty() && d.second_step.front().supported) {
      d.second_cause = d.second_step.front().name;
      d.extended = d.second_step.front().score;
    }
  }
  if (d.extended) d.confounded = confounded_with(d, obs, o.confounding);
  if (progress && step < total) progress(total, total, "done");
  const auto& ext = d.extended ? *d.extended : d.nominal;
  d.gain_percent = d.nominal.cv_error > 0 ? 100.0 * (1.0 - ext.cv_error / d.nominal.cv_error) : 0.0;
  d.extended_residuals = analyse_residuals(obs, ext.cv_prediction, ctx, o.structure);
  // Nothing named, yet the nominal residual has structure: not `none` (issue 32, item 3).
  if (!d.extended && d.nominal_residuals.structured()) d.cause = "unexplained";
  d.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return d;
}

}  // namespace hil::diagnose
