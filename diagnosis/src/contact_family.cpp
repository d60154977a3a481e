#include <hil/diagnose/contact_family.hpp>
#include <hil/so3/so3.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace hil::diagnose {

namespace {

using Vec3 = Eigen::Vector3d;

Eigen::Isometry3d deflect(const Eigen::Isometry3d& T, const Vector6d& d) {
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  D.linear() = so3::exp(d.tail<3>());
  D.translation() = d.head<3>();
  return T * D;
}

double quantise(double v, double step) { return step > 0 ? step * std::round(v / step) : v; }

/// Linear interpolation of the rows of a per-sample signal at time t (clamped at the ends).
template <class Get>
void interpolate(const std::vector<double>& t, double tq, Get&& get) {
  const auto it = std::upper_bound(t.begin(), t.end(), tq);
  if (it == t.begin()) return get(0, 0, 0.0);
  if (it == t.end()) return get(t.size() - 1, t.size() - 1, 0.0);
  const std::size_t j1 = static_cast<std::size_t>(it - t.begin()), j0 = j1 - 1;
  const double a = (tq - t[j0]) / (t[j1] - t[j0]);
  get(j0, j1, a);
}

}  // namespace

const std::vector<std::string>& contact_extensions() { return effect_names(FamilyKind::contact); }

std::string describe_extension(const std::string& n) {
  if (n == "none") return "no extension predicts held-out data better than the nominal model beyond the noise";
  if (n == "unexplained")
    return "no extension predicts held-out data better than the nominal model beyond the noise, yet its residual has structure (listed): "
           "an effect outside the library?";
  const Effect* e = find_effect(n);
  return e ? e->description() : "";
}

namespace {

/// The coarsest grid through levels.front() holding every level (sorted, distinct), its step the
/// smallest gap or a fraction 1/k of it (k <= kMaxDivisor, k > 1 only on kMinLevelsBelowGap data
/// levels); 0 when there is none.
double coarsest_grid(const std::vector<double>& levels, std::size_t data_levels) {
  // A signal that never takes two adjacent levels has a step a fraction of its smallest gap (a slow
  // move's normal twist at ±1, ±5, ±11, ±15 steps of 2e-5 m/s). Three levels fit some fraction by
  // chance (0, 2, 5 on a grid of 1), while each further level off a grid lands on it with
  // probability 2e-3 (the tolerance): a finer step needs five.
  constexpr int kMaxDivisor = 10;
  constexpr std::size_t kMinLevelsBelowGap = 5;
  double gap = 0.0;
  for (std::size_t i = 1; i < levels.size(); ++i) {
    const double g = levels[i] - levels[i - 1];
    if (g > 1e-12 * std::max(1.0, std::abs(levels[i])) && (gap == 0.0 || g < gap)) gap = g;
  }
  const double scale = std::max(std::abs(levels.front()), std::abs(levels.back()));
  for (int k = 1; k <= kMaxDivisor && (k == 1 || data_levels >= kMinLevelsBelowGap); ++k) {
    const double step = gap / k;
    if (step == 0.0 || step < 1e-9 * scale) return 0.0;
    const bool on_grid = std::all_of(levels.begin(), levels.end(), [&](double x) {
      const double r = (x - levels.front()) / step;
      return std::abs(r - std::round(r)) <= 1e-3;
    });
    if (on_grid) return step;
  }
  return 0.0;
}

}  // namespace

double quantum_of(std::vector<double> v, std::size_t min_levels) {
  if (!std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); })) return 0.0;  // (and sort needs an order)
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  if (v.size() < std::max<std::size_t>(3, min_levels)) return 0.0;
  // A register holds an integer count of its step, so zero is on the grid: the values with zero
  // first (levels at odd multiples only are then seen on their step, not on twice it), then, for a
  // signal offset after its quantiser (a tare), the values alone.
  std::vector<double> with_zero = v;
  with_zero.insert(std::lower_bound(with_zero.begin(), with_zero.end(), 0.0), 0.0);
  with_zero.erase(std::unique(with_zero.begin(), with_zero.end()), with_zero.end());
  const double zero_grid = coarsest_grid(with_zero, v.size());
  return zero_grid > 0.0 ? zero_grid : coarsest_grid(v, v.size());
}

double quantisation_bias_variance(double step, double sigma) {
  if (!(step > 0.0)) return 0.0;
  if (!(sigma > 0.0)) return step * step / 12.0;  // the series' sum, Σ 1/k² = π²/6
  constexpr double pi = 3.141592653589793;
  double v = 0.0;
  for (int k = 1; k <= 64; ++k)
    v += step * step / (2.0 * pi * pi * k * k) * std::exp(-4.0 * pi * pi * k * k * sigma * sigma / (step * step));
  return v;
}

double quantisation_bias_variance(const std::vector<double>& series, double step) {
  if (!(step > 0.0)) return 0.0;
  std::vector<double> sq;
  for (std::size_t k = 1; k + 1 < series.size(); ++k) sq.push_back(std::pow(series[k + 1] - 2.0 * series[k] + series[k - 1], 2));
  const std::size_t kept = sq.size() * 9 / 10;
  if (kept == 0) return quantisation_bias_variance(step, 0.0);
  std::nth_element(sq.begin(), sq.begin() + static_cast<std::ptrdiff_t>(kept), sq.end());
  double mean = 0.0;
  for (std::size_t k = 0; k < kept; ++k) mean += sq[k] / static_cast<double>(kept);
  // A Gaussian's second moment within its central 90 % (|x| < 1.6449 s) is 0.6230 s²; white noise's
  // second differences have the variance 6 σ².
  const double var = mean / (0.6230 * 6.0) - step * step / 12.0;
  return quantisation_bias_variance(step, var > 0.0 ? std::sqrt(var) : 0.0);
}

double touching_probability(double delta_m, const Eigen::Vector3d& normal, const Eigen::Vector3d& quantum_m) {
  const Eigen::Vector3d spread = (normal.cwiseAbs().array() * quantum_m.cwiseAbs().array()).matrix();
  Eigen::Index j = 0;
  const double widest = spread.maxCoeff(&j);
  if (!(widest > 0.0)) return delta_m > 0.0 ? 1.0 : 0.0;
  // The errors are bounded: beyond their reach the contact is decided (the Gaussian part's tails
  // would leave a rounding's worth there).
  const double reach = spread.sum() / 2.0;
  if (delta_m >= reach) return 1.0;
  if (delta_m <= -reach) return 0.0;
  const double h = widest / 2.0;
  const double s = std::sqrt((spread.squaredNorm() - widest * widest) / 12.0);
  if (!(s > 1e-6 * h)) return std::clamp((delta_m + h) / (2.0 * h), 0.0, 1.0);
  constexpr double inv_sqrt_2pi = 0.3989422804014327;
  auto G = [](double u) { return u * 0.5 * std::erfc(-u / std::sqrt(2.0)) + inv_sqrt_2pi * std::exp(-0.5 * u * u); };
  return std::clamp(s / (2.0 * h) * (G((delta_m + h) / s) - G((delta_m - h) / s)), 0.0, 1.0);
}

// Lobes of the Lanczos window of the pose interpolation (2 kSincLobes samples per instant).
// Why not a linear blend of the two neighbours: the reported poses are quantised (2 µm on the
// paper's rig) and a blend halves the quantisation noise's variance at a half-sample shift, so a
// fitted delay drifted towards fractional shifts (τ 10 % high on the blind suite's 20 ms). The
// windowed sinc keeps 92-100 % of white noise's variance at every fraction. Its weights get the
// least change that makes them reproduce cubics exactly (a truncated sinc alone shifts a ramp by up
// to 0.007 of a sample); exact at the samples, so τ = 0 gives the measured kinematics.
constexpr int kSincLobes = 8;

std::vector<double> delay_crossings(const ContactData& d, double lower_s, double upper_s, double merge_s) {
  const auto& t = d.obs.t_s;
  const std::size_t n = t.size();
  std::vector<double> at;            // the instants the delayed sample instants must not cross unnoticed
  std::vector<bool> near(n, false);  // sample instants within a step's interpolation window
  constexpr std::size_t window = 2 * kSincLobes;
  for (const auto* steps : {&d.v_step, &d.w_step, &d.rate_step}) {
    if (steps->empty()) continue;
    if (steps->size() + 1 != n)
      throw std::invalid_argument("delay_crossings: steps for " + std::to_string(steps->size()) + " intervals, the run has " +
                                  std::to_string(n) + " samples");
    for (std::size_t j = 0; j + 1 < n; ++j) {
      const double f = (*steps)[j];
      if (!std::isfinite(f)) continue;
      at.push_back(t[j] + f * (t[j + 1] - t[j]));
      for (std::size_t k = j > window ? j - window : 0; k < std::min(n, j + window + 2); ++k) near[k] = true;
    }
  }
  if (at.empty()) return {};
  for (std::size_t k = 0; k < n; ++k)
    if (near[k]) at.push_back(t[k]);
  std::vector<double> tau;
  for (const double s : at) {  // t_k - s in [lower, upper]: t_k in [s + lower, s + upper]
    const auto from = std::lower_bound(t.begin(), t.end(), s + lower_s);
    for (auto k = from; k != t.end() && *k <= s + upper_s; ++k) tau.push_back(*k - s);
  }
  std::sort(tau.begin(), tau.end());
  std::vector<double> out;
  for (std::size_t i = 0; i < tau.size();) {  // runs of neighbours closer than merge_s: their mean
    std::size_t j = i + 1;
    double sum = tau[i];
    while (j < tau.size() && tau[j] - tau[j - 1] < merge_s) sum += tau[j++];
    out.push_back(sum / static_cast<double>(j - i));
    i = j;
  }
  return out;
}

std::vector<double> rate_steps(const std::vector<double>& t_s, const std::vector<Vec3>& rate, const std::vector<Vec3>& increment,
                               double quantum, double increment_quantum) {
  const std::size_t n = rate.size();
  if (t_s.size() != n || increment.size() + 1 != std::max<std::size_t>(n, 1))
    throw std::invalid_argument("rate_steps: " + std::to_string(n) + " rates need as many times and one increment fewer");
  std::vector<double> out(n > 1 ? n - 1 : 0, std::numeric_limits<double>::quiet_NaN());
  if (n < 3) return out;
  std::vector<double> jump(n - 1);
  for (std::size_t j = 0; j + 1 < n; ++j) jump[j] = (rate[j + 1] - rate[j]).norm();
  std::vector<double> sorted = jump;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  const double floor = kStepFloor * std::max(quantum, sorted[sorted.size() / 2]);
  std::vector<bool> step(n - 1, false);
  for (std::size_t j = 0; j + 1 < n; ++j) {
    const double before = j > 0 ? jump[j - 1] : 0.0, after = j + 2 < n ? jump[j + 1] : 0.0;
    step[j] = jump[j] > floor && jump[j] > kStepRatio * std::max(before, after);
  }
  // Where the measured increments and the trapezoidal integral of the rate disagree, interval by
  // interval: the quantisation of what is integrated (2 µm of a pose against a step's 0.1 mm), which
  // would misplace a step by a third of a millisecond; the increments over m intervals on each
  // side average it, while the rate's own quantum (a bias over a whole segment) grows with m: m
  // balances the two (q_x / sqrt(m) against q_v h m / 2).
  std::vector<Vec3> mismatch(n - 1);
  for (std::size_t i = 0; i + 1 < n; ++i) mismatch[i] = increment[i] - 0.5 * (rate[i] + rate[i + 1]) * (t_s[i + 1] - t_s[i]);
  for (std::size_t j = 0; j + 1 < n; ++j) {
    if (!step[j]) continue;
    const double h = t_s[j + 1] - t_s[j];
    const double span = quantum > 0.0 ? std::pow(increment_quantum / (quantum * h), 2.0 / 3.0) : static_cast<double>(kStepSpan);
    const auto m = static_cast<std::size_t>(std::clamp(std::lround(span), 1L, static_cast<long>(kStepSpan)));
    // The position (say) at t_j and at t_j+1 as the samples before and after predict them.
    Vec3 before = Vec3::Zero(), after = Vec3::Zero(), sum = Vec3::Zero();
    std::size_t nb = 1, na = 1;  // a = 0: the sample itself
    for (std::size_t a = 1; a < m && a <= j && !step[j - a]; ++a, ++nb) before += (sum -= mismatch[j - a]);
    sum.setZero();
    for (std::size_t b = 1; b < m && j + b + 1 < n && !step[j + b]; ++b, ++na) after += (sum += mismatch[j + b]);
    const Vec3 across = increment[j] + after / static_cast<double>(na) - before / static_cast<double>(nb);
    // across = rate[j] s h + rate[j+1] (1 - s) h, solved for s along the jump.
    const Vec3 dv = rate[j] - rate[j + 1];
    const double s = (across - rate[j + 1] * h).dot(dv) / (dv.squaredNorm() * h);
    out[j] = std::isfinite(s) ? std::clamp(s, 0.0, 1.0) : 0.5;
  }
  return out;
}

double slope_over(const std::vector<double>& t_s, const std::vector<double>& x, std::size_t lo, std::size_t hi) {
  double tm = 0.0, xm = 0.0;
  for (std::size_t j = lo; j <= hi; ++j) {
    tm += t_s[j];
    xm += x[j];
  }
  tm /= static_cast<double>(hi - lo + 1);
  xm /= static_cast<double>(hi - lo + 1);
  double stt = 0.0, stx = 0.0;
  for (std::size_t j = lo; j <= hi; ++j) {
    const double dt = t_s[j] - tm;
    stt += dt * dt;
    stx += dt * (x[j] - xm);
  }
  return stt > 0 ? stx / stt : 0.0;
}

std::vector<double> windowed_slope(const std::vector<double>& t_s, const std::vector<double>& x, int half_window) {
  const auto n = static_cast<std::ptrdiff_t>(x.size());
  std::vector<double> out(x.size(), 0.0);
  for (std::ptrdiff_t k = 0; k < n; ++k) {
    const std::ptrdiff_t lo = std::max<std::ptrdiff_t>(0, k - half_window), hi = std::min<std::ptrdiff_t>(n - 1, k + half_window);
    out[static_cast<std::size_t>(k)] = slope_over(t_s, x, static_cast<std::size_t>(lo), static_cast<std::size_t>(hi));
  }
  return out;
}

RateChoice choose_rate(const std::vector<double>& t_s, const std::vector<double>& x_m, const std::vector<double>& v_m_per_s,
                       RateSource rates, int half_window) {
  const std::size_t n = t_s.size();
  if (x_m.size() != n || v_m_per_s.size() != n || n < 2 || half_window < 2)
    throw std::invalid_argument("choose_rate: needs as many positions and velocities as times (>= 2), and a half-window >= 2");
  for (std::size_t k = 0; k < n; ++k)
    if (!std::isfinite(t_s[k]) || !std::isfinite(x_m[k]) || !std::isfinite(v_m_per_s[k]) || (k > 0 && !(t_s[k] > t_s[k - 1])))
      throw std::invalid_argument("choose_rate: sample " + std::to_string(k) + ": non-finite value or time not increasing");
  RateChoice c;
  c.v_m_per_s = v_m_per_s;
  c.position_quantum_m = quantum_of(x_m);
  c.velocity_quantum_m_per_s = quantum_of(v_m_per_s);
  std::vector<double> dts(n - 1);
  for (std::size_t k = 1; k < n; ++k) dts[k - 1] = t_s[k] - t_s[k - 1];
  std::nth_element(dts.begin(), dts.begin() + static_cast<long>(dts.size() / 2), dts.end());
  const double dt = dts[dts.size() / 2];
  // White noise of variance σ² on the positions gives a slope over ± h samples the variance σ²/Σt².
  // The two streams' errors are independent: E(slope - twist)² = mse_slope + mse_twist. A twist
  // quantised at q has mse_twist = q²/12 when the motion crosses its levels (the error is then
  // uniform), less where the motion sits on the grid (a commanded speed may). So:
  //  * E(slope - twist)² < 3/4 q²/12: the twist's error is below its bound and its size unknown:
  //    the reported twist is kept (the conservative choice);
  //  * else mse_slope = E(slope - twist)² - q²/12 (noise and smoothing bias together), and the
  //    slope is taken when that is below half the twist's.
  const double var_twist = c.velocity_quantum_m_per_s * c.velocity_quantum_m_per_s / 12.0;
  const double var_x = c.position_quantum_m * c.position_quantum_m / 12.0;
  const double var_slope = var_x / (dt * dt * half_window * (half_window + 1.0) * (2.0 * half_window + 1.0) / 3.0);
  const bool quantised = c.position_quantum_m > 0 && var_twist > 0;
  if (rates == RateSource::twist || (rates == RateSource::automatic && !(quantised && var_slope < 0.5 * var_twist))) return c;
  const std::vector<double> slope = windowed_slope(t_s, x_m, half_window);
  double msd = 0.0;
  for (std::size_t k = 0; k < n; ++k) msd += (slope[k] - v_m_per_s[k]) * (slope[k] - v_m_per_s[k]);
  msd /= static_cast<double>(n);
  const double mse = std::max(var_slope, msd - var_twist);
  if (var_twist > 0) c.mse_ratio = mse / var_twist;
  c.from_poses = rates == RateSource::poses || (msd >= 0.75 * var_twist && mse < 0.5 * var_twist);
  if (c.from_poses) c.v_m_per_s = slope;
  return c;
}

std::string ContactData::rate_source() const {
  static const char* axis[] = {"x", "y", "z"};
  std::string from_poses, detail;
  char buf[160];
  for (int a = 0; a < 3; ++a) {
    if (!rate_from_poses[static_cast<std::size_t>(a)]) continue;
    from_poses += std::string(from_poses.empty() ? "" : ", ") + axis[a];
    if (std::isnan(rate_mse_ratio(a))) std::snprintf(buf, sizeof buf, "%s%s: chosen", detail.empty() ? "" : "; ", axis[a]);
    else
      std::snprintf(buf, sizeof buf,
                    "%s%s: position step %.3g m, twist step %.3g m/s, the slope's estimated mean square error %.2f of the twist's bound",
                    detail.empty() ? "" : "; ", axis[a], position_quantum_m(a), velocity_quantum_m_per_s(a), rate_mse_ratio(a));
    detail += buf;
  }
  if (from_poses.empty()) return "penetration rates from the reported twist";
  return "penetration rates along " + from_poses + " from the slope of the reported positions over +-" + std::to_string(kRateHalfWindow) +
         " samples (" + detail + ")";
}

Vector6d plate_wrench_of(const Eigen::Isometry3d& T_world_fp, const Vec3& f, const Vec3& p) {
  // The plate feels -f applied at p; moment about the plate origin, both in the plate frame.
  const Vec3 o = T_world_fp.translation();
  Vector6d w;
  w.head<3>() = T_world_fp.linear().transpose() * (-f);
  w.tail<3>() = T_world_fp.linear().transpose() * (p - o).cross(-f);
  return w;
}

ContactData make_contact_data(const cid::Scene& scene, double v_tm, const std::vector<cid::Measurement>& m, double force_scale_n,
                              double moment_scale_nm, RateSource rates) {
  ContactData d;
  d.scene = scene;
  d.v_tm = v_tm;
  const std::size_t n = m.size();
  if (n < 10) throw std::runtime_error("the run has " + std::to_string(n) + " samples: too few to diagnose");
  d.obs.t_s.resize(n);
  d.obs.y.resize(static_cast<Eigen::Index>(n), 6);
  d.kin.resize(n);
  d.contacts.resize(n);
  const Eigen::VectorXd xd = scene.design();
  cid::MindistWorkspace ws;
  std::vector<double> deltas;
  double fmax = 0.0, mmax = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    if (!m[k].w_fp.allFinite() || !m[k].kin.T_world_ee.matrix().allFinite() || !m[k].kin.v_world_ee.allFinite() ||
        !m[k].kin.w_world_ee.allFinite() || !std::isfinite(m[k].t_s))
      throw std::runtime_error("sample " + std::to_string(k) + " (t = " + std::to_string(m[k].t_s) + " s): non-finite value");
    if (k > 0 && !(m[k].t_s > m[k - 1].t_s)) throw std::runtime_error("sample " + std::to_string(k) + ": time does not increase");
    d.obs.t_s[k] = m[k].t_s;
    d.obs.y.row(static_cast<Eigen::Index>(k)) = m[k].w_fp.transpose();
    d.kin[k] = m[k].kin;
    cid::mindist(scene, m[k].kin, xd, v_tm, d.contacts[k], ws);
    if (!d.contacts[k].empty()) ++d.samples_in_contact;
    for (const auto& c : d.contacts[k]) deltas.push_back(c.delta);
    fmax = std::max(fmax, m[k].w_fp.head<3>().cwiseAbs().maxCoeff());
    mmax = std::max(mmax, m[k].w_fp.tail<3>().cwiseAbs().maxCoeff());
  }
  if (d.samples_in_contact == 0)
    throw std::runtime_error("no sample brings the objects into contact under the nominal geometry: nothing to diagnose");
  for (int c = 0; c < 6; ++c) {
    const std::vector<double> series(d.obs.y.col(c).data(), d.obs.y.col(c).data() + n);
    d.resolution(c) = quantum_of(series);
    d.quantisation_bias_variance(c) = quantisation_bias_variance(series, d.resolution(c));
  }

  // The damping's penetration rates. Their noise attenuates the fitted D (errors in variables) and,
  // at a coarse twist step, hides the rate altogether; a quantised pose stream's slope is often far
  // less noisy than a quantised twist.
  d.v_rate_world.resize(n);
  for (int a = 0; a < 3; ++a) {
    std::vector<double> x(n), v(n);
    for (std::size_t k = 0; k < n; ++k) {
      x[k] = d.kin[k].T_world_ee.translation()(a);
      v[k] = d.kin[k].v_world_ee(a);
    }
    const RateChoice c = choose_rate(d.obs.t_s, x, v, rates);
    d.position_quantum_m(a) = c.position_quantum_m;
    d.velocity_quantum_m_per_s(a) = c.velocity_quantum_m_per_s;
    d.rate_mse_ratio(a) = c.mse_ratio;
    d.rate_from_poses[static_cast<std::size_t>(a)] = c.from_poses;
    for (std::size_t k = 0; k < n; ++k) d.v_rate_world[k](a) = c.v_m_per_s[k];
  }
  // Where the reported twist and the rates step (a robot's moves and stops), placed by the poses.
  {
    std::vector<Vec3> v(n), w(n), dp(n - 1), dth(n - 1);
    Vec3 w_quantum = Vec3::Zero(), rate_quantum = Vec3::Zero();
    for (std::size_t k = 0; k < n; ++k) {
      v[k] = d.kin[k].v_world_ee;
      w[k] = d.kin[k].w_world_ee;
      if (k + 1 < n) {
        dp[k] = d.kin[k + 1].T_world_ee.translation() - d.kin[k].T_world_ee.translation();
        dth[k] = so3::log(Eigen::Matrix3d(d.kin[k + 1].T_world_ee.linear() * d.kin[k].T_world_ee.linear().transpose()));  // world frame
      }
    }
    for (int a = 0; a < 3; ++a) {
      std::vector<double> c(n);
      for (std::size_t k = 0; k < n; ++k) c[k] = w[k](a);
      w_quantum(a) = quantum_of(c);
      rate_quantum(a) = d.rate_from_poses[static_cast<std::size_t>(a)] ? 0.0 : d.velocity_quantum_m_per_s(a);
    }
    const double q_p = d.position_quantum_m.norm();
    d.v_step = rate_steps(d.obs.t_s, v, dp, d.velocity_quantum_m_per_s.norm(), q_p);
    d.w_step = rate_steps(d.obs.t_s, w, dth, w_quantum.norm(), 0.0);
    d.rate_step = rate_steps(d.obs.t_s, d.v_rate_world, dp, rate_quantum.norm(), q_p);
  }
  std::nth_element(deltas.begin(), deltas.begin() + static_cast<long>(deltas.size() / 2), deltas.end());
  d.delta_ref_m = deltas[deltas.size() / 2];
  const double fs = force_scale_n > 0 ? force_scale_n : (fmax > 0 ? fmax : 1.0);
  const double ms = moment_scale_nm > 0 ? moment_scale_nm : (mmax > 0 ? mmax : 1.0);
  d.obs.weight << 1 / fs, 1 / fs, 1 / fs, 1 / ms, 1 / ms, 1 / ms;

  // Which feature uncertainties the data can inform (contact paper sec. 7.2.1).
  if (!scene.uncertainties.empty()) {
    try {
      cid::ContactProblem p(scene, m);
      const auto obs = cid::analyse_observability(p, xd);
      for (int j = 0; j < p.uncertainties(); ++j) {
        const auto& name = scene.uncertainties[static_cast<std::size_t>(j)].name;
        const bool unobs = std::find(obs.unobservable.begin(), obs.unobservable.end(), name) != obs.unobservable.end();
        const bool weak = std::find(obs.weak.begin(), obs.weak.end(), name) != obs.weak.end();
        if (unobs || weak) d.unfit_uncertainties.push_back(name + (unobs ? " (unobservable)" : " (weakly observable)"));
        else d.fit_uncertainties.push_back(j);
      }
    } catch (const std::exception& e) {
      d.unfit_uncertainties.push_back(std::string("all (") + e.what() + ")");
    }
  }
  return d;
}

ContactFamily::ContactFamily(const ContactData& d, std::set<std::string> extensions)
    : ContactFamily(d, std::move(extensions), std::vector<int>{}) {}

std::unique_ptr<ModelFamily> ContactFamily::restricted(const std::vector<int>& train) const {
  if (std::none_of(terms_.begin(), terms_.end(), [](const Bound& b) { return b.term->derives_from_data(); })) return nullptr;
  // The pair table depends on the design geometry and the measured poses only: shared.
  return std::unique_ptr<ModelFamily>(new ContactFamily(d_, ext_, train, pairs_));
}

std::vector<ModelFamily::ModelForm> ContactFamily::model_forms() const {
  std::vector<ModelForm> out;
  for (const double kappa : {-0.75, 0.75}) {
    auto m = std::make_unique<ContactFamily>(*this);
    m->friction_lever_ = kappa;
    // Always covered (a level plate's gains make it collinear with μK), and its values weighted by
    // how much the run prefers it (a point foot's friction at its tip biased the tilting moments,
    // and where the run preferred it by less than the margin, the delay: docs/diagnosis.md).
    out.push_back({std::string("the friction's line of action 3/4 of the interference's depth from its centroid ") +
                       (kappa < 0 ? "against" : "along") + " the normal",
                   std::move(m),
                   false,
                   {},
                   true,
                   true});
  }
  if (has("time_offset") && !lag_filter_) {
    auto m = std::make_unique<ContactFamily>(*this);
    m->lag_filter_ = true;
    const auto it = std::find_if(nonlinear_.begin(), nonlinear_.end(), [](const Param& q) { return q.name == "time_offset_s"; });
    m->nonlinear_.push_back({kLagFilter, "s", it->scale, true, 0.0, it->upper});
    m->nonlinear_owner_.push_back(-1);
    // Starts around the pure delay's optimum τ_p: the filter's cost is flat at τ_f = 0 to first
    // order (a short filter is a short delay), and the delay's steps where the motion kinks stop a
    // search along τ_d (delay_crossings). A pure-delay fit reads a filter as a delay of c τ_f, c
    // between ln 2 (steps) and 1 (ramps): the starts lie about that valley, τ_d = τ_p - c τ_f.
    const auto tau = static_cast<Eigen::Index>(it - nonlinear_.begin());
    auto from = [tau](const Eigen::VectorXd& optimum) {
      std::vector<Eigen::VectorXd> x;
      const double tp = optimum(tau);
      if (!(tp > 0)) return x;  // a lead: no causal filter leads
      for (const double share : {0.1, 0.2, 0.35, 0.5, 0.75, 1.0, 1.4})
        for (const double c : {0.6, 0.75, 0.9}) {
          x.push_back(optimum);
          x.back()(tau) = tp - c * share * tp;
          x.back()(optimum.size() - 1) = share * tp;
        }
      return x;
    };
    out.push_back({"the wrench's lag a pure delay followed by a first-order low-pass filter, both fitted (time_offset_s their sum)",
                   std::move(m), true, from});
  }
  if (has("contact_damping") && damping_depth_m_ == 0.0) {
    // δ̄ = Σ δ δ̇² / Σ δ̇² over the run's contacts (design geometry, measured poses, the rates the
    // columns use): then Σ D (δ/δ̄) δ̇² / Σ δ̇² = D, the form's D is its best linear dashpot.
    double num = 0.0, den = 0.0;
    for (std::size_t k = 0; k < d_.contacts.size(); ++k) {
      cid::Kinematics k_rate = d_.kin[k];
      k_rate.v_world_ee = d_.v_rate_world[k];
      for (const auto& c : d_.contacts[k]) {
        const double rate = cid::relative_velocity(d_.scene, k_rate, c.point).dot(c.normal);
        num += c.delta * rate * rate;
        den += rate * rate;
      }
    }
    if (den > 0.0 && num > 0.0) {
      auto m = std::make_unique<ContactFamily>(*this);
      m->damping_depth_m_ = num / den;
      out.push_back({"Hunt-Crossley's dashpot D (δ/δ̄) δ̇ instead of a linear one (δ̄ the run's rate-weighted mean interference)",
                     std::move(m),
                     true,
                     {},
                     true});
    }
  }
  if (has("contact_damping") && has("slow_slip") && !slow_friction_elastic_) {
    // The family's slow contacts bear μ_s times the total normal force, as the sliding ones' bound
    // follows it with μ_D; a contact law whose friction follows the elastic force only (μ_D = 0)
    // puts the slow contacts' on it too. The run decides it where the damping's share of the slow
    // friction shows (development draws: by 18-3,800 long-run variances either way on 6 of 9 and 5
    // of 9), and its values are taken there; elsewhere it widens μ_s / μ (docs/diagnosis.md).
    auto m = std::make_unique<ContactFamily>(*this);
    m->slow_friction_elastic_ = true;
    out.push_back({kSlowFrictionElasticForm, std::move(m), true, {}, true});
  }
  return out;
}

std::vector<ModelFamily::ErrorInVariable> ContactFamily::errors_in_variables() const {
  std::vector<ErrorInVariable> out;
  if (lag_filter_) return out;  // a model form's refit: never scored on its own
  const std::size_t n = d_.kin.size();
  for (int a = 0; a < 3; ++a) {
    const double step = d_.position_quantum_m(a);
    if (!(step > 0)) continue;
    // The correction is an expectation over where the true position lies within its step. Along a
    // held position (kHoldSamples or more equal reported values in a row) that is one unknown
    // offset for the whole hold, a first-order error the correction cannot represent; a run whose
    // press holds at a value on the grid has no error there at all. An axis held for more than
    // kHeldShare of the run is not declared.
    std::size_t held = 0, same = 1;
    for (std::size_t k = 1; k <= n; ++k) {
      if (k < n && d_.kin[k].T_world_ee.translation()(a) == d_.kin[k - 1].T_world_ee.translation()(a)) {
        ++same;
        continue;
      }
      if (same >= kHoldSamples) held += same;
      same = 1;
    }
    if (static_cast<double>(held) > kHeldShare * static_cast<double>(n)) continue;
    auto shifted = [this, a](double by_m) {
      auto data = std::make_shared<ContactData>(d_);
      const Eigen::VectorXd xd = data->scene.design();
      cid::MindistWorkspace ws;
      data->samples_in_contact = 0;
      for (std::size_t k = 0; k < data->kin.size(); ++k) {
        data->kin[k].T_world_ee.translation()(a) += by_m;
        cid::mindist(data->scene, data->kin[k], xd, data->v_tm, data->contacts[k], ws);
        if (!data->contacts[k].empty()) ++data->samples_in_contact;
      }
      // Its effects bound to the shifted data (a choice they derive from it is made anew, and a
      // family whose parameters then differ gets no correction: errors_in_variables_bias).
      std::unique_ptr<ContactFamily> m(new ContactFamily(*data, ext_, samples_, nullptr));
      m->owned_ = std::move(data);
      m->friction_lever_ = friction_lever_;
      m->damping_depth_m_ = damping_depth_m_;
      return std::unique_ptr<ModelFamily>(std::move(m));
    };
    out.push_back({fmt::format("the reported ee position along world {} (quantised to {:.3g} um)", "xyz"[a], 1e6 * step),
                   step / std::sqrt(12.0), shifted});
  }
  return out;
}

ContactFamily::ContactFamily(const ContactData& d, std::set<std::string> extensions, const std::vector<int>& samples)
    : ContactFamily(d, std::move(extensions), samples, nullptr) {}

ContactFamily::ContactFamily(const ContactData& d, std::vector<std::shared_ptr<const ContactTerm>> terms, std::set<std::string> names,
                             std::shared_ptr<const PairTable> pairs)
    : d_(d), ext_(std::move(names)), pairs_(std::move(pairs)) {
  std::vector<Bound> bound;
  for (auto& t : terms) bound.push_back({std::move(t), {}, static_cast<int>(bound.size())});
  add_terms(std::move(bound));
}

ContactFamily::ContactFamily(const ContactData& d, std::set<std::string> extensions, const std::vector<int>& samples,
                             std::shared_ptr<const PairTable> pairs)
    : d_(d), samples_(samples), ext_(std::move(extensions)), pairs_(std::move(pairs)) {
  std::vector<int> used = samples;
  if (used.empty()) {
    used.resize(d.obs.size());
    for (std::size_t k = 0; k < used.size(); ++k) used[k] = static_cast<int>(k);
  }
  const auto& names = contact_extensions();
  for (const auto& e : ext_)
    if (std::find(names.begin(), names.end(), e) == names.end()) throw std::invalid_argument("unknown extension '" + e + "'");
  // The effects in the registry's order (report_rank), bound in their layout order: an effect that
  // derives a choice from the design (robot_compliance) finds the pair table made.
  std::vector<std::pair<const ContactEffect*, int>> effects;
  for (const auto& n : names)
    if (has(n)) effects.emplace_back(find_effect(n)->contact(), static_cast<int>(effects.size()));
  std::stable_sort(effects.begin(), effects.end(),
                   [](const auto& a, const auto& b) { return a.first->layout_order() < b.first->layout_order(); });
  const ContactBinding binding{d, used, [&](std::shared_ptr<const ContactTerm> term, const Eigen::VectorXd& phi, Eigen::MatrixXd& A) {
                                 if (!pairs_) pairs_ = make_pairs(d);
                                 ContactFamily alone(d, {std::move(term)}, {}, pairs_);
                                 alone.design(phi, A);
                               }};
  std::vector<Bound> bound;
  for (const auto& [effect, rank] : effects) bound.push_back({effect->bind(binding), {}, rank});
  add_terms(std::move(bound));
}

void ContactFamily::add_terms(std::vector<Bound> terms) {
  linear_.push_back({"K", "N/m", 1e5, false});
  linear_.push_back({"muK", "N/m", 1e4, false});
  linear_owner_.assign(2, -1);
  terms_ = std::move(terms);
  for (std::size_t t = 0; t < terms_.size(); ++t) {
    auto& b = terms_[t];
    for (const auto& q : b.term->linear()) {
      if (b.slots.linear < 0) b.slots.linear = static_cast<Eigen::Index>(linear_.size());
      linear_.push_back(q);
      linear_owner_.push_back(static_cast<int>(t));
    }
    for (const auto& q : b.term->nonlinear()) {
      if (b.slots.nonlinear < 0) b.slots.nonlinear = static_cast<Eigen::Index>(nonlinear_.size());
      nonlinear_.push_back(q);
      nonlinear_owner_.push_back(static_cast<int>(t));
    }
    moves_contacts_ = moves_contacts_ || b.term->moves_contacts();
    needs_rates_ = needs_rates_ || b.term->needs_rates();
  }
  if (!pairs_ && moves_contacts_) pairs_ = make_pairs(d_);
}

std::string ContactFamily::name() const {
  if (ext_.empty()) return "nominal";
  std::string s;
  for (const auto& e : contact_extensions())
    if (has(e)) s += (s.empty() ? "" : "+") + e;
  return s;
}

std::vector<Eigen::VectorXd> ContactFamily::starts() const {
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(nonlinear_.size()));
  std::vector<Eigen::VectorXd> out{zero};
  std::vector<const Bound*> ranked;
  for (const auto& b : terms_) ranked.push_back(&b);
  std::sort(ranked.begin(), ranked.end(), [](const Bound* a, const Bound* b) { return a->report_rank < b->report_rank; });
  for (const Bound* b : ranked) b->term->starts(b->slots, zero, out);
  return out;
}

std::vector<Eigen::VectorXd> ContactFamily::starts_near(const Eigen::VectorXd& best) const {
  std::vector<Eigen::VectorXd> out;
  for (const auto& b : terms_) b.term->starts_near(b.slots, best, out);
  return out;
}

void ContactFamily::columns(const std::vector<cid::ContactPoint>& cs, const cid::Kinematics& k, const Vec3& v_rate,
                            const ContactChannels& ch, Eigen::Ref<Eigen::MatrixXd> out) const {
  const auto& T = d_.scene.T_world_fp;
  const double p = ch.stiffness_exponent;
  cid::Kinematics k_rate = k;
  k_rate.v_world_ee = v_rate;
  for (const auto& c : cs) {
    const double de = p == 1.0 ? c.delta : d_.delta_ref_m * std::pow(c.delta / d_.delta_ref_m, p);
    // With damping the normal force is K (δ_e + τ_D δ̇): a foot withdrawing faster than δ_e / τ_D
    // pushes nothing and does not pull, so it bears no friction either (issue 32: a damping column
    // D δ̇ wherever the contact exists predicted a pull there, and the fit lowered D).
    double normal = de;
    const double dashpot = damping_depth_m_ > 0.0 ? c.delta / damping_depth_m_ : 1.0;  // the Hunt-Crossley form's δ / δ̄
    if (ch.damping_time_s != 0.0) {
      normal += ch.damping_time_s * dashpot * -cid::relative_velocity(d_.scene, k_rate, c.point).dot(c.normal);
      if (normal <= 0.0) continue;
    }
    const Eigen::Vector3d pt = c.point + friction_lever_ * c.delta * c.normal;  // the tangential forces' point
    out.col(0) += plate_wrench_of(T, normal * c.normal, c.point);
    out.col(1) += plate_wrench_of(T, de * c.tangent, pt);
    const ContactAt at{d_, c, k_rate, pt, dashpot, de, slow_friction_elastic_ ? de : normal};
    for (const auto& b : terms_) b.term->contact_columns(b.slots, at, out);
  }
}

ContactFamily::SincWeights ContactFamily::sinc_weights(double t) const {
  const auto& ts = d_.obs.t_s;
  // The interval [t_j0, t_j0+1) holding t and the fraction a in it (the sample times may jitter:
  // the neighbours count as evenly spaced).
  const auto it = std::upper_bound(ts.begin(), ts.end(), t);
  const std::ptrdiff_t j0 = std::max<std::ptrdiff_t>(0, (it - ts.begin()) - 1);
  const auto at = [&](std::ptrdiff_t j) { return ts[static_cast<std::size_t>(j)]; };
  const double a = it == ts.begin() || it == ts.end() ? 0.0 : (t - at(j0)) / (at(j0 + 1) - at(j0));
  SincWeights w;
  w.first = j0;
  w.interval = j0;
  w.fraction = a;
  if (a == 0.0) return w;

  constexpr int m = 2 * kSincLobes;
  static_assert(m <= SincWeights::kMaxTaps);
  constexpr double pi = 3.14159265358979323846;
  const auto sinc = [](double x) { return x == 0.0 ? 1.0 : std::sin(pi * x) / (pi * x); };
  Eigen::Matrix<double, m, 1> h;
  Eigen::Matrix<double, 4, m> B;  // rows: the offsets' powers 0..3
  for (int i = 0; i < m; ++i) {
    const double x = (i + 1 - kSincLobes) - a;
    h(i) = sinc(x) * sinc(x / kSincLobes);
    B.col(i) << 1.0, x, x * x, x * x * x;
  }
  // Σ h x^p = [p = 0] for p = 0..3, by the least-norm correction.
  const Eigen::Vector4d miss = B * h - Eigen::Vector4d::UnitX();
  h -= B.transpose() * (B * B.transpose()).ldlt().solve(miss);
  w.first = j0 + 1 - kSincLobes;
  w.taps = m;
  std::copy(h.data(), h.data() + m, w.h.begin());
  return w;
}

cid::Kinematics ContactFamily::kinematics_at(double t) const { return kinematics_at(sinc_weights(t)); }

cid::Kinematics ContactFamily::kinematics_at(const SincWeights& sw) const {
  const auto n = static_cast<std::ptrdiff_t>(d_.kin.size());
  const auto sample = [&](std::ptrdiff_t j) -> const cid::Kinematics& {
    return d_.kin[static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(j, 0, n - 1))];
  };
  if (sw.taps == 0) return sample(sw.first);
  const cid::Kinematics& centre = sample(sw.first + kSincLobes - 1);
  const Eigen::Quaterniond qc(centre.T_world_ee.linear());
  Eigen::Vector3d p = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero();
  Eigen::Vector4d q = Eigen::Vector4d::Zero();  // blended quaternions: the rotations within a window are close
  for (int i = 0; i < sw.taps; ++i) {
    const auto& k = sample(sw.first + i);
    const double hi = sw.h[static_cast<std::size_t>(i)];
    Eigen::Quaterniond qk(k.T_world_ee.linear());
    if (qk.dot(qc) < 0.0) qk.coeffs() = -qk.coeffs();
    p += hi * k.T_world_ee.translation();
    v += hi * k.v_world_ee;
    w += hi * k.w_world_ee;
    q += hi * qk.coeffs();
  }
  cid::Kinematics out = centre;
  out.T_world_ee.translation() = p;
  out.v_world_ee = v;
  out.w_world_ee = w;
  out.T_world_ee.linear() = Eigen::Quaterniond(q).normalized().toRotationMatrix();
  // Near a step of the twist the sinc rings (a stop's zero velocity turns into a slip in some
  // direction), and halfway is the wrong time for the step: there the twist is what the samples and
  // the step say, linear between them, stepping where the poses put the step. The poses stay the
  // sinc's: a linear blend would lower their quantisation noise at some fractions of a sample more
  // than others, and a fitted delay would drift there (above).
  const auto& k0 = sample(sw.interval);
  const auto& k1 = sample(sw.interval + 1);
  if (const auto v_step = velocity_near_step(d_.v_step, sw, k0.v_world_ee, k1.v_world_ee)) out.v_world_ee = *v_step;
  if (const auto w_step = velocity_near_step(d_.w_step, sw, k0.w_world_ee, k1.w_world_ee)) out.w_world_ee = *w_step;
  return out;
}

std::optional<Vec3> ContactFamily::velocity_near_step(const std::vector<double>& steps, const SincWeights& sw, const Vec3& v0,
                                                      const Vec3& v1) {
  if (steps.empty() || sw.taps == 0) return std::nullopt;
  const auto last = static_cast<std::ptrdiff_t>(steps.size()) - 1;
  bool near = false;
  for (std::ptrdiff_t j = std::max<std::ptrdiff_t>(0, sw.first); j <= std::min(last, sw.first + sw.taps - 2); ++j)
    near = near || std::isfinite(steps[static_cast<std::size_t>(j)]);
  if (!near) return std::nullopt;
  if (sw.interval >= 0 && sw.interval <= last && std::isfinite(steps[static_cast<std::size_t>(sw.interval)]))
    return sw.fraction < steps[static_cast<std::size_t>(sw.interval)] ? v0 : v1;
  const double a = sw.fraction;
  return Vec3((1 - a) * v0 + a * v1);
}

Vec3 ContactFamily::rate_velocity_at(const SincWeights& sw) const {
  const auto n = static_cast<std::ptrdiff_t>(d_.v_rate_world.size());
  const auto sample = [&](std::ptrdiff_t j) -> const Vec3& {
    return d_.v_rate_world[static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(j, 0, n - 1))];
  };
  if (sw.taps == 0) return sample(sw.first);
  if (const auto v_step = velocity_near_step(d_.rate_step, sw, sample(sw.interval), sample(sw.interval + 1))) return *v_step;
  Vec3 v = Vec3::Zero();
  for (int i = 0; i < sw.taps; ++i) v += sw.h[static_cast<std::size_t>(i)] * sample(sw.first + i);
  return v;
}

std::shared_ptr<const ContactFamily::PairTable> ContactFamily::make_pairs(const ContactData& d) {
  auto t = std::make_shared<PairTable>();
  const Eigen::VectorXd xd = d.scene.design();
  for (int b = 0; b < 2; ++b) {
    const auto& body = d.scene.bodies[static_cast<std::size_t>(b)];
    auto& index = t->index[static_cast<std::size_t>(b)];
    index = d.scene.polyhedron_index(b);
    for (const auto& [f, q] : index) {
      const Eigen::Isometry3d T = cid::feature_transform(d.scene.uncertainties, xd, b, f);
      double r = 0.0;
      for (const auto& v : body.features[static_cast<std::size_t>(f)].polyhedra[static_cast<std::size_t>(q)].vertices())
        r = std::max(r, (T * v).norm());
      t->radius_m[static_cast<std::size_t>(b)].push_back(r);
    }
  }
  cid::PosedScene ps;
  t->near.resize(d.obs.size());
  for (std::size_t k = 0; k < d.obs.size(); ++k) {
    cid::pose_scene(d.scene, xd, d.kin[k].T_world_ee, ps);
    const auto& A = ps.polys[0];
    const auto& B = ps.polys[1];
    for (std::size_t i = 0; i < A.size(); ++i)
      for (std::size_t j = 0; j < B.size(); ++j) {
        if (!cid::near(A[i], B[j], kReach_m)) continue;
        const double gap = cid::separation_lower_bound(A[i], B[j], kReach_m);
        if (gap > kReach_m) continue;
        t->near[k].push_back({static_cast<int>(i), static_cast<int>(j), gap > 0 ? gap : -std::numeric_limits<double>::infinity()});
      }
  }
  return t;
}

ContactFamily::Geometry ContactFamily::geometry_at(const Eigen::VectorXd& x, const Base& base) const {
  Geometry g;
  g.x = x;
  const Eigen::VectorXd xd = d_.scene.design();
  for (int b = 0; b < 2; ++b) {
    const auto bi = static_cast<std::size_t>(b);
    const auto& body = d_.scene.bodies[bi];
    for (std::size_t f = 0; f < body.features.size(); ++f)
      g.T_body_feature[bi].push_back(cid::feature_transform(d_.scene.uncertainties, x, b, static_cast<int>(f)));
    for (const auto& [f, q] : pairs_->index[bi]) {
      // A rigid motion moves a convex polyhedron's points farthest at a vertex.
      const Eigen::Isometry3d Td = cid::feature_transform(d_.scene.uncertainties, xd, b, f);
      double m = 0.0;
      for (const auto& v : body.features[static_cast<std::size_t>(f)].polyhedra[static_cast<std::size_t>(q)].vertices())
        m = std::max(m, (g.T_body_feature[bi][static_cast<std::size_t>(f)] * v - Td * v).norm());
      g.moved_m[bi].push_back(m);
    }
    g.changed[bi].assign(body.features.size(), true);
    if (base.valid)
      for (std::size_t f = 0; f < body.features.size(); ++f)
        g.changed[bi][f] = !(g.T_body_feature[bi][f].matrix().array() == base.T_body_feature[bi][f].matrix().array()).all();
  }
  return g;
}

bool ContactFamily::sample_contacts(std::size_t k, const cid::Kinematics& kin, const Geometry& g,
                                    const std::vector<cid::ContactPoint>* base, std::vector<cid::ContactPoint>& out, Scratch& w) const {
  const auto& sc = d_.scene;
  // How far each body moved from its measured pose: translation of its origin and turn angle.
  std::array<Eigen::Isometry3d, 2> T;
  std::array<double, 2> shift_m{}, turn_rad{}, reach_m{};
  // The most a point of polyhedron q of body b moved from the table's configuration.
  auto moved = [&](std::size_t b, std::size_t q) { return g.moved_m[b][q] + shift_m[b] + turn_rad[b] * pairs_->radius_m[b][q]; };
  for (std::size_t b = 0; b < 2; ++b) {
    T[b] = cid::body_pose(sc.bodies[b], kin.T_world_ee);
    if (sc.bodies[b].on_end_effector) {
      const Eigen::Isometry3d T0 = cid::body_pose(sc.bodies[b], d_.kin[k].T_world_ee);
      shift_m[b] = (T[b].translation() - T0.translation()).norm();
      turn_rad[b] = so3::angle(T[b].linear() * T0.linear().transpose());
    }
    w.done[b].assign(pairs_->index[b].size(), 0);
    w.posed[b].resize(pairs_->index[b].size());
    for (std::size_t q = 0; q < pairs_->index[b].size(); ++q) reach_m[b] = std::max(reach_m[b], moved(b, q));
  }
  if (reach_m[0] + reach_m[1] >= 0.5 * kReach_m) {  // beyond the table: every pair
    cid::mindist(sc, kin, g.x, d_.v_tm, out, w.ws);
    return false;
  }
  auto posed = [&](std::size_t b, int q) -> const cid::PosedPolyhedron& {
    const auto qi = static_cast<std::size_t>(q);
    if (!w.done[b][qi]) {
      const auto [f, p] = pairs_->index[b][qi];
      const Eigen::Isometry3d Tf = T[b] * g.T_body_feature[b][static_cast<std::size_t>(f)];  // as pose_scene
      w.posed[b][qi].pose(sc.bodies[b].features[static_cast<std::size_t>(f)].polyhedra[static_cast<std::size_t>(p)], Tf);
      w.done[b][qi] = 1;
    }
    return w.posed[b][qi];
  };
  out.clear();
  auto from_base = base ? base->begin() : std::vector<cid::ContactPoint>::const_iterator{};
  for (const auto& np : pairs_->near[k]) {
    const auto i = static_cast<std::size_t>(np.poly1), j = static_cast<std::size_t>(np.poly2);
    if (base && !g.changed[0][static_cast<std::size_t>(pairs_->index[0][i].first)] &&
        !g.changed[1][static_cast<std::size_t>(pairs_->index[1][j].first)]) {
      // Both features and the ee pose as in the base: the base's contact (if any) is this pair's.
      while (from_base != base->end() && std::make_pair(from_base->poly1, from_base->poly2) < std::make_pair(np.poly1, np.poly2))
        ++from_base;
      if (from_base != base->end() && from_base->poly1 == np.poly1 && from_base->poly2 == np.poly2) out.push_back(*from_base);
      continue;
    }
    if (np.gap_m > (moved(0, i) + moved(1, j)) * (1.0 + 1e-9) + 1e-12) continue;  // still apart
    const auto& A = posed(0, np.poly1);
    const auto& B = posed(1, np.poly2);
    cid::PairContact pc;
    if (!cid::near(A, B) || !cid::penetration(A, B, pc, w.ws.clip)) continue;
    cid::ContactPoint c{pc.delta, pc.point, pc.normal, Vec3::Zero(), 0.0, np.poly1, np.poly2};
    cid::tangent(sc, kin, d_.v_tm, c);
    out.push_back(c);
  }
  return true;
}

Context contact_context(const ContactData& d) {
  Context ctx;
  const std::size_t n = d.obs.size();
  auto& s = ctx.signals;
  for (const char* k :
       {"speed", "acceleration", "interference", "penetration_rate", "slip_speed", "load", "time", "px", "py", "pz", "vx", "vy", "vz"})
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
    ctx.state.push_back(cs.empty()
                            ? "no contact"
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

std::unique_ptr<FamilyData> ContactFamily::make_data() const { return std::make_unique<Data>(); }

void ContactFamily::design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData& data) const {
  auto& own = dynamic_cast<Data&>(data);  // a std::bad_cast on another family's data
  Base& base = own.base;
  const std::size_t n = d_.obs.size();
  const Eigen::Index p = static_cast<Eigen::Index>(linear_.size());
  A.setZero(static_cast<Eigen::Index>(6 * n), p);
  ContactChannels ch;
  ch.x = d_.scene.design();
  for (const auto& b : terms_) b.term->channels(b.slots, phi, ch);
  // The lag form: the model's wrench at the delayed poses, then filtered (below).
  const double lag_s = lag_filter_ ? phi(phi.size() - 1) : 0.0;
  const double tau = ch.delay_s;
  const bool recompute = ch.recompute;
  const Eigen::VectorXd& x = ch.x;
  const Matrix6d& C = ch.compliance;
  if (!recompute) {
    for (std::size_t k = 0; k < n; ++k)
      columns(d_.contacts[k], d_.kin[k], d_.v_rate_world[k], ch, A.block(static_cast<Eigen::Index>(6 * k), 0, 6, p));
  } else {
    if (!base.valid) {
      // The first base: the contacts at the design geometry and the measured poses.
      base.contacts = d_.contacts;  // every interfering pair is in the table (gap -inf)
      base.full.assign(n, false);
      base.T_body_feature = geometry_at(d_.scene.design(), base).T_body_feature;
      base.valid = true;
    }
    const Geometry g = geometry_at(x, base);
    const bool same_poses = tau == base.tau_s && C == base.C;
    int changed = 0;
    for (const auto& b : g.changed) changed += static_cast<int>(std::count(b.begin(), b.end(), true));
    std::vector<std::vector<cid::ContactPoint>> cs(n);
    std::vector<bool> full(n);
    for (std::size_t k = 0; k < n; ++k) {
      // A delayed wrench stream: the wrench at t_k is the one of the pose at t_k - τ.
      const SincWeights sw = tau != 0.0 ? sinc_weights(d_.obs.t_s[k] - tau) : SincWeights{static_cast<std::ptrdiff_t>(k)};
      cid::Kinematics kin = tau != 0.0 ? kinematics_at(sw) : d_.kin[k];
      const Vec3 v_rate = !needs_rates_ ? Vec3::Zero() : tau != 0.0 ? rate_velocity_at(sw) : d_.v_rate_world[k];
      if (ch.deflect) {
        // The measured contact wrench on the held object, about the ee origin, in ee.
        const Vector6d w_ee = cid::plate_to_object1(d_.obs.y.row(static_cast<Eigen::Index>(k)).transpose(), d_.scene.T_world_fp,
                                                    kin.T_world_ee);
        kin.T_world_ee = deflect(kin.T_world_ee, C * w_ee);
      }
      const bool reuse = same_poses && !base.full[k];
      full[k] = !sample_contacts(k, kin, g, reuse ? &base.contacts[k] : nullptr, cs[k], own.scratch);
      columns(cs[k], kin, v_rate, ch, A.block(static_cast<Eigen::Index>(6 * k), 0, 6, p));
    }
    // A finite-difference step moves one feature: the point it steps from stays the base.
    if (!same_poses || changed > 1) {
      base.tau_s = tau;
      base.C = C;
      base.T_body_feature = g.T_body_feature;
      base.contacts = std::move(cs);
      base.full = std::move(full);
    }
  }
  // A is linear in θ, so the filtered wrench is the design with each column filtered; the gains
  // (a scaling) and the bias (a constant, which a settled filter passes) commute with it.
  if (lag_s > 0) first_order_lag(d_.obs.t_s, lag_s, A);
  // Row scalings (sensor_gain) before constant columns (sensor_bias): the layout order.
  for (const auto& b : terms_) b.term->finish(b.slots, phi, A);
}

void first_order_lag(const std::vector<double>& t_s, double tau_s, Eigen::Ref<Eigen::MatrixXd> A) {
  const std::size_t n = t_s.size();
  if (!(tau_s > 0) || n < 2) return;
  if (A.rows() % static_cast<Eigen::Index>(n) != 0) throw std::invalid_argument("first_order_lag: rows are not a multiple of the samples");
  const Eigen::Index c = A.rows() / static_cast<Eigen::Index>(n);
  // y' = (x - y) / τ with x linear between its samples (first-order hold): over a step h with slope
  // s = (x_k - x_k-1) / h, y_k = x_k - s τ + e^(-h/τ) (y_k-1 - x_k-1 + s τ), exact. The first
  // sample starts settled (y = x); a step that does not advance in time (another run) restarts it.
  Eigen::MatrixXd prev = A.topRows(c);  // x_k-1
  for (std::size_t k = 1; k < n; ++k) {
    const double h = t_s[k] - t_s[k - 1];
    auto row = A.middleRows(static_cast<Eigen::Index>(k) * c, c);
    const Eigen::MatrixXd x = row;
    if (h > 0) {
      const double a = std::exp(-h / tau_s), b = tau_s / h;
      const auto y_prev = A.middleRows(static_cast<Eigen::Index>(k - 1) * c, c);
      row = x - b * (x - prev) + a * (y_prev - prev + b * (x - prev));
    }
    prev = x;
  }
}

std::vector<Reported> ContactFamily::report(const Fit& f) const {
  std::vector<Reported> out;
  const double K = f.theta(0), muK = f.theta(1);
  out.push_back({"K", "N/m", K, std::sqrt(std::max(0.0, f.cov(0, 0))), false});
  const double mu = K != 0 ? muK / K : 0.0;
  const double vmu = (f.cov(1, 1) - 2 * mu * f.cov(0, 1) + mu * mu * f.cov(0, 0)) / (K * K);
  if (!f.is_fixed(1)) out.push_back({"mu", "", mu, std::sqrt(std::max(0.0, vmu)), false});  // fixed: nothing slides
  const Eigen::Index p = static_cast<Eigen::Index>(linear_.size());
  // Each parameter's line as fitted, then as its effect reads it (a derived name, a nominal value).
  auto line = [&](bool linear, Eigen::Index j, const Param& q, double value, Eigen::Index cov_index) {
    if (!linear && nonlinear_owner_[static_cast<std::size_t>(j)] < 0) {  // the lag form's filter
      out.push_back({q.name, q.unit, value, std::sqrt(std::max(0.0, f.cov(cov_index, cov_index))), true});
      return;
    }
    const Bound& b = terms_[static_cast<std::size_t>((linear ? linear_owner_ : nonlinear_owner_)[static_cast<std::size_t>(j)])];
    const Eigen::Index index = j - (linear ? b.slots.linear : b.slots.nonlinear);
    const double var = std::max(0.0, f.cov(cov_index, cov_index)) + b.term->added_variance(linear, index);
    Reported r{q.name, q.unit, value, std::sqrt(var), true};
    b.term->report(b.slots, linear, index, f, r);
    out.push_back(r);
  };
  for (Eigen::Index j = 2; j < p; ++j) line(true, j, linear_[static_cast<std::size_t>(j)], f.theta(j), j);
  for (Eigen::Index j = 0; j < static_cast<Eigen::Index>(nonlinear_.size()); ++j)
    line(false, j, nonlinear_[static_cast<std::size_t>(j)], f.phi(j), p + j);
  for (const auto& b : terms_) b.term->report_derived(b.slots, p, f, out);
  if (lag_filter_) {  // the chain's low-frequency group delay: the delay and the filter's lag
    const double tau_f = f.phi(f.phi.size() - 1);
    for (auto& r : out)
      if (r.name == "time_offset_s") r.value += tau_f;
  }
  return out;
}

double max_min_eigenvalue(const Matrix6d& C, const std::vector<Matrix6d>& free_directions, int iterations) {
  Matrix6d X = C;
  Eigen::SelfAdjointEigenSolver<Matrix6d> es(X);
  double best = es.eigenvalues()(0);
  if (free_directions.empty()) return best;
  const double step0 = std::max(C.norm(), 1e-12);
  for (int it = 0; it < iterations && best < 0; ++it) {
    const Vector6d u = es.eigenvectors().col(0);
    Eigen::VectorXd g(static_cast<Eigen::Index>(free_directions.size()));
    for (std::size_t k = 0; k < free_directions.size(); ++k) g(static_cast<Eigen::Index>(k)) = u.dot(free_directions[k] * u);
    const double gn = g.norm();
    if (!(gn > 1e-12)) break;  // no free direction moves the lowest eigenvalue
    const double step = step0 / std::sqrt(1.0 + it);
    for (std::size_t k = 0; k < free_directions.size(); ++k) X += (step * g(static_cast<Eigen::Index>(k)) / gn) * free_directions[k];
    es.compute(X);
    best = std::max(best, es.eigenvalues()(0));
  }
  return best;
}

std::vector<std::string> ContactFamily::notes() const {
  std::vector<const Bound*> ordered;
  for (const auto& b : terms_) ordered.push_back(&b);
  std::stable_sort(ordered.begin(), ordered.end(), [](const Bound* a, const Bound* b) { return a->report_rank < b->report_rank; });
  std::vector<std::string> out;
  for (const Bound* b : ordered)
    if (auto n = b->term->note(); !n.empty()) out.push_back(std::move(n));
  return out;
}

std::string ContactFamily::check(const Fit& f) const {
  for (const auto& q : f.reported) {
    if (q.name == "K" && !(q.value > 0)) return "K = " + std::to_string(q.value) + " N/m is not positive";
    if (q.name == "mu" && q.value < -2.0 * q.std) return q.name + " = " + std::to_string(q.value) + " is negative";
    for (const auto& b : terms_)
      if (auto why = b.term->check_line(q); !why.empty()) return why;
  }
  for (const auto& b : terms_)
    if (auto why = b.term->check(b.slots, static_cast<Eigen::Index>(linear_.size()), f); !why.empty()) return why;
  return "";
}

// ---------------------------------------------------------------------------------------------

std::shared_ptr<const Injection> ContactEffect::draw(unsigned, const cid::Scene&) const {
  throw std::invalid_argument("'" + name() + "' cannot be injected into a simulation");
}

std::shared_ptr<const Injection> ContactEffect::inject(const TruthValues&) const {
  throw std::invalid_argument("'" + name() + "' cannot be injected into a simulation");
}

double truth_value(const TruthValues& values, const std::string& key, double fallback) {
  const auto it = values.find(key);
  return it == values.end() ? fallback : it->second;
}

void check_truth_keys(const std::string& effect, const TruthValues& values, const std::vector<std::string>& known) {
  for (const auto& [key, value] : values)
    if (std::find(known.begin(), known.end(), key) == known.end())
      throw std::invalid_argument(effect + ": no true value '" + key + "' (expected " + fmt::format("{}", fmt::join(known, ", ")) + ")");
}

hil::Vector6d per_component(const std::string& effect, const std::string& prefix, const TruthValues& values) {
  std::vector<std::string> keys;
  for (const char* c : kWrenchComponents) keys.push_back(prefix + c);
  check_truth_keys(effect, values, keys);
  Vector6d w;
  for (int c = 0; c < 6; ++c) w(c) = truth_value(values, keys[static_cast<std::size_t>(c)]);
  return w;
}

TruthValues by_component(const std::string& prefix, const hil::Vector6d& w) {
  TruthValues t;
  for (int c = 0; c < 6; ++c) t[prefix + kWrenchComponents[static_cast<std::size_t>(c)]] = w(c);
  return t;
}

void set_uncertainties(const cid::Scene& scene, const TruthValues& by_name, Eigen::VectorXd& x) {
  for (const auto& [name, v] : by_name) {
    bool found = false;
    for (std::size_t j = 0; j < scene.uncertainties.size(); ++j)
      if (scene.uncertainties[j].name == name) {
        x(static_cast<Eigen::Index>(j)) = v;
        found = true;
      }
    if (!found) throw std::invalid_argument("unknown geometric uncertainty '" + name + "'");
  }
}

namespace {

/// The registered injectable contact effect of that name. \throws std::invalid_argument if none.
const ContactEffect& injectable_effect(const std::string& name) {
  const Effect* effect = find_effect(name);
  if (!effect || !effect->contact())
    throw std::invalid_argument("unknown effect '" + name + "' (expected one of the diagnosis' candidates)");
  if (!effect->contact()->injectable())
    throw std::invalid_argument(fmt::format("effect '{}' is a diagnosis candidate the hidden-effect generator cannot hide (it hides {})",
                                            name, fmt::join(injectable_contact_effects(), ", ")));
  return *effect->contact();
}

/// The injected effects in their layout order (ContactEffect::layout_order, then the registry's):
/// the order their parts of the forward simulation are applied in.
std::vector<const Injection*> in_layout_order(const Effects& e) {
  std::vector<std::pair<int, const Injection*>> order;
  for (const Effect* x : registered_effects())
    if (const auto it = e.injected.find(x->name()); it != e.injected.end() && x->contact())
      order.emplace_back(x->contact()->layout_order(), it->second.get());
  std::stable_sort(order.begin(), order.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
  std::vector<const Injection*> out;
  for (const auto& [rank, inj] : order) out.push_back(inj);
  return out;
}

}  // namespace

std::vector<std::string> Effects::names() const {
  std::vector<std::string> n;
  for (const Effect* e : registered_effects())
    if (injected.count(e->name())) n.push_back(e->name());
  return n;
}

std::optional<double> Effects::truth_of(const std::string& name, const cid::Scene& scene) const {
  for (const auto& [effect, inj] : injected) {
    const TruthValues t = inj->truth();
    if (const auto it = t.find(name); it != t.end()) return it->second;
  }
  for (const auto& u : scene.uncertainties)
    if (u.name == name) {
      const auto it = geometric.find(name);
      return it != geometric.end() ? it->second : u.design_value;
    }
  return std::nullopt;
}

void draw_effect(const std::string& name, unsigned seed, const cid::Scene& scene, Effects& e) {
  e.injected[name] = injectable_effect(name).draw(seed, scene);
}

void inject_effect(const std::string& name, const TruthValues& values, Effects& e) {
  e.injected[name] = injectable_effect(name).inject(values);
}

std::vector<std::string> injectable_contact_effects() {
  std::vector<std::string> out;
  for (const Effect* x : registered_effects())
    if (x->contact() && x->contact()->injectable()) out.push_back(x->name());
  return out;
}

std::vector<TruthField> truth_file_fields(const Effects& e) {
  std::vector<TruthField> out;
  for (const Effect* x : registered_effects()) {
    if (!x->contact() || !x->contact()->injectable()) continue;
    const auto it = e.injected.find(x->name());
    const auto inj = it != e.injected.end() ? it->second : x->contact()->inject({});
    for (auto& f : inj->file_fields()) out.push_back(std::move(f));
  }
  return out;
}

std::vector<cid::SimulatedSample> simulate_with_effects(const cid::Scene& s, const cid::ContactModel& m, const Effects& e,
                                                        const std::vector<double>& t_s, const std::vector<cid::Kinematics>& truth,
                                                        const cid::SensorModel& sensor) {
  m.check();
  if (t_s.size() != truth.size()) throw std::invalid_argument("simulate_with_effects: times and kinematics differ in length");
  SimulationChannels ch;
  ch.x = s.design();
  set_uncertainties(s, e.geometric, ch.x);
  const std::vector<const Injection*> effects = in_layout_order(e);
  for (const Injection* inj : effects) inj->channels(s, ch);
  const Eigen::VectorXd& x = ch.x;
  cid::MindistWorkspace ws;
  std::vector<cid::ContactPoint> cs;
  const std::size_t n = truth.size();
  std::vector<Vector6d> w(n);
  std::vector<int> count(n);
  auto wrench = [&](const cid::Kinematics& k) {
    cid::mindist(s, k, x, m.v_tm, cs, ws);
    Vector6d out = Vector6d::Zero();
    for (const auto& c : cs) {
      ContactForce cf;
      cf.delta_m = c.delta;
      const SimulatedContact at{s, k, c};
      for (const Injection* inj : effects) inj->contact_force(at, cf);
      const double elastic_n = m.K * cf.delta_m;
      if (elastic_n + cf.normal_n <= 0.0) continue;  // lift-off: a contact pushes, it never pulls
      const double friction_n = m.mu * (elastic_n + cf.friction_normal_n);
      const Vec3 f = (elastic_n + cf.normal_n) * c.normal + (friction_n + cf.tangential_n) * c.tangent;
      out += plate_wrench_of(s.T_world_fp, f, c.point);
    }
    return out;
  };
  for (std::size_t k = 0; k < n; ++k) {
    cid::Kinematics kin = truth[k];
    w[k] = wrench(kin);
    if (!ch.compliance.isZero()) {
      // The deflected pose and its load agree: fixed point T = T_cmd Exp(C w_ee(T)).
      for (int it = 0; it < 50; ++it) {
        const Vector6d w_ee = cid::plate_to_object1(w[k], s.T_world_fp, kin.T_world_ee);
        const Eigen::Isometry3d T = deflect(truth[k].T_world_ee, ch.compliance * w_ee);
        const double change = (T.matrix() - kin.T_world_ee.matrix()).norm();
        kin.T_world_ee = T;
        w[k] = wrench(kin);
        if (change < 1e-13) break;
      }
    }
    count[k] = static_cast<int>(cs.size());
  }
  std::mt19937_64 rng(sensor.seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<cid::SimulatedSample> out(n);
  for (std::size_t k = 0; k < n; ++k) {
    auto& smp = out[k];
    smp.contacts = count[k];
    Vector6d wt = w[k];
    if (ch.delay_s != 0)
      interpolate(t_s, t_s[k] - ch.delay_s, [&](std::size_t j0, std::size_t j1, double a) { wt = (1 - a) * w[j0] + a * w[j1]; });
    for (const Injection* inj : effects) inj->sensor(wt);
    smp.w_fp_true = wt;
    smp.kin = truth[k];
    for (int i = 0; i < 3; ++i) {
      smp.kin.T_world_ee.translation()[i] = quantise(truth[k].T_world_ee.translation()[i], sensor.position_resolution_m);
      smp.kin.v_world_ee[i] = quantise(truth[k].v_world_ee[i], sensor.velocity_resolution_m_per_s);
    }
    for (int i = 0; i < 6; ++i) {
      const bool force = i < 3;
      const double noise = force ? sensor.force_noise_n : sensor.moment_noise_nm;
      const double step = force ? sensor.force_resolution_n : sensor.moment_resolution_nm;
      smp.w_fp[i] = quantise(wt[i] + noise * g(rng), step);
    }
  }
  return out;
}

}  // namespace hil::diagnose
