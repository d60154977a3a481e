// GCC 12 reports a false -Wmaybe-uninitialized inside Eigen's triangular matrix-vector product
// (instantiated by the Householder QR below); Eigen 3.4 + GCC 12 known issue.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include "hil/contact_id/identification.hpp"
#include "hil/so3/so3.hpp"

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

namespace hil::contact_id {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Residual variance of the force rows and of the moment rows (rows come as 3 force + 3 moment
/// per sample); `p` parameters were fitted. The paper's W_Y equalises the relative errors but is
/// not the noise covariance, so one pooled variance would misstate the intervals.
Eigen::VectorXd row_variances(const Eigen::VectorXd& e, int p) {
  const Eigen::Index n = e.size();
  double sf = 0.0, sm = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) (i % 6 < 3 ? sf : sm) += e[i] * e[i];
  const double dof = std::max(1.0, static_cast<double>(n - p)) / static_cast<double>(n);
  const double half = static_cast<double>(n) / 2.0;
  const double vf = sf / (half * dof), vm = sm / (half * dof);
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = i % 6 < 3 ? vf : vm;
  return v;
}

std::string num(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// ContactProblem

ContactProblem::ContactProblem(Scene scene, std::vector<Measurement> data, const ProblemOptions& options)
    : scene_(std::move(scene)), data_(std::move(data)), opt_(options) {
  if (!(opt_.v_tm >= 0.0) || !std::isfinite(opt_.v_tm)) throw std::invalid_argument("sticking threshold must be >= 0");
  if (!(opt_.force_scale_n >= 0.0) || !(opt_.moment_scale_nm >= 0.0))
    throw std::invalid_argument("force and moment scales must be >= 0 (0 = from data)");
  for (std::size_t k = 0; k < data_.size(); ++k) {
    const auto& d = data_[k];
    const bool ok = std::isfinite(d.t_s) && d.kin.T_world_ee.matrix().allFinite() && d.kin.v_world_ee.allFinite() &&
                    d.kin.w_world_ee.allFinite() && d.w_fp.allFinite();
    if (!ok) throw std::invalid_argument("sample " + std::to_string(k) + " (t = " + num(d.t_s) + " s) has non-finite values");
  }
  const auto M = scene_.uncertainties.size();
  const Eigen::VectorXd xd = scene_.design();
  for (int b = 0; b < 2; ++b) index_[static_cast<std::size_t>(b)] = scene_.polyhedron_index(b);
  std::vector<std::vector<bool>> uncertain(2);
  for (int b = 0; b < 2; ++b) uncertain[static_cast<std::size_t>(b)].assign(scene_.bodies[static_cast<std::size_t>(b)].features.size(), false);
  for (const auto& u : scene_.uncertainties) uncertain[static_cast<std::size_t>(u.body)][static_cast<std::size_t>(u.feature)] = true;
  touched_.assign(M, false);

  // Feature transforms at x_u^d (the same for every sample); the polyhedra of a body that does not
  // move with the end effector (object 2, normally) are posed once, the others once per sample.
  for (int b = 0; b < 2; ++b) {
    const auto& body = scene_.bodies[static_cast<std::size_t>(b)];
    fixed_body_[static_cast<std::size_t>(b)] = !body.on_end_effector;
    Tf_[static_cast<std::size_t>(b)].resize(body.features.size());
    disp_[static_cast<std::size_t>(b)].assign(body.features.size(), 0.0);
    for (std::size_t f = 0; f < body.features.size(); ++f)
      Tf_[static_cast<std::size_t>(b)][f] = feature_transform(scene_.uncertainties, xd, b, static_cast<int>(f));
    posed_[static_cast<std::size_t>(b)].resize(index_[static_cast<std::size_t>(b)].size());
  }
  reach_.assign(M, 0.0);
  for (std::size_t u = 0; u < M; ++u) {
    // How far a vertex of the feature can move per unit |x_u - x_u^d|: 1 for a translation; for a
    // rotation, the largest distance from the axis of a vertex placed by the uncertainties listed
    // before it (at their design values; the chord is at most the arc).
    const auto& U = scene_.uncertainties[u];
    if (U.kind == Uncertainty::Kind::translation) {
      reach_[u] = 1.0;
      continue;
    }
    Eigen::Isometry3d Tprev = Eigen::Isometry3d::Identity();
    for (std::size_t v = 0; v < u; ++v) {
      const auto& V = scene_.uncertainties[v];
      if (V.body == U.body && V.feature == U.feature) Tprev = uncertainty_transform(V, xd[static_cast<Eigen::Index>(v)]) * Tprev;
    }
    const auto& feat = scene_.bodies[static_cast<std::size_t>(U.body)].features[static_cast<std::size_t>(U.feature)];
    for (const auto& poly : feat.polyhedra)
      for (const auto& v : poly.vertices()) {
        const Vec3 d = Tprev * v - U.point;
        reach_[u] = std::max(reach_[u], (d - U.axis * U.axis.dot(d)).norm());
      }
    reach_[u] *= 1.0 + 1e-9;
  }
  for (int j = 0; j < static_cast<int>(M); ++j)
    if (scene_.uncertainties[static_cast<std::size_t>(j)].kind == Uncertainty::Kind::rotation)
      max_turn_rad_ = std::max(max_turn_rad_, fd_step(j) * (1.0 + 1e-6));  // room for rounding
  for (int b = 0; b < 2; ++b)
    if (fixed_body_[static_cast<std::size_t>(b)]) pose_body(b, scene_.bodies[static_cast<std::size_t>(b)].T_attach, posed_[static_cast<std::size_t>(b)]);

  ClipWorkspace clip;
  std::vector<VarPair> pending;
  std::vector<Regressor> var_rows, design_rows;
  var_.reserve(4 * data_.size());
  for (std::size_t k = 0; k < data_.size(); ++k) {
    const auto& kin = data_[k].kin;
    std::array<Eigen::Isometry3d, 2> Tb;
    for (int b = 0; b < 2; ++b) {
      Tb[static_cast<std::size_t>(b)] = body_pose(scene_.bodies[static_cast<std::size_t>(b)], kin.T_world_ee);
      if (!fixed_body_[static_cast<std::size_t>(b)]) pose_body(b, Tb[static_cast<std::size_t>(b)], posed_[static_cast<std::size_t>(b)]);
    }
    const auto& A = posed_[0];
    const auto& B = posed_[1];
    Regressor fixed = Regressor::Zero();
    int fixed_n = 0, var_n = 0;
    pending.clear();
    var_rows.clear();
    const int a = static_cast<int>(used_.size());
    for (std::size_t i = 0; i < A.size(); ++i)
      for (std::size_t j = 0; j < B.size(); ++j) {
        const int f1 = index_[0][i].first, f2 = index_[1][j].first;
        const bool var = uncertain[0][static_cast<std::size_t>(f1)] || uncertain[1][static_cast<std::size_t>(f2)];
        if (!near(A[i], B[j], var ? opt_.broad_margin_m : 0.0)) continue;
        if (var) {
          // Keep the pair if it interferes now, or could within the margin.
          PairContact pc;
          VarPair vp{a, static_cast<int>(i), static_cast<int>(j), f1, f2, -std::numeric_limits<double>::infinity()};
          // One separating-axis pass: the contact, or the gap with an early exit once the pair is
          // known to be farther apart than the margin. A kept pair gets the full bound (used to skip
          // it while x_u cannot close the gap).
          double gap = 0.0;
          if (penetration_or_gap(A[i], B[j], opt_.broad_margin_m, pc, gap, clip)) {
            ContactPoint c{pc.delta, pc.point, pc.normal, Vec3::Zero(), 0.0, vp.p1, vp.p2};
            tangent(scene_, kin, opt_.v_tm, c);
            var_rows.push_back(regressor_row(c, Tb[0]));
            ++var_n;
          } else {
            if (gap > opt_.broad_margin_m) continue;
            vp.gap = gap;
          }
          pending.push_back(vp);
          continue;
        }
        PairContact pc;
        if (!penetration(A[i], B[j], pc, clip)) continue;
        ContactPoint c{pc.delta, pc.point, pc.normal, Vec3::Zero(), 0.0, static_cast<int>(i), static_cast<int>(j)};
        tangent(scene_, kin, opt_.v_tm, c);
        fixed += regressor_row(c, Tb[0]);
        ++fixed_n;
      }
    // Feature-touch bookkeeping uses all candidate pairs of all samples.
    for (const auto& vp : pending)
      for (std::size_t u = 0; u < M; ++u) {
        const auto& U = scene_.uncertainties[u];
        if ((U.body == 0 && U.feature == vp.f1) || (U.body == 1 && U.feature == vp.f2)) touched_[u] = true;
      }
    if (fixed_n + var_n == 0) continue;
    used_.push_back(static_cast<int>(k));
    fixed_.push_back(fixed);
    fixed_contacts_.push_back(fixed_n);
    var_.insert(var_.end(), pending.begin(), pending.end());
    // Φ at the design geometry: the fixed pairs, then the contacts of the pairs x_u may move.
    Regressor design = fixed;
    for (const auto& r : var_rows) design += r;
    design_rows.push_back(design);
    contacts_design_.push_back(fixed_n + var_n);
    T_o1_.push_back(Tb[0]);
    if (!fixed_body_[1]) T_o2_.push_back(Tb[1]);  // a fixed body's pose is T_attach for every sample
    y_o1_.push_back(plate_to_object1(data_[k].w_fp, scene_.T_world_fp, Tb[0]));
  }
  if (used_.empty())
    throw std::runtime_error("no sample of the run brings the objects into contact (" + std::to_string(data_.size()) +
                             " samples checked): nothing to identify");
  // touched_ must only count features that are actually close to contact somewhere; refine: a
  // feature is touched if some pair of it is within the margin in some sample (done above).
  double fmax = 0.0, mmax = 0.0;
  for (const auto& y : y_o1_) {
    fmax = std::max(fmax, y.head<3>().cwiseAbs().maxCoeff());
    mmax = std::max(mmax, y.tail<3>().cwiseAbs().maxCoeff());
  }
  f_scale_ = opt_.force_scale_n > 0.0 ? opt_.force_scale_n : (fmax > 0.0 ? fmax : 1.0);
  m_scale_ = opt_.moment_scale_nm > 0.0 ? opt_.moment_scale_nm : (mmax > 0.0 ? mmax : 1.0);
  const Eigen::Index L = static_cast<Eigen::Index>(used_.size());
  y_.resize(6 * L);
  w_.resize(6 * L);
  for (Eigen::Index a = 0; a < L; ++a) {
    for (int r = 0; r < 6; ++r) w_[6 * a + r] = r < 3 ? 1.0 / f_scale_ : 1.0 / m_scale_;
    y_.segment<6>(6 * a) = w_.segment<6>(6 * a).cwiseProduct(y_o1_[static_cast<std::size_t>(a)]);
  }
  // Φ at the design geometry from the pair contributions computed above (no second mindist pass).
  A_design_.resize(6 * L, 2);
  for (Eigen::Index a = 0; a < L; ++a) A_design_.block<6, 2>(6 * a, 0) = design_rows[static_cast<std::size_t>(a)];
  A_design_.array().colwise() *= w_.array();
}

double ContactProblem::fd_step(int j) const {
  const auto& u = scene_.uncertainties[static_cast<std::size_t>(j)];
  if (u.prior_std > 0.0) return 1e-3 * u.prior_std;
  return u.kind == Uncertainty::Kind::translation ? 1e-7 : 1e-6;
}

void ContactProblem::pose_body(int b, const Eigen::Isometry3d& T_world_body, std::vector<PosedPolyhedron>& out) const {
  const auto& body = scene_.bodies[static_cast<std::size_t>(b)];
  const auto& index = index_[static_cast<std::size_t>(b)];
  out.resize(index.size());
  for (std::size_t q = 0; q < index.size(); ++q) {
    const auto [f, k] = index[q];
    out[q].pose(body.features[static_cast<std::size_t>(f)].polyhedra[static_cast<std::size_t>(k)],
                T_world_body * Tf_[static_cast<std::size_t>(b)][static_cast<std::size_t>(f)]);
  }
}

void ContactProblem::prepare(const Eigen::VectorXd& x) const {
  const auto& us = scene_.uncertainties;
  for (int b = 0; b < 2; ++b) {
    const auto& body = scene_.bodies[static_cast<std::size_t>(b)];
    for (std::size_t f = 0; f < body.features.size(); ++f) {
      Tf_[static_cast<std::size_t>(b)][f] = feature_transform(us, x, b, static_cast<int>(f));
      disp_[static_cast<std::size_t>(b)][f] = 0.0;
    }
  }
  for (std::size_t u = 0; u < us.size(); ++u)
    disp_[static_cast<std::size_t>(us[u].body)][static_cast<std::size_t>(us[u].feature)] +=
        reach_[u] * std::abs(x[static_cast<Eigen::Index>(u)] - us[u].design_value);
  for (int b = 0; b < 2; ++b)
    if (fixed_body_[static_cast<std::size_t>(b)]) pose_body(b, scene_.bodies[static_cast<std::size_t>(b)].T_attach, posed_[static_cast<std::size_t>(b)]);
}

const PosedPolyhedron& ContactProblem::posed(int b, int q, int a, const Eigen::Isometry3d& Tf, PosedPolyhedron& scratch) const {
  const auto [f, k] = index_[static_cast<std::size_t>(b)][static_cast<std::size_t>(q)];
  const auto& T = (b == 0 ? T_o1_ : T_o2_)[static_cast<std::size_t>(a)];
  scratch.pose(scene_.bodies[static_cast<std::size_t>(b)].features[static_cast<std::size_t>(f)].polyhedra[static_cast<std::size_t>(k)], T * Tf);
  return scratch;
}

bool ContactProblem::out_of_reach(const VarPair& vp, double d1, double d2) const {
  // The pair was at least vp.gap apart under x_u^d; its polyhedra moved by at most d1 and d2 since.
  return vp.gap > (d1 + d2) * (1.0 + 1e-9) + 1e-12;
}

Regressor ContactProblem::pair_rows(const VarPair& vp, const PairContact& pc) const {
  ContactPoint c{pc.delta, pc.point, pc.normal, Vec3::Zero(), 0.0, vp.p1, vp.p2};
  tangent(scene_, data_[static_cast<std::size_t>(used_[static_cast<std::size_t>(vp.a)])].kin, opt_.v_tm, c);
  return regressor_row(c, T_o1_[static_cast<std::size_t>(vp.a)]);
}

Regressor ContactProblem::pair_contact(const VarPair& vp, const PosedPolyhedron& A, const PosedPolyhedron& B, int* in_contact) const {
  PairContact pc;
  if (!near(A, B) || !penetration(A, B, pc, clip_)) return Regressor::Zero();
  if (in_contact) ++*in_contact;
  return pair_rows(vp, pc);
}

void ContactProblem::regressor(const Eigen::VectorXd& x, Eigen::MatrixX2d& A, std::vector<int>* contacts) const {
  const Eigen::Index L = static_cast<Eigen::Index>(used_.size());
  if (A_design_.rows() == 6 * L && &A != &A_design_ && x == scene_.design()) {
    A = A_design_;
    if (contacts) *contacts = contacts_design_;
    return;
  }
  A.resize(6 * L, 2);
  for (Eigen::Index a = 0; a < L; ++a) A.block<6, 2>(6 * a, 0) = fixed_[static_cast<std::size_t>(a)];
  if (contacts) contacts->assign(fixed_contacts_.begin(), fixed_contacts_.end());
  prepare(x);
  base_x_.resize(0);  // invalid while being filled
  base_sat_.resize(var_.size());
  for (std::size_t i = 0; i < var_.size(); ++i) {
    const auto& vp = var_[i];
    base_sat_[i] = SatRecord{};
    const double d1 = disp_[0][static_cast<std::size_t>(vp.f1)], d2 = disp_[1][static_cast<std::size_t>(vp.f2)];
    if (out_of_reach(vp, d1, d2)) {
      base_sat_[i].gap = vp.gap - (d1 + d2) * (1.0 + 1e-9) - 1e-12;  // > 0: a lower bound on their distance at x
      continue;
    }
    const auto& P1 = fixed_body_[0] ? posed_[0][static_cast<std::size_t>(vp.p1)] : posed(0, vp.p1, vp.a, Tf_[0][static_cast<std::size_t>(vp.f1)], pa_);
    const auto& P2 = fixed_body_[1] ? posed_[1][static_cast<std::size_t>(vp.p2)] : posed(1, vp.p2, vp.a, Tf_[1][static_cast<std::size_t>(vp.f2)], pb_);
    PairContact pc;
    if (!penetration_recorded(P1, P2, max_turn_rad_, pc, base_sat_[i], clip_)) continue;
    A.block<6, 2>(6 * vp.a, 0) += pair_rows(vp, pc);
    if (contacts) ++(*contacts)[static_cast<std::size_t>(vp.a)];
  }
  base_x_ = x;
  A.array().colwise() *= w_.array();
}

void ContactProblem::sensitivity(const Eigen::VectorXd& x, int j, double h, Eigen::MatrixX2d& dA) const {
  const Eigen::Index L = static_cast<Eigen::Index>(used_.size());
  dA.setZero(6 * L, 2);
  const auto& U = scene_.uncertainties[static_cast<std::size_t>(j)];
  const auto mb = static_cast<std::size_t>(U.body), ob = 1 - mb;  // moved body, other body
  // If the last regressor() call was at x (as in a solver's Jacobian after its residual), its
  // separating-axis records spare the axis search at x ± h.
  const bool cached = base_x_.size() == x.size() && base_x_ == x;
  Eigen::VectorXd xp = x, xm = x;
  xp[j] += h;
  xm[j] -= h;
  prepare(x);  // the other body's features stay at x
  const Eigen::Isometry3d Tp = feature_transform(scene_.uncertainties, xp, U.body, U.feature);
  const Eigen::Isometry3d Tm = feature_transform(scene_.uncertainties, xm, U.body, U.feature);
  // Displacement bound of the moved feature at x ± h.
  const double dmoved = disp_[mb][static_cast<std::size_t>(U.feature)] + reach_[static_cast<std::size_t>(j)] * std::abs(h);
  if (fixed_body_[mb]) {
    const auto& index = index_[mb];
    const auto& feat = scene_.bodies[mb].features[static_cast<std::size_t>(U.feature)];
    const auto& Tb = scene_.bodies[mb].T_attach;
    plus_.resize(index.size());
    minus_.resize(index.size());
    for (std::size_t q = 0; q < index.size(); ++q)
      if (index[q].first == U.feature) {
        plus_[q].pose(feat.polyhedra[static_cast<std::size_t>(index[q].second)], Tb * Tp);
        minus_[q].pose(feat.polyhedra[static_cast<std::size_t>(index[q].second)], Tb * Tm);
      }
  }
  // How far x ± h moves the feature from x: the largest vertex displacement and the turn.
  const auto& Tx = Tf_[mb][static_cast<std::size_t>(U.feature)];
  auto motion = [&](const Eigen::Isometry3d& T, double& moved_m, double& turn_rad) {
    moved_m = 0.0;
    for (const auto& poly : scene_.bodies[mb].features[static_cast<std::size_t>(U.feature)].polyhedra)
      for (const auto& v : poly.vertices()) moved_m = std::max(moved_m, (T * v - Tx * v).norm());
    moved_m = moved_m * (1.0 + 1e-9) + 1e-15;  // rounding
    // (exactly 0 for a translation: acos near 1 would turn rounding into ~1e-8 rad)
    turn_rad = T.linear() == Tx.linear() ? 0.0 : so3::angle(T.linear() * Tx.linear().transpose()) * (1.0 + 1e-9);
  };
  double moved_p, turn_p, moved_m, turn_m;
  motion(Tp, moved_p, turn_p);
  motion(Tm, moved_m, turn_m);
  for (std::size_t i = 0; i < var_.size(); ++i) {
    const auto& vp = var_[i];
    const int f_moved = mb == 0 ? vp.f1 : vp.f2, f_other = mb == 0 ? vp.f2 : vp.f1;
    if (f_moved != U.feature) continue;
    if (out_of_reach(vp, dmoved, disp_[ob][static_cast<std::size_t>(f_other)])) continue;
    const int q_moved = mb == 0 ? vp.p1 : vp.p2, q_other = mb == 0 ? vp.p2 : vp.p1;
    const auto& O = fixed_body_[ob] ? posed_[ob][static_cast<std::size_t>(q_other)]
                                    : posed(static_cast<int>(ob), q_other, vp.a, Tf_[ob][static_cast<std::size_t>(f_other)], pb_);
    const auto at = [&](const std::vector<PosedPolyhedron>& fixed_posed, const Eigen::Isometry3d& T, double moved,
                        double turn) -> Regressor {
      const auto& P = fixed_body_[mb] ? fixed_posed[static_cast<std::size_t>(q_moved)] : posed(static_cast<int>(mb), q_moved, vp.a, T, pa_);
      const auto& A1 = mb == 0 ? P : O;
      const auto& A2 = mb == 0 ? O : P;
      if (!cached) return pair_contact(vp, A1, A2, nullptr);
      PairContact pc;
      if (!penetration_after_motion(A1, A2, base_sat_[i], moved, turn, pc, clip_)) return Regressor::Zero();
      return pair_rows(vp, pc);
    };
    dA.block<6, 2>(6 * vp.a, 0) += (at(plus_, Tp, moved_p, turn_p) - at(minus_, Tm, moved_m, turn_m)) / (2.0 * h);
  }
  dA.array().colwise() *= w_.array();
}

// ---------------------------------------------------------------------------------------------
// Linear estimate

LinearEstimate solve_theta(const Eigen::MatrixX2d& A, const Eigen::VectorXd& b) {
  LinearEstimate e;
  e.rows = A.rows();
  const double n0 = A.col(0).norm(), n1 = A.col(1).norm();
  if (!(n0 > 0.0)) throw std::runtime_error("the regressor is zero: no interference in the samples used");
  if (n1 <= 1e-12 * n0) {
    // All contacts stick: only K is identifiable.
    const double K = A.col(0).dot(b) / (n0 * n0);
    e.theta = {K, kNaN};
    e.rank = 1;
    e.condition = std::numeric_limits<double>::infinity();
    const Eigen::VectorXd r = b - A.col(0) * K;
    const double dof = std::max<double>(1.0, static_cast<double>(A.rows()) - 1.0);
    e.sigma2 = r.squaredNorm() / dof;
    e.cov.setZero();
    e.cov(0, 0) = A.col(0).cwiseAbs2().dot(row_variances(r, 1)) / (n0 * n0 * n0 * n0);
    e.cov(1, 1) = kNaN;
    e.K = K;
    e.K_std = std::sqrt(e.cov(0, 0));
    e.mu = kNaN;
    e.mu_std = kNaN;
    e.mu_identifiable = false;
    e.relative_force_error = std::sqrt(r.squaredNorm() / static_cast<double>(A.rows()));
    e.note = "rank-deficient regressor: every contact sticks (tangential speed below v_t,m) in the samples used, so "
             "the friction column of Φ is zero; only K is identifiable, μ is not";
    return e;
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& s = svd.singularValues();
  e.rank = s[1] > 1e-12 * s[0] ? 2 : 1;
  e.condition = e.rank == 2 ? s[0] / s[1] : std::numeric_limits<double>::infinity();
  svd.setThreshold(1e-12);
  e.theta = svd.solve(b);
  const Eigen::VectorXd r = b - A * e.theta;
  const double dof = std::max<double>(1.0, static_cast<double>(A.rows()) - 2.0);
  e.sigma2 = r.squaredNorm() / dof;
  e.relative_force_error = std::sqrt(r.squaredNorm() / static_cast<double>(A.rows()));
  if (e.rank == 2) {
    // cov = A^+ diag(σ_row²) A^+T with A^+ = V S^-1 U^T (per-group residual variances).
    const Eigen::MatrixXd B = svd.matrixU() * s.cwiseInverse().asDiagonal() * svd.matrixV().transpose();
    e.cov = B.transpose() * row_variances(r, 2).asDiagonal() * B;
  } else {
    e.cov.setConstant(kNaN);
    e.note = "rank-deficient regressor: the stiffness and friction columns are collinear; θ is the minimum-norm solution";
  }
  e.K = e.theta[0];
  e.K_std = std::sqrt(e.cov(0, 0));
  e.mu_identifiable = e.rank == 2;
  e.mu = e.theta[1] / e.theta[0];
  const Eigen::Vector2d g(-e.theta[1] / (e.theta[0] * e.theta[0]), 1.0 / e.theta[0]);
  e.mu_std = std::sqrt(std::max(0.0, g.dot(e.cov * g)));
  if (!(e.K > 0.0)) e.note += (e.note.empty() ? "" : "; ") + std::string("the identified K is not positive: the data do not fit the contact model");
  return e;
}

void RunningLeastSquares::add(const Regressor& A, const Vector6d& b) {
  Eigen::Matrix<double, 8, 2> M;
  Eigen::Matrix<double, 8, 1> y;
  M << R_, A;
  y << z_, b;
  Eigen::HouseholderQR<Eigen::Matrix<double, 8, 2>> qr(M);
  const Eigen::Matrix<double, 8, 1> qy = qr.householderQ().transpose() * y;
  R_ = qr.matrixQR().topRows<2>().triangularView<Eigen::Upper>();
  z_ = qy.head<2>();
  rss_ += qy.tail<6>().squaredNorm();
  ++n_;
}

LinearEstimate RunningLeastSquares::estimate() const {
  LinearEstimate e;
  e.rows = static_cast<Eigen::Index>(6 * n_);
  if (n_ == 0 || !(std::abs(R_(0, 0)) > 0.0)) {
    e.note = "no contact yet";
    return e;
  }
  const double dof = std::max(1.0, static_cast<double>(e.rows) - 2.0);
  e.sigma2 = rss_ / dof;
  e.relative_force_error = std::sqrt(rss_ / static_cast<double>(e.rows));
  Eigen::JacobiSVD<Eigen::Matrix2d> svd(R_);
  const auto s = svd.singularValues();
  e.rank = s[1] > 1e-12 * s[0] ? 2 : 1;
  e.condition = e.rank == 2 ? s[0] / s[1] : std::numeric_limits<double>::infinity();
  if (e.rank == 2) {
    e.theta = R_.triangularView<Eigen::Upper>().solve(z_);
    const Eigen::Matrix2d Ri = R_.triangularView<Eigen::Upper>().solve(Eigen::Matrix2d::Identity());
    e.cov = e.sigma2 * Ri * Ri.transpose();
    e.mu_identifiable = true;
    e.K = e.theta[0];
    e.mu = e.theta[1] / e.theta[0];
    const Eigen::Vector2d g(-e.theta[1] / (e.theta[0] * e.theta[0]), 1.0 / e.theta[0]);
    e.mu_std = std::sqrt(std::max(0.0, g.dot(e.cov * g)));
  } else {
    // Only the stiffness column carries information (all contacts stuck so far).
    e.K = z_[0] / R_(0, 0);
    e.theta = {e.K, kNaN};
    e.cov.setConstant(kNaN);
    e.cov(0, 0) = e.sigma2 / (R_(0, 0) * R_(0, 0));
    e.mu = kNaN;
    e.mu_std = kNaN;
    e.note = "every contact has stuck so far: only K is identifiable";
  }
  e.K_std = std::sqrt(e.cov(0, 0));
  return e;
}

LinearEstimate global_estimate(const ContactProblem& p, const Eigen::VectorXd& x) {
  Eigen::MatrixX2d A;
  p.regressor(x, A);
  return solve_theta(A, p.y());
}

std::vector<InstantEstimate> instantaneous(const ContactProblem& p, const Eigen::VectorXd& x, int window) {
  Eigen::MatrixX2d A;
  std::vector<int> n;
  p.regressor(x, A, &n);
  const auto L = static_cast<Eigen::Index>(p.used().size());
  const Eigen::Index half = std::max(0, window - 1) / 2;
  std::vector<InstantEstimate> out(static_cast<std::size_t>(L));
  for (Eigen::Index a = 0; a < L; ++a) {
    auto& e = out[static_cast<std::size_t>(a)];
    e.t_s = p.data()[static_cast<std::size_t>(p.used()[static_cast<std::size_t>(a)])].t_s;
    e.contacts = n[static_cast<std::size_t>(a)];
    const Eigen::Index lo = std::max<Eigen::Index>(0, a - half), hi = std::min<Eigen::Index>(L - 1, a + half);
    const auto Ab = A.middleRows(6 * lo, 6 * (hi - lo + 1));
    const auto bb = p.y().segment(6 * lo, 6 * (hi - lo + 1));
    if (!(Ab.col(0).norm() > 0.0)) continue;
    const auto est = solve_theta(Ab, bb);
    e.valid = true;
    e.K = est.K;
    e.mu_valid = est.mu_identifiable;
    e.mu = est.mu_identifiable ? est.mu : kNaN;
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Variable projection

namespace {

struct Vp {
  const ContactProblem& p;
  double lambda;
  std::vector<int> idx;  ///< fitted uncertainty indices
  Eigen::VectorXd xd, sd;
  int evaluations = 0;
  int jacobians = 0;
  Eigen::MatrixX2d A;
  Eigen::MatrixX2d dA;

  Vp(const ContactProblem& pp, double lam, const std::vector<bool>& fitted) : p(pp), lambda(lam) {
    xd = p.scene().design();
    sd = p.scene().prior_std();
    for (int j = 0; j < p.uncertainties(); ++j) {
      const auto& u = p.scene().uncertainties[static_cast<std::size_t>(j)];
      if (!(sd[j] > 0.0)) sd[j] = u.kind == Uncertainty::Kind::translation ? 1e-4 : 1e-3;
      if (fitted[static_cast<std::size_t>(j)]) idx.push_back(j);
    }
  }
  int m() const { return static_cast<int>(idx.size()); }
  Eigen::VectorXd x_of(const Eigen::VectorXd& z) const {
    Eigen::VectorXd x = xd;
    for (int i = 0; i < m(); ++i) x[idx[static_cast<std::size_t>(i)]] += sd[idx[static_cast<std::size_t>(i)]] * z[i];
    return x;
  }
  /// Residual [r/sqrt(n); sqrt(λ/m) z]; fills the SVD of A if asked.
  double residual(const Eigen::VectorXd& z, Eigen::VectorXd& R, Eigen::Vector2d& theta, double* fc = nullptr,
                  double* gc = nullptr) {
    ++evaluations;
    p.regressor(x_of(z), A);
    const double n = static_cast<double>(A.rows());
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
    svd.setThreshold(1e-12);
    theta = svd.solve(p.y());
    R.resize(A.rows() + m());
    R.head(A.rows()) = (p.y() - A * theta) / std::sqrt(n);
    R.tail(m()) = std::sqrt(lambda / std::max(1, m())) * z;
    const double f = R.head(A.rows()).squaredNorm();
    const double g = z.squaredNorm() / std::max(1, m());
    if (fc) *fc = f;
    if (gc) *gc = g;
    return f + lambda * g;
  }
  /// Jacobian of the residual at z (after residual(z) filled A and theta).
  void jacobian(const Eigen::VectorXd& z, const Eigen::VectorXd& R, const Eigen::Vector2d& theta, VpJacobian kind,
                Eigen::MatrixXd& J) {
    ++jacobians;
    const Eigen::Index n = A.rows();
    const double sn = std::sqrt(static_cast<double>(n));
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::MatrixXd& U = svd.matrixU();
    const Eigen::Vector2d s = svd.singularValues();
    const Eigen::Matrix2d V = svd.matrixV();
    Eigen::Vector2d sinv;
    for (int i = 0; i < 2; ++i) sinv[i] = s[i] > 1e-12 * s[0] ? 1.0 / s[i] : 0.0;
    const Eigen::VectorXd r = R.head(n) * sn;
    const Eigen::VectorXd x = x_of(z);
    J.setZero(n + m(), m());
    for (int i = 0; i < m(); ++i) {
      const int j = idx[static_cast<std::size_t>(i)];
      p.sensitivity(x, j, p.fd_step(j), dA);
      Eigen::VectorXd g = dA * theta;
      g -= U * (U.transpose() * g);  // P⊥ dA θ
      if (kind == VpJacobian::golub_pereyra) {
        const Eigen::Vector2d t = V.transpose() * (dA.transpose() * r);
        g += U * sinv.cwiseProduct(t);  // (A^+)^T dA^T r
      }
      J.col(i).head(n) = -sd[j] * g / sn;
    }
    J.bottomRows(m()).diagonal().setConstant(std::sqrt(lambda / std::max(1, m())));
  }
};

}  // namespace

double projected_objective(const ContactProblem& p, const Eigen::VectorXd& x, double lambda, const std::vector<bool>& fitted,
                           double* force_cost, double* geometric_cost) {
  Vp vp(p, lambda, fitted);
  Eigen::VectorXd z(vp.m());
  for (int i = 0; i < vp.m(); ++i) {
    const int j = vp.idx[static_cast<std::size_t>(i)];
    z[i] = (x[j] - vp.xd[j]) / vp.sd[j];
  }
  Eigen::VectorXd R;
  Eigen::Vector2d th;
  return vp.residual(z, R, th, force_cost, geometric_cost);
}

GeometricEstimate identify_geometry(const ContactProblem& p, const GeometricOptions& o, const Eigen::VectorXd* x0) {
  if (!(o.lambda >= 0.0) || !std::isfinite(o.lambda)) throw std::invalid_argument("lambda must be finite and >= 0");
  const int M = p.uncertainties();
  std::vector<bool> fitted(static_cast<std::size_t>(M), false);
  for (int j = 0; j < M; ++j)
    fitted[static_cast<std::size_t>(j)] = (o.fit.empty() || o.fit[static_cast<std::size_t>(j)]) && p.touches(j);
  Vp vp(p, o.lambda, fitted);
  if (vp.m() == 0)
    throw std::runtime_error("no geometric uncertainty can be fitted: the features they move are never near a contact "
                             "in this run (unobservable)");
  const int m = vp.m();
  Eigen::VectorXd z = Eigen::VectorXd::Zero(m);
  if (x0)
    for (int i = 0; i < m; ++i) {
      const int j = vp.idx[static_cast<std::size_t>(i)];
      z[i] = ((*x0)[j] - vp.xd[j]) / vp.sd[j];
    }
  GeometricEstimate g;
  g.lambda = o.lambda;
  Eigen::VectorXd R;
  Eigen::Vector2d th;
  double f = vp.residual(z, R, th);

  if (o.solver == Solver::levenberg_marquardt) {
    // Levenberg-Marquardt in prior-std units (z), damping μ D with a per-parameter diagonal D.
    //
    // Where the max-depth δ has a kink (a face turning through parallel: the deepest vertex jumps
    // to the other end) the objective is V-shaped along that parameter and its minimum sits on the
    // kink. The Gauss-Newton model, built from the slope of one side, then overshoots across the
    // kink at every step; a single μ for all parameters makes every other parameter crawl with it
    // (the old behaviour: 200 iterations). A change of sign of ∂f/∂z_j between two accepted
    // iterates says the step went past the minimum along z_j, so z_j's own damping D_jj is raised
    // (x8, relaxed /2 while the sign holds): a parameter sitting on a kink converges to it
    // geometrically while the smooth ones keep Gauss-Newton steps.
    //
    // Stopping: besides the relative tolerance, progress is statistically meaningless once an
    // accepted step lowers the objective by less than statistical_tolerance × σ²/(6L), σ² ≈ the force
    // cost (a change of Δχ² = 6L Δf/σ² < statistical_tolerance), twice in a row.
    const double n_data = static_cast<double>(p.rows());
    Eigen::MatrixXd J;
    vp.jacobian(z, R, th, o.jacobian, J);
    Eigen::VectorXd grad = J.transpose() * R;
    const double jmax = J.colwise().squaredNorm().maxCoeff();
    const double mu0 = 1e-3 * (jmax > 0.0 ? jmax : 1.0);  // Madsen-Nielsen-Tingleff start and update
    double mu = mu0, nu = 2.0;
    Eigen::VectorXd D = Eigen::VectorXd::Ones(m);
    std::vector<double> history{f};
    int small_gains = 0;
    for (g.iterations = 0; g.iterations < o.max_iterations; ++g.iterations) {
      // Stall: five iterations together gained less than 100 x tolerance.
      if (history.size() > 5 && history[history.size() - 6] - f <= 100.0 * o.tolerance * f) {
        g.converged = true;
        break;
      }
      if (grad.lpNorm<Eigen::Infinity>() < 1e-14 * std::max(1.0, f)) {
        g.converged = true;
        break;
      }
      // J = Q [Rj; 0]: each damped trial solves a small (2m x m) problem.
      Eigen::HouseholderQR<Eigen::MatrixXd> qr(J);
      const Eigen::MatrixXd Rj = qr.matrixQR().topRows(m).triangularView<Eigen::Upper>();
      const Eigen::VectorXd c = -(qr.householderQ().transpose() * R).head(m);
      bool accepted = false;
      for (int tries = 0; tries < 30 && !accepted; ++tries) {
        Eigen::MatrixXd Aug(2 * m, m);
        Aug << Rj, Eigen::MatrixXd((mu * D).cwiseSqrt().asDiagonal());
        Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * m);
        rhs.head(m) = c;
        const Eigen::VectorXd step = Aug.colPivHouseholderQr().solve(rhs);
        // Decrease predicted by the undamped linear model.
        const double predicted = c.squaredNorm() - (c - Rj * step).squaredNorm();
        Eigen::VectorXd Rn;
        Eigen::Vector2d thn;
        const Eigen::VectorXd zn = z + step;
        const double fn = vp.residual(zn, Rn, thn);
        if (fn < f) {
          const double df = f - fn;
          const double rho = predicted > 0.0 ? df / predicted : 0.0;
          z = zn;
          R = Rn;
          th = thn;
          f = fn;
          mu = std::max(mu * std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)), 1e-12 * mu0);
          nu = 2.0;
          accepted = true;
          history.push_back(f);
          const double sigma2 = R.head(R.size() - m).squaredNorm();  // force cost ≈ weighted noise variance
          small_gains = df <= o.statistical_tolerance * sigma2 / n_data ? small_gains + 1 : 0;
          if (df <= o.tolerance * f || small_gains >= 2 || step.norm() <= o.x_tolerance * (1.0 + z.norm())) {
            g.converged = true;
          } else {
            vp.jacobian(z, R, th, o.jacobian, J);
            const Eigen::VectorXd gn = J.transpose() * R;
            for (int i = 0; i < m; ++i) D[i] = gn[i] * grad[i] < 0.0 ? 8.0 * D[i] : std::max(1.0, 0.5 * D[i]);
            grad = gn;
          }
        } else {
          mu *= nu;
          nu *= 2.0;
          if (step.norm() <= o.x_tolerance * (1.0 + z.norm())) {
            g.converged = true;
            break;
          }
        }
      }
      if (g.converged || !accepted) {
        g.converged = true;
        break;
      }
    }
  } else {
    // Nelder-Mead with the adaptive coefficients of Gao and Han (2012).
    const double n = m;
    const double alpha = 1.0, beta = 1.0 + 2.0 / n, gamma = 0.75 - 1.0 / (2.0 * n), delta = 1.0 - 1.0 / n;
    std::vector<Eigen::VectorXd> S(static_cast<std::size_t>(m + 1), z);
    std::vector<double> F(static_cast<std::size_t>(m + 1));
    // A simplex of unit steps (one prior std) about z0, whose value is f0.
    auto start = [&](const Eigen::VectorXd& z0, double f0) {
      for (auto& v : S) v = z0;
      F[0] = f0;
      for (int i = 0; i < m; ++i) {
        S[static_cast<std::size_t>(i + 1)][i] += 1.0;
        F[static_cast<std::size_t>(i + 1)] = vp.residual(S[static_cast<std::size_t>(i + 1)], R, th);
      }
    };
    start(z, f);
    std::vector<int> ord(static_cast<std::size_t>(m + 1));
    auto eval = [&](const Eigen::VectorXd& v) { return vp.residual(v, R, th); };
    for (g.iterations = 0; g.iterations < o.max_iterations * 50 && vp.evaluations < o.max_evaluations; ++g.iterations) {
      std::iota(ord.begin(), ord.end(), 0);
      std::sort(ord.begin(), ord.end(), [&](int a, int b) { return F[static_cast<std::size_t>(a)] < F[static_cast<std::size_t>(b)]; });
      const auto best = static_cast<std::size_t>(ord.front()), worst = static_cast<std::size_t>(ord.back()),
                 second = static_cast<std::size_t>(ord[ord.size() - 2]);
      double diam = 0.0;
      for (const auto& v : S) diam = std::max(diam, (v - S[best]).lpNorm<Eigen::Infinity>());
      if (F[best] <= o.stop_at_objective) {
        g.converged = true;
        break;
      }
      if (F[worst] - F[best] <= o.tolerance * std::abs(F[best]) + 1e-300 && diam <= o.x_tolerance * 10.0) {
        // Collapsed. A restart from a full-size simplex about the best vertex can leave a kink
        // the collapsed simplex could not (the usual remedy for Nelder-Mead's stalls).
        if (g.restarts < o.nelder_mead_restarts) {
          ++g.restarts;
          start(Eigen::VectorXd(S[best]), F[best]);
          continue;
        }
        g.converged = true;
        break;
      }
      Eigen::VectorXd c = Eigen::VectorXd::Zero(m);
      for (std::size_t i = 0; i < S.size(); ++i)
        if (i != worst) c += S[i];
      c /= n;
      const Eigen::VectorXd xr = c + alpha * (c - S[worst]);
      const double fr = eval(xr);
      if (fr < F[best]) {
        const Eigen::VectorXd xe = c + beta * (xr - c);
        const double fe = eval(xe);
        if (fe < fr) {
          S[worst] = xe;
          F[worst] = fe;
        } else {
          S[worst] = xr;
          F[worst] = fr;
        }
      } else if (fr < F[second]) {
        S[worst] = xr;
        F[worst] = fr;
      } else {
        const bool outside = fr < F[worst];
        const Eigen::VectorXd xc = outside ? Eigen::VectorXd(c + gamma * (xr - c)) : Eigen::VectorXd(c - gamma * (xr - c));
        const double fc = eval(xc);
        if (fc < (outside ? fr : F[worst])) {
          S[worst] = xc;
          F[worst] = fc;
        } else {
          for (std::size_t i = 0; i < S.size(); ++i)
            if (i != best) {
              S[i] = S[best] + delta * (S[i] - S[best]);
              F[i] = eval(S[i]);
            }
        }
      }
    }
    const auto bi = static_cast<std::size_t>(std::min_element(F.begin(), F.end()) - F.begin());
    z = S[bi];
  }

  g.x = vp.x_of(z);
  g.fitted = fitted;
  g.objective = vp.residual(z, R, th, &g.force_cost, &g.geometric_cost);
  g.evaluations = vp.evaluations;
  g.jacobian_evaluations = vp.jacobians;

  // θ at x and the joint covariance of (θ, x_fitted): sandwich form of the regularised estimator.
  Eigen::MatrixX2d A;
  p.regressor(g.x, A);
  g.theta = solve_theta(A, p.y());
  const Eigen::Index n = A.rows();
  Eigen::MatrixXd J(n, 2 + m);
  J.leftCols<2>() = A;
  Eigen::MatrixX2d dA;
  for (int i = 0; i < m; ++i) {
    const int j = vp.idx[static_cast<std::size_t>(i)];
    p.sensitivity(g.x, j, p.fd_step(j), dA);
    J.col(2 + i) = dA * g.theta.theta;
  }
  const Eigen::VectorXd e = p.y() - A * g.theta.theta;
  const Eigen::VectorXd s2 = row_variances(e, 2 + m);
  const double c = static_cast<double>(n) * o.lambda / std::max(1, m);
  Eigen::MatrixXd Jaug = Eigen::MatrixXd::Zero(n + m, 2 + m);
  Jaug.topRows(n) = J;
  for (int i = 0; i < m; ++i) Jaug(n + i, 2 + i) = std::sqrt(c) / vp.sd[vp.idx[static_cast<std::size_t>(i)]];
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(Jaug);
  const Eigen::MatrixXd Rf = qr.matrixQR().topRows(2 + m).triangularView<Eigen::Upper>();
  // H^{-1} = R^{-1} R^{-T}; cov = s2 H^{-1} (J^T J) H^{-1} = s2 (R^{-1} R^{-T} J^T)(...)^T
  const Eigen::MatrixXd Ri = Rf.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(2 + m, 2 + m));
  const Eigen::MatrixXd B = J * (Ri * Ri.transpose());  // n x (2+m)
  Eigen::MatrixXd cov = B.transpose() * s2.asDiagonal() * B;
  g.x_std = Eigen::VectorXd::Zero(M);
  for (int i = 0; i < m; ++i) g.x_std[vp.idx[static_cast<std::size_t>(i)]] = std::sqrt(std::max(0.0, cov(2 + i, 2 + i)));
  if (g.theta.rank == 2) {
    g.theta.cov = cov.topLeftCorner<2, 2>();
    g.theta.K_std = std::sqrt(g.theta.cov(0, 0));
    const Eigen::Vector2d gr(-g.theta.theta[1] / (g.theta.theta[0] * g.theta.theta[0]), 1.0 / g.theta.theta[0]);
    g.theta.mu_std = std::sqrt(std::max(0.0, gr.dot(g.theta.cov * gr)));
  }
  return g;
}

// ---------------------------------------------------------------------------------------------
// Observability

Observability analyse_observability(const ContactProblem& p, const Eigen::VectorXd& x) {
  const int M = p.uncertainties();
  Observability o;
  o.ratio.setZero(M, 2);
  o.touched.resize(static_cast<std::size_t>(M));
  Eigen::MatrixX2d A;
  p.regressor(x, A);
  const Eigen::Index n = A.rows();
  auto centred = [](const Eigen::VectorXd& v) { return Eigen::VectorXd(v.array() - v.mean()); };
  auto sd = [&](const Eigen::VectorXd& v) { return std::sqrt(centred(v).squaredNorm() / std::max<double>(1.0, static_cast<double>(v.size()) - 1.0)); };
  std::array<Eigen::MatrixXd, 2> C;
  for (int c = 0; c < 2; ++c) {
    C[static_cast<std::size_t>(c)].resize(n, M + 1);
    C[static_cast<std::size_t>(c)].col(0) = A.col(c);
  }
  const auto& sc = p.scene();
  std::vector<Eigen::MatrixX2d> dAs(static_cast<std::size_t>(M));
  for (int j = 0; j < M; ++j) {
    const auto& u = sc.uncertainties[static_cast<std::size_t>(j)];
    o.touched[static_cast<std::size_t>(j)] = p.touches(j);
    p.sensitivity(x, j, p.fd_step(j), dAs[static_cast<std::size_t>(j)]);
    const auto& dA = dAs[static_cast<std::size_t>(j)];
    for (int c = 0; c < 2; ++c) {
      C[static_cast<std::size_t>(c)].col(j + 1) = dA.col(c);
      const double s0 = sd(A.col(c));
      o.ratio(j, c) = s0 > 0.0 ? sd(dA.col(c)) / s0 : 0.0;
    }
    const double prior = u.prior_std > 0.0 ? u.prior_std : (u.kind == Uncertainty::Kind::translation ? 1e-4 : 1e-3);
    if (!p.touches(j) || dA.norm() == 0.0) {
      o.unobservable.push_back(u.name + " (its feature is never in contact)");
    } else if (dA.norm() * prior < 1e-2 * A.norm()) {
      o.weak.push_back(u.name);
    }
  }
  auto corr = [&](const Eigen::MatrixXd& X) {
    const Eigen::Index k = X.cols();
    Eigen::MatrixXd Z(X.rows(), k);
    for (Eigen::Index i = 0; i < k; ++i) {
      Eigen::VectorXd v = centred(X.col(i));
      const double nv = v.norm();
      Z.col(i) = nv > 0.0 ? Eigen::VectorXd(v / nv) : Eigen::VectorXd::Zero(X.rows());
    }
    return Eigen::MatrixXd(Z.transpose() * Z);
  };
  o.P1 = corr(C[0]);
  o.P2 = corr(C[1]);
  const bool col2 = A.col(1).norm() > 0.0;
  for (int j = 0; j < M; ++j) {
    if (!o.touched[static_cast<std::size_t>(j)]) continue;
    const double c1 = std::abs(o.P1(0, j + 1)), c2 = col2 ? std::abs(o.P2(0, j + 1)) : 1.0;
    if (c1 >= 0.85 && c2 >= 0.85)
      o.coupled.emplace_back(sc.uncertainties[static_cast<std::size_t>(j)].name, "theta");
    for (int l = j + 1; l < M; ++l) {
      const double d1 = std::abs(o.P1(j + 1, l + 1)), d2 = col2 ? std::abs(o.P2(j + 1, l + 1)) : 1.0;
      if (d1 >= 0.85 && d2 >= 0.85)
        o.coupled.emplace_back(sc.uncertainties[static_cast<std::size_t>(j)].name, sc.uncertainties[static_cast<std::size_t>(l)].name);
    }
  }
  // Singular values of the projected (Kaufman) Jacobian in prior-std units: how well the data
  // determine x beyond what θ absorbs.
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  svd.setThreshold(1e-12);
  const Eigen::Vector2d th = svd.solve(p.y());
  const Eigen::MatrixXd& U = svd.matrixU();
  Eigen::MatrixXd J(n, M);
  for (int j = 0; j < M; ++j) {
    const auto& u = sc.uncertainties[static_cast<std::size_t>(j)];
    const double prior = u.prior_std > 0.0 ? u.prior_std : (u.kind == Uncertainty::Kind::translation ? 1e-4 : 1e-3);
    Eigen::VectorXd g = dAs[static_cast<std::size_t>(j)] * th;
    g -= U * (U.transpose() * g);
    J.col(j) = prior * g / std::sqrt(static_cast<double>(n));
  }
  if (M > 0) {
    Eigen::JacobiSVD<Eigen::MatrixXd> sj(J);
    for (Eigen::Index i = 0; i < sj.singularValues().size(); ++i) o.projected_singular_values.push_back(sj.singularValues()[i]);
  }
  return o;
}

// ---------------------------------------------------------------------------------------------
// L-curve

LCurve l_curve(const ContactProblem& p, const GeometricOptions& base, double lo, double hi, int n) {
  if (!(lo > 0.0 && hi > lo && n >= 3)) throw std::invalid_argument("L-curve needs 0 < lo < hi and at least 3 values");
  LCurve c;
  GeometricOptions o = base;
  Eigen::VectorXd x = p.scene().design();
  for (int i = n - 1; i >= 0; --i) {
    const double t = std::log(lo) + (std::log(hi) - std::log(lo)) * i / (n - 1);
    o.lambda = std::exp(t);
    const auto g = identify_geometry(p, o, &x);
    x = g.x;
    c.lambda.push_back(o.lambda);
    c.force_cost.push_back(g.force_cost);
    c.geometric_cost.push_back(g.geometric_cost);
    c.x.push_back(g.x);
  }
  // Ascending λ.
  std::reverse(c.lambda.begin(), c.lambda.end());
  std::reverse(c.force_cost.begin(), c.force_cost.end());
  std::reverse(c.geometric_cost.begin(), c.geometric_cost.end());
  std::reverse(c.x.begin(), c.x.end());
  const auto N = c.lambda.size();
  c.curvature.assign(N, 0.0);
  double gfloor = 1e-300;
  for (double g : c.geometric_cost) gfloor = std::max(gfloor, g * 1e-12);
  std::vector<double> X(N), Y(N), T(N);
  for (std::size_t i = 0; i < N; ++i) {
    X[i] = std::log(std::max(c.force_cost[i], 1e-300));
    Y[i] = std::log(std::max(c.geometric_cost[i], gfloor));
    T[i] = std::log(c.lambda[i]);
  }
  double best = -std::numeric_limits<double>::infinity();
  c.corner = N / 2;
  for (std::size_t i = 1; i + 1 < N; ++i) {
    const double h1 = T[i] - T[i - 1], h2 = T[i + 1] - T[i];
    const double dx = (X[i + 1] - X[i - 1]) / (h1 + h2), dy = (Y[i + 1] - Y[i - 1]) / (h1 + h2);
    const double ddx = 2.0 * ((X[i + 1] - X[i]) / h2 - (X[i] - X[i - 1]) / h1) / (h1 + h2);
    const double ddy = 2.0 * ((Y[i + 1] - Y[i]) / h2 - (Y[i] - Y[i - 1]) / h1) / (h1 + h2);
    const double den = std::pow(dx * dx + dy * dy, 1.5);
    const double k = den > 0.0 ? (dx * ddy - dy * ddx) / den : 0.0;
    c.curvature[i] = k;
    if (k > best) {
      best = k;
      c.corner = i;
    }
  }
  return c;
}

}  // namespace hil::contact_id
