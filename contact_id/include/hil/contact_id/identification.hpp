#pragma once
/// \file Identification of θ = (K, μK) and of the geometric uncertainties x_u (contact paper sec. 3, 6).
///
/// Weighted least squares: every sample contributes 6 rows, forces divided by F_max and moments by
/// M_max (the paper's W_Y^{-1/2}). The linear problem is solved by SVD (rank, condition and
/// covariance reported), never by normal equations. The geometric problem (eq. 21)
///   min_x (1/6L) ||W^{-1/2}(Y - Φ(x)^T θ̂(x))||² + (λ/M) Σ_j ((x_j - x_j^d)/σ_j)²
/// is solved by variable projection (θ̂(x) is the linear LS solution), either with Nelder-Mead on
/// the projected functional (as in the paper) or with Levenberg-Marquardt on the projected residual
/// with the Golub-Pereyra (or Kaufman) Jacobian; regressor sensitivities ∂Φ/∂x_j come from mindist
/// by central differences, recomputing only the polyhedron pairs of the feature x_j moves.
///
/// Not thread-safe: a ContactProblem keeps scratch buffers; use one per thread.
#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include <hil/contact_id/model.hpp>

namespace hil::contact_id {

/// One measured sample: kinematics and the plate wrench (fp frame, about the fp origin).
struct Measurement {
  double t_s = 0.0;
  Kinematics kin;
  Vector6d w_fp = Vector6d::Zero();
};

struct ProblemOptions {
  double force_scale_n = 0.0;    ///< F_max; 0 = largest measured force component over the contact samples
  double moment_scale_nm = 0.0;  ///< M_max; 0 = largest measured moment component
  double v_tm = 1e-3;            ///< sticking threshold, m/s
  /// Pairs whose geometry x_u may move are kept when closer than this under x_u^d (bounding
  /// spheres, then the separating-axis gap). Must exceed how far x_u can move a feature.
  double broad_margin_m = 1e-3;
};

/// The data set of one identification: samples, their weighted outputs and the cached contact
/// structure. The used samples are those in contact under the design geometry x_u^d (the paper
/// drops samples without contact points); the set stays fixed while x_u varies, so the objective
/// is continuous in x_u (a sample that loses contact keeps its rows, with Φ = 0).
class ContactProblem {
 public:
  /// \throws std::invalid_argument on non-finite input or bad scales;
  /// \throws std::runtime_error if no sample brings the objects into contact.
  ContactProblem(Scene scene, std::vector<Measurement> data, const ProblemOptions& options = {});

  const Scene& scene() const { return scene_; }
  const std::vector<Measurement>& data() const { return data_; }
  const std::vector<int>& used() const { return used_; }  ///< indices of the samples used
  Eigen::Index rows() const { return static_cast<Eigen::Index>(6 * used_.size()); }
  int uncertainties() const { return static_cast<int>(scene_.uncertainties.size()); }
  const Eigen::VectorXd& y() const { return y_; }        ///< W^{-1/2} Y (stacked, 6 rows per used sample)
  const Eigen::VectorXd& weights() const { return w_; }  ///< the row weights (1/F_max, 1/M_max)
  double force_scale() const { return f_scale_; }
  double moment_scale() const { return m_scale_; }
  double v_tm() const { return opt_.v_tm; }
  /// The measured contact wrench on object 1 (o1 frame) of used sample a.
  const Vector6d& measured(std::size_t a) const { return y_o1_[a]; }

  /// W^{-1/2} Φ^T stacked over the used samples at x. `contacts` (optional): contact points per used sample.
  void regressor(const Eigen::VectorXd& x, Eigen::MatrixX2d& A, std::vector<int>* contacts = nullptr) const;
  /// ∂(W^{-1/2} Φ^T)/∂x_j at x by central differences with step h (m or rad). Only the pairs of
  /// the feature x_j moves are recomputed; right after regressor(x), without their axis searches.
  void sensitivity(const Eigen::VectorXd& x, int j, double h, Eigen::MatrixX2d& dA) const;
  /// Whether any candidate pair involves the feature of uncertainty j (else ∂Φ/∂x_j ≡ 0).
  bool touches(int j) const { return touched_[static_cast<std::size_t>(j)]; }
  /// Finite-difference step for x_j: 1e-3 prior std (or 1e-7 m / 1e-6 rad without a prior).
  double fd_step(int j) const;

 private:
  struct VarPair {
    int a;       ///< used-sample index
    int p1, p2;  ///< flattened polyhedron indices
    int f1, f2;  ///< their features
    double gap;  ///< lower bound on the pair's distance at x_u^d (-inf when in contact)
  };
  /// Feature transforms, displacement bounds and posed fixed bodies at x (into the scratch below).
  void prepare(const Eigen::VectorXd& x) const;
  /// Poses every polyhedron of body b with the feature transforms of the last prepare().
  void pose_body(int b, const Eigen::Isometry3d& T_world_body, std::vector<PosedPolyhedron>& out) const;
  const PosedPolyhedron& posed(int b, int q, int a, const Eigen::Isometry3d& Tf, PosedPolyhedron& scratch) const;
  /// Whether a pair that was vp.gap apart under x_u^d stays apart when its polyhedra moved by d1, d2.
  bool out_of_reach(const VarPair& vp, double d1, double d2) const;
  Regressor pair_contact(const VarPair& vp, const PosedPolyhedron& A, const PosedPolyhedron& B, int* in_contact) const;
  /// The regressor rows of a pair's contact (tangent from the sample's relative velocity).
  Regressor pair_rows(const VarPair& vp, const PairContact& pc) const;

  Scene scene_;
  std::vector<Measurement> data_;
  ProblemOptions opt_;
  std::vector<int> used_;
  std::vector<Regressor> fixed_;  ///< per used sample: contribution of pairs no x_u moves
  std::vector<int> fixed_contacts_;
  std::vector<VarPair> var_;
  std::vector<Eigen::Isometry3d> T_o1_, T_o2_;  ///< per used sample (T_o2_ empty when object 2 is fixed)
  std::vector<Vector6d> y_o1_;
  std::vector<bool> touched_;
  std::array<std::vector<std::pair<int, int>>, 2> index_;  ///< flattened polyhedron -> (feature, polyhedron)
  Eigen::VectorXd y_, w_;
  Eigen::MatrixX2d A_design_;  ///< W^{-1/2} Φ^T at x_u^d (computed once)
  std::vector<int> contacts_design_;
  double f_scale_ = 1.0, m_scale_ = 1.0;
  std::array<bool, 2> fixed_body_{};                           ///< body not carried by the end effector: one pose for all samples
  std::vector<double> reach_;                                  ///< per uncertainty: vertex displacement per unit |x_j - x_j^d|
  mutable std::array<std::vector<Eigen::Isometry3d>, 2> Tf_;   ///< feature transforms at the current x
  mutable std::array<std::vector<double>, 2> disp_;            ///< per feature: displacement bound from x_u^d
  mutable std::array<std::vector<PosedPolyhedron>, 2> posed_;  ///< fixed bodies posed at the current x
  mutable std::vector<PosedPolyhedron> plus_, minus_;          ///< moved feature at x ± h (sensitivity)
  mutable PosedPolyhedron pa_, pb_;
  mutable ClipWorkspace clip_;
  double max_turn_rad_ = 0.0;                ///< largest finite-difference rotation step
  mutable Eigen::VectorXd base_x_;           ///< x of the last regressor() evaluation (empty: none)
  mutable std::vector<SatRecord> base_sat_;  ///< per var_ pair: its separating-axis pass at base_x_
};

/// The linear estimate of θ = (K, μK) with its statistics.
struct LinearEstimate {
  Eigen::Vector2d theta = Eigen::Vector2d::Zero();
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  int rank = 0;
  double condition = 0.0;  ///< σ_max / σ_min of W^{-1/2} Φ^T (inf when rank deficient)
  double sigma2 = 0.0;     ///< residual variance (weighted units)
  double K = 0.0, K_std = 0.0;
  double mu = 0.0, mu_std = 0.0;
  bool mu_identifiable = false;       ///< false when all contacts stick (Φ's friction column is zero)
  double relative_force_error = 0.0;  ///< sqrt of the mean squared weighted residual (paper: mean relative force error)
  Eigen::Index rows = 0;
  std::string note;  ///< e.g. why μ is not identifiable
};

/// Least squares on weighted rows (A θ ≈ b) by SVD. \throws std::runtime_error if A is zero.
LinearEstimate solve_theta(const Eigen::MatrixX2d& A, const Eigen::VectorXd& b);

/// The global estimate over all used samples at geometry x.
LinearEstimate global_estimate(const ContactProblem& p, const Eigen::VectorXd& x);

/// Running global estimate for online use: each sample's 6 weighted rows are folded into a 2x2
/// triangular factor by Householder QR of [R; A_k] (no normal equations, O(1) per sample, no
/// allocation). The residual sum of squares is carried along exactly.
class RunningLeastSquares {
 public:
  /// Adds one sample's weighted rows (A_k θ ≈ b_k).
  void add(const Regressor& A, const Vector6d& b);
  std::size_t samples() const { return n_; }
  /// The estimate so far; mu_identifiable false until some contact slid. Valid once samples() > 0.
  LinearEstimate estimate() const;

 private:
  Eigen::Matrix2d R_ = Eigen::Matrix2d::Zero();
  Eigen::Vector2d z_ = Eigen::Vector2d::Zero();
  double rss_ = 0.0;
  std::size_t n_ = 0;
};

/// An instantaneous estimate (one sample, or a centred window of used samples).
struct InstantEstimate {
  double t_s = 0.0;
  int contacts = 0;
  bool valid = false;     ///< K estimated
  bool mu_valid = false;  ///< μ estimated (some contact sliding)
  double K = 0.0, mu = 0.0;
};
/// Per used sample (window = 1) or over a centred window of `window` used samples.
std::vector<InstantEstimate> instantaneous(const ContactProblem& p, const Eigen::VectorXd& x, int window = 1);

enum class Solver { levenberg_marquardt, nelder_mead };
enum class VpJacobian { golub_pereyra, kaufman };

struct GeometricOptions {
  double lambda = 1e-2;
  Solver solver = Solver::levenberg_marquardt;
  VpJacobian jacobian = VpJacobian::golub_pereyra;
  int max_iterations = 200;     ///< LM iterations, or NM iterations
  int max_evaluations = 20000;  ///< NM objective evaluations
  /// Stop when an accepted step lowers the objective by less than this fraction (statistically
  /// meaningful changes are of order 1/(6L), far larger).
  double tolerance = 1e-7;    ///< (LM also stops when 5 iterations gained < 100 x this)
  double x_tolerance = 1e-5;  ///< stop when a step is shorter than this (prior-std units)
  /// LM also stops when two accepted steps in a row lowered the objective by less than this many
  /// units of σ²/(6L) (σ² estimated by the force cost): a change of the weighted χ² = 6L f/σ² below
  /// this is statistically meaningless (1 is the change of a one-standard-deviation parameter move).
  double statistical_tolerance = 1e-2;
  std::vector<bool> fit;  ///< which x_j to fit (empty: all touched ones)
  /// Nelder-Mead stops as soon as its best objective is <= this (to measure the effort needed to
  /// reach another solver's optimum); -inf: off.
  double stop_at_objective = -std::numeric_limits<double>::infinity();
  /// Nelder-Mead: how many times a collapsed simplex is restarted (full size, about its best vertex).
  int nelder_mead_restarts = 0;
};

struct GeometricEstimate {
  Eigen::VectorXd x, x_std;  ///< estimate and standard deviation (0 for the ones not fitted)
  std::vector<bool> fitted;
  LinearEstimate theta;  ///< θ at x; K_std, mu_std from the joint covariance of (θ, x)
  double lambda = 0.0;
  double force_cost = 0.0;      ///< (1/6L) ||W^{-1/2}(Y - Φθ)||²
  double geometric_cost = 0.0;  ///< (1/M) Σ ((x - x^d)/σ)²
  double objective = 0.0;
  int evaluations = 0;           ///< objective (full regressor) evaluations
  int jacobian_evaluations = 0;  ///< LM only
  int restarts = 0;              ///< Nelder-Mead restarts used
  int iterations = 0;
  bool converged = false;
};

/// The projected objective at x (eq. 21 with θ = θ̂(x)); also returns its two terms.
double projected_objective(const ContactProblem& p, const Eigen::VectorXd& x, double lambda, const std::vector<bool>& fitted,
                           double* force_cost = nullptr, double* geometric_cost = nullptr);

/// Variable projection. Starts at x^d unless x0 is given. Uncertainties whose prior_std is 0 use
/// 1e-4 m / 1e-3 rad. \throws std::runtime_error if no uncertainty can be fitted.
GeometricEstimate identify_geometry(const ContactProblem& p, const GeometricOptions& o, const Eigen::VectorXd* x0 = nullptr);

/// Observability before fitting (paper sec. 7.2.1), evaluated at x.
struct Observability {
  /// ratio(j, c): std of column c of W^{-1/2}∂Φ/∂x_j over std of column c of W^{-1/2}Φ (Table 2; 1/m or 1/rad).
  Eigen::MatrixXd ratio;
  /// Correlations of the normalised columns [Φ_c, ∂Φ/∂x_1 c, ..., ∂Φ/∂x_M c] for c = 1 (P1) and 2 (P2), eq. 28-29.
  Eigen::MatrixXd P1, P2;
  std::vector<bool> touched;                                 ///< feature ever near a contact
  std::vector<std::string> unobservable;                     ///< never touched, zero sensitivity, or absorbed by θ
  std::vector<std::string> weak;                             ///< sensitivity over a prior std below 1 % of the regressor
  std::vector<std::pair<std::string, std::string>> coupled;  ///< |P1| and |P2| >= 0.85
  std::vector<double> projected_singular_values;             ///< of the VP Jacobian in prior-std units
};
Observability analyse_observability(const ContactProblem& p, const Eigen::VectorXd& x);

/// The L-curve (paper sec. 7.2.2): the regularised problem solved for λ from hi down to lo
/// (warm-started), the corner at the point of maximum curvature of (log force cost, log geometric cost).
struct LCurve {
  std::vector<double> lambda, force_cost, geometric_cost, curvature;
  std::vector<Eigen::VectorXd> x;
  std::size_t corner = 0;
};
LCurve l_curve(const ContactProblem& p, const GeometricOptions& base, double lo = 1e-4, double hi = 1e3, int n = 30);

}  // namespace hil::contact_id
