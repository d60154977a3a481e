// robot_compliance: the ee deflects under the contact load. φ: coordinates of a symmetric 6x6
// Cartesian compliance C (ee frame) on its identifiable directions; the true ee pose is
// T_meas Exp(C w_ee), w_ee the measured contact wrench on the held object about the ee origin (ee
// frame). The 21 entries are reduced to the directions the SVD of the projected Jacobian at C = 0
// can see (what K absorbs drops out); the others stay free for the validity check.
#include <hil/diagnose/contact_family.hpp>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <cmath>

namespace hil::diagnose {
namespace {

using hil::Matrix6d;

/// The name the fit reports entry (i, j) of C under (C_x_x ... C_rz_rz).
std::string entry_name(int i, int j) {
  static const char* ax[6] = {"x", "y", "z", "rx", "ry", "rz"};
  return std::string("C_") + ax[i] + "_" + ax[j];
}

// Typical sizes of the compliance entries: 1 µm/N translational, 10 µrad/N coupling, 0.1 mrad/(N m)
// rotational; the identifiable directions are chosen in these units.
double compliance_scale(int i, int j) {
  const bool ti = i < 3, tj = j < 3;
  if (ti && tj) return 1e-6;
  if (!ti && !tj) return 1e-4;
  return 1e-5;
}

std::vector<Matrix6d> all_basis() {
  std::vector<Matrix6d> b;
  for (int i = 0; i < 6; ++i)
    for (int j = i; j < 6; ++j) {
      Matrix6d E = Matrix6d::Zero();
      E(i, j) = E(j, i) = compliance_scale(i, j);
      b.push_back(E);
    }
  return b;
}

class Term : public ContactTerm {
 public:
  /// Every symmetric direction, none reduced: the design the reduction differentiates.
  Term() : basis_(all_basis()) {}
  explicit Term(const ContactBinding& b) {
    // Reduce the 21 symmetric coordinates to the directions the data can see: the SVD of the
    // Jacobian of the projected residual at C = 0 (θ projected out, so what K absorbs is dropped).
    const auto& d = b.data;
    const auto full_term = std::make_shared<const Term>();
    const auto& full = full_term->basis_;
    auto projected = [&](const Eigen::VectorXd& c) {
      Eigen::MatrixXd A;
      b.design_alone(full_term, c, A);
      const Eigen::Index m = static_cast<Eigen::Index>(6 * b.samples.size());
      Eigen::VectorXd y(m);
      Eigen::MatrixXd Aw(m, A.cols());
      for (Eigen::Index r = 0; r < m; ++r) {
        const int k = b.samples[static_cast<std::size_t>(r / 6)], c6 = static_cast<int>(r % 6);
        const double w = d.obs.weight(c6);
        y(r) = w * d.obs.y(k, c6);
        Aw.row(r) = w * A.row(6 * k + c6);
      }
      Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(Aw);
      return Eigen::VectorXd(y - Aw * cod.solve(y));
    };
    const Eigen::VectorXd c0 = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(full.size()));
    const Eigen::VectorXd r0 = projected(c0);
    Eigen::MatrixXd J(r0.size(), c0.size());
    for (Eigen::Index j = 0; j < c0.size(); ++j) {
      Eigen::VectorXd c = c0;
      c(j) = 1e-2;
      J.col(j) = (projected(c) - r0) / 1e-2;
    }
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(J, Eigen::ComputeThinV);
    const Eigen::VectorXd sv = svd.singularValues();
    for (Eigen::Index i = 0; i < svd.matrixV().cols(); ++i) {
      Matrix6d B = Matrix6d::Zero();
      for (Eigen::Index j = 0; j < c0.size(); ++j) B += svd.matrixV()(j, i) * full[static_cast<std::size_t>(j)];
      const bool seen = i < sv.size() && i < 6 && sv(i) > 0.05 * sv(0) && basis_.size() == static_cast<std::size_t>(i);
      (seen ? basis_ : null_basis_).push_back(B);
    }
  }
  std::vector<Param> nonlinear() const override {
    std::vector<Param> p;
    for (std::size_t i = 0; i < basis_.size(); ++i) p.push_back({"compliance_c" + std::to_string(i + 1), "", 1.0, true, -100, 100});
    return p;
  }
  bool moves_contacts() const override { return true; }
  bool derives_from_data() const override { return true; }
  void channels(const ContactSlots& s, const Eigen::VectorXd& phi, ContactChannels& c) const override {
    for (std::size_t i = 0; i < basis_.size(); ++i) c.compliance += phi(s.nonlinear + static_cast<Eigen::Index>(i)) * basis_[i];
    c.deflect = true;
    c.recompute = true;
  }
  void report(const ContactSlots&, bool linear, Eigen::Index, const Fit&, Reported& r) const override {
    if (!linear) r.fold_comparable = false;  // coordinates on a basis each fold chooses anew
  }
  void report_derived(const ContactSlots& s, Eigen::Index p, const Fit& f, std::vector<Reported>& out) const override {
    // The compliance entries the fitted directions give (informative, not PNR-checked).
    const Eigen::Index q0 = p + s.nonlinear;
    const Eigen::Index r = static_cast<Eigen::Index>(basis_.size());
    for (int i = 0; i < 6; ++i)
      for (int j = i; j < 6; ++j) {
        Eigen::VectorXd b(r);
        for (Eigen::Index m = 0; m < r; ++m) b(m) = basis_[static_cast<std::size_t>(m)](i, j);
        if (b.norm() < 1e-3 * compliance_scale(i, j)) continue;
        const double v = b.dot(f.phi.segment(s.nonlinear, r));
        const double sd = std::sqrt(std::max(0.0, b.dot(f.cov.block(q0, q0, r, r) * b)));
        const std::string unit = (i < 3 && j < 3) ? "m/N" : (i >= 3 && j >= 3) ? "rad/(N m)" : "m/(N m)";
        out.push_back({entry_name(i, j), unit, v, sd, false});
      }
  }
  std::string check(const ContactSlots& slots, Eigen::Index p, const Fit& f) const override {
    if (basis_.empty()) return "";
    // C in balanced units (µm/N, 0.1 mrad/(N m)): positive semi-definiteness is invariant under it.
    hil::Vector6d s;
    s << 1e3, 1e3, 1e3, 1e2, 1e2, 1e2;
    const Eigen::Index i0 = slots.nonlinear, r = static_cast<Eigen::Index>(basis_.size());
    Matrix6d C = Matrix6d::Zero(), V = Matrix6d::Zero();
    for (Eigen::Index m = 0; m < r; ++m) C += f.phi(i0 + m) * basis_[static_cast<std::size_t>(m)];
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) {
        Eigen::VectorXd b(r);
        for (Eigen::Index m = 0; m < r; ++m) b(m) = basis_[static_cast<std::size_t>(m)](i, j);
        V(i, j) = std::sqrt(std::max(0.0, b.dot(f.cov.block(p + i0, p + i0, r, r) * b)));
      }
    const Matrix6d Cs = s.asDiagonal() * C * s.asDiagonal(), Vs = s.asDiagonal() * V * s.asDiagonal();
    // The fit fixes C only along the identifiable directions; the others are free. It is physical
    // when some compliance with the fitted coordinates is positive semi-definite (within two
    // standard deviations): max over the free coordinates z of λ_min(C + Σ z_k N_k), a concave
    // function of z, by subgradient ascent (the gradient is u^T N_k u, u the lowest eigenvector).
    std::vector<Matrix6d> Ns;
    for (const auto& N : null_basis_) Ns.push_back(s.asDiagonal() * N * s.asDiagonal());
    if (max_min_eigenvalue(Cs, Ns) < -2.0 * Vs.norm()) return "no positive semi-definite compliance has the fitted coordinates";
    return "";
  }
  const std::vector<Matrix6d>& basis() const { return basis_; }

 private:
  std::vector<Matrix6d> basis_;
  std::vector<Matrix6d> null_basis_;  ///< the symmetric directions the data cannot see (the rest of the 21)
};

/// The ee deflects under its load: T = T_cmd Exp(C w_ee).
class Wrist : public Injection {
 public:
  explicit Wrist(const Matrix6d& C) : C_(C) {}
  /// The entries it sets (those the test can check a fit's derived entries against).
  TruthValues truth() const override {
    TruthValues t;
    for (int i = 0; i < 6; ++i)
      for (int j = i; j < 6; ++j)
        if (C_(i, j) != 0.0) t[entry_name(i, j)] = C_(i, j);
    return t;
  }
  std::vector<TruthField> file_fields() const override {
    return {{"compliance", C_, {}, "wrist compliance (robot_compliance), 6x6 from wrench (N, N m) to displacement (m, rad)"}};
  }
  void channels(const contact_id::Scene&, SimulationChannels& c) const override { c.compliance = C_; }

 private:
  Matrix6d C_;
};

class RobotCompliance : public ContactEffect {
 public:
  std::string name() const override { return "robot_compliance"; }
  int list_order() const override { return 20; }
  std::string description() const override { return "the end effector deflects under the contact load (6x6 Cartesian compliance)"; }
  bool extends(FamilyKind f) const override { return f == FamilyKind::contact || f == FamilyKind::deflection; }
  int layout_order() const override { return 20; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding& b) const override { return std::make_shared<Term>(b); }
  bool injectable() const override { return true; }
  std::shared_ptr<const Injection> draw(unsigned seed, const contact_id::Scene&) const override {
    EffectDraw r(seed, name());
    // A lateral compliance of the wrist: 0.5-1 µm/N in x and y of the ee frame (a tenth to a fifth
    // of the contact's own compliance 1/K).
    const double cxx = std::abs(r.magnitude(0.5e-6, 1e-6));
    return inject({{"C_x_x", cxx}, {"C_y_y", std::abs(r.magnitude(0.5e-6, 1e-6))}});
  }
  /// Keys C_<i>_<j> (i <= j of x y z rx ry rz): the entries of the symmetric C, as the fit reports them.
  std::shared_ptr<const Injection> inject(const TruthValues& v) const override {
    std::vector<std::string> keys;
    Matrix6d C = Matrix6d::Zero();
    for (int i = 0; i < 6; ++i)
      for (int j = i; j < 6; ++j) {
        keys.push_back(entry_name(i, j));
        C(i, j) = C(j, i) = truth_value(v, keys.back());
      }
    check_truth_keys(name(), v, keys);
    return std::make_shared<Wrist>(C);
  }
};

}  // namespace

std::shared_ptr<const Effect> make_robot_compliance() { return std::make_shared<RobotCompliance>(); }

}  // namespace hil::diagnose
