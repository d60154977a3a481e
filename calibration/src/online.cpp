#include <hil/calibration/online.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace hil::calibration {

OnlineIdentifier::OnlineIdentifier(VjmModel model, ParameterSet free, ParameterSet fixed, Eigen::VectorXd fixed_values, NoiseModel noise,
                                   PipelineOptions options, bool reduce)
    : model_(std::move(model)), fixed_values_(std::move(fixed_values)), noise_(noise), options_(std::move(options)), reduce_(reduce) {
  if (fixed_values_.size() != static_cast<Eigen::Index>(fixed.size())) throw std::invalid_argument("online: one value per fixed parameter");
  if (reduce_ && !fixed.empty()) throw std::invalid_argument("online: reduction runs on free parameters only");
  n_free_ = free.size();
  params_ = std::move(free);
  params_.insert(params_.end(), fixed.begin(), fixed.end());
  const auto n = static_cast<Eigen::Index>(params_.size());
  if (n == 0) throw std::invalid_argument("online: no parameters");
  sys_.R = Eigen::MatrixXd::Zero(n, n);
  sys_.z = Eigen::VectorXd::Zero(n);
  for (auto& s : axis_sys_) {
    s.R = Eigen::MatrixXd::Zero(n, n);
    s.z = Eigen::VectorXd::Zero(n);
  }
  for (std::size_t a = 0; a < 6; ++a) axis_sigma_[a] = a < 3 ? noise_.position_m : noise_.rotation_rad;
  A6_.resize(6, n);
  row_.resize(n);
}

void OnlineIdentifier::rotate_in(Eigen::MatrixXd& R, Eigen::VectorXd& z, double& rss, const Eigen::Ref<const Eigen::RowVectorXd>& a,
                                 double b) {
  row_ = a;
  const Eigen::Index n = R.cols();
  for (Eigen::Index j = 0; j < n; ++j) {
    const double x = row_[j];
    if (x == 0.0) continue;
    const double d = R(j, j);
    const double h = std::hypot(d, x);
    const double c = d / h, s = x / h;
    R(j, j) = h;
    row_[j] = 0.0;
    for (Eigen::Index k = j + 1; k < n; ++k) {
      const double rk = R(j, k), ak = row_[k];
      R(j, k) = c * rk + s * ak;
      row_[k] = -s * rk + c * ak;
    }
    const double zj = z[j];
    z[j] = c * zj + s * b;
    b = -s * zj + c * b;
  }
  rss += b * b;
}

void OnlineIdentifier::add(const Measurement& m) {
  if (m.q_rad.size() != model_.dof()) throw std::invalid_argument("online: wrong number of joint values");
  const int rows = measurement_rows(m);
  if (rows == 0 || m.displacement.size() != rows) throw std::invalid_argument("online: measured values do not match the measurement kind");
  model_.jacobians(m.q_rad, ws_);
  tool_observation(model_, params_, ws_, m.w_world, A6_);
  const Eigen::MatrixXd S = projection(m, ws_.poses.T_world_ee);
  A_.resize(rows, A6_.cols());
  A_.noalias() = S * A6_;
  axes_.clear();
  row_axes(m, axes_);
  for (int r = 0; r < rows; ++r) {
    const auto axis = static_cast<std::size_t>(axes_[static_cast<std::size_t>(r)]);
    const double sigma = axis_sigma_[axis];
    if (!(sigma > 0.0)) throw std::invalid_argument("online: noise of the measured quantity must be > 0");
    const double b = m.displacement[r] / sigma;
    A_.row(r) /= sigma;
    rotate_in(sys_.R, sys_.z, sys_.rss_outside, A_.row(r), b);
    rotate_in(axis_sys_[axis].R, axis_sys_[axis].z, axis_sys_[axis].rss_outside, A_.row(r), b);
    ++axis_sys_[axis].rows;
  }
  rows_ += rows;
  sys_.rows = rows_;
  ++measurements_;
  if (std::find(configs_.begin(), configs_.end(), m.config) == configs_.end()) configs_.push_back(m.config);
}

PipelineOptions OnlineIdentifier::effective_options() const {
  // R is the product of rows_ Givens updates, and its backward error grows with them (Higham,
  // Accuracy and Stability of Numerical Algorithms, 2nd ed., §19.6: γ of the row count): the bound
  // on an exactly dependent column's part outside the others' span climbed from 1e-13 to 5e-10 of
  // the largest in 40 minutes of 1 kHz measurements (docs/calibration.md, "The rank tolerance over
  // long streams"). A singular value below rows·ε of the largest cannot be told from zero, so the
  // rank tolerance is never below it.
  PipelineOptions o = options_;
  o.algebraic.rank.tolerance = std::max(o.algebraic.rank.tolerance, std::numeric_limits<double>::epsilon() * static_cast<double>(rows_));
  return o;
}

OnlineEstimate OnlineIdentifier::estimate() const {
  const PipelineOptions options = effective_options();
  OnlineEstimate out;
  out.measurements = measurements_;
  out.configurations = configs_.size();
  std::vector<int> free_cols, fixed_cols;
  std::vector<double> fixed_vals;
  std::vector<std::string> steps;
  LsqSolution s;
  if (reduce_) {
    std::vector<int> cols(n_free_);
    std::iota(cols.begin(), cols.end(), 0);
    AlgebraicResult a;
    if (reuse_ && have_reduction_ && reverify_algebraic(model_, sys_, params_, cols, options, reduction_, a)) {
      ++stats_.verified;
    } else {
      a = reduce_algebraic(model_, sys_, params_, cols, options);
      ++stats_.full;
    }
    if (reuse_) {
      reduction_ = a;
      have_reduction_ = true;
    }
    free_cols = a.free_cols;
    fixed_cols = a.fixed_cols;
    fixed_vals = a.fixed_values;
    steps = a.fixed_steps;
    s = std::move(a.solution);
  } else {
    free_cols.resize(n_free_);
    std::iota(free_cols.begin(), free_cols.end(), 0);
    for (std::size_t i = n_free_; i < params_.size(); ++i) {
      fixed_cols.push_back(static_cast<int>(i));
      fixed_vals.push_back(fixed_values_[static_cast<Eigen::Index>(i - n_free_)]);
      steps.emplace_back("given");
    }
    s = solve(sys_, free_cols, fixed_cols,
              Eigen::Map<const Eigen::VectorXd>(fixed_vals.data(), static_cast<Eigen::Index>(fixed_vals.size())), options.algebraic.rank);
  }
  out.rank = s.rank;
  out.full_rank = s.full_rank;
  Eigen::VectorXd all = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(params_.size()));
  for (std::size_t i = 0; i < free_cols.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    KeptParameter kp;
    kp.parameter = params_[static_cast<std::size_t>(free_cols[i])];
    kp.value = s.value.size() ? s.value[k] : 0.0;
    kp.std_dev = s.std_dev.size() ? s.std_dev[k] : std::numeric_limits<double>::quiet_NaN();
    kp.ci95_low = kp.value - 1.959963984540054 * kp.std_dev;
    kp.ci95_high = kp.value + 1.959963984540054 * kp.std_dev;
    kp.pnr = std::abs(kp.value) / kp.std_dev;
    kp.cls = classify(kp.pnr, options_.pnr);
    out.kept.push_back(kp);
    all[free_cols[i]] = kp.value;
  }
  for (std::size_t i = 0; i < fixed_cols.size(); ++i) {
    out.fixed.push_back({params_[static_cast<std::size_t>(fixed_cols[i])], fixed_vals[i], steps[i]});
    all[fixed_cols[i]] = fixed_vals[i];
  }
  for (std::size_t a = 0; a < 6; ++a) {
    const CompressedSystem& c = axis_sys_[a];
    if (c.rows == 0) {
      out.residual_rms[a] = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    const double rss_w = c.rss_outside + (c.R * all - c.z).squaredNorm();
    out.residual_rms[a] = axis_sigma_[a] * std::sqrt(rss_w / static_cast<double>(c.rows));
  }
  return out;
}

}  // namespace hil::calibration
