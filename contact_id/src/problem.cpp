// The contact identification problem (hil/contact_id/identification.hpp): the data, the regressor
// A(x) of y = A(x) θ and its sensitivities to the geometric uncertainties.
#include <hil/contact_id/identification.hpp>
#include <hil/so3/so3.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace hil::contact_id {

namespace {
std::string num(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}
}  // namespace

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
  for (int b = 0; b < 2; ++b)
    uncertain[static_cast<std::size_t>(b)].assign(scene_.bodies[static_cast<std::size_t>(b)].features.size(), false);
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
    if (fixed_body_[static_cast<std::size_t>(b)])
      pose_body(b, scene_.bodies[static_cast<std::size_t>(b)].T_attach, posed_[static_cast<std::size_t>(b)]);

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
    if (fixed_body_[static_cast<std::size_t>(b)])
      pose_body(b, scene_.bodies[static_cast<std::size_t>(b)].T_attach, posed_[static_cast<std::size_t>(b)]);
}

const PosedPolyhedron& ContactProblem::posed(int b, int q, int a, const Eigen::Isometry3d& Tf, PosedPolyhedron& scratch) const {
  const auto [f, k] = index_[static_cast<std::size_t>(b)][static_cast<std::size_t>(q)];
  const auto& T = (b == 0 ? T_o1_ : T_o2_)[static_cast<std::size_t>(a)];
  scratch.pose(scene_.bodies[static_cast<std::size_t>(b)].features[static_cast<std::size_t>(f)].polyhedra[static_cast<std::size_t>(k)],
               T * Tf);
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
    const auto& P1 = fixed_body_[0] ? posed_[0][static_cast<std::size_t>(vp.p1)]
                                    : posed(0, vp.p1, vp.a, Tf_[0][static_cast<std::size_t>(vp.f1)], pa_);
    const auto& P2 = fixed_body_[1] ? posed_[1][static_cast<std::size_t>(vp.p2)]
                                    : posed(1, vp.p2, vp.a, Tf_[1][static_cast<std::size_t>(vp.f2)], pb_);
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

}  // namespace hil::contact_id
