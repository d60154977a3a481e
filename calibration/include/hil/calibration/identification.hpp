#pragma once
/// \file Weighted least squares (paper eq. 7) and its covariance (eq. 8), solved by QR and SVD.
///
/// The weighted system η A π ≈ η t is first compressed by a Householder QR, A_w = Q R, keeping
/// R (n x n), z = Qᵀ t_w (n) and the squared norm of the part of t_w no parameter reaches. Every
/// later question (a column subset, parameters moved to fixed values, rank and singular values) is
/// answered from R and z alone: any column selection C gives ‖A_w C π - t_w‖² = ‖R C π - z‖² + rss_outside.
/// The normal equations are never formed. Columns are scaled to unit norm before the SVD so that
/// parameters of very different magnitudes (m/N next to rad/(N·m)) share one rank tolerance.
#include <vector>

#include <Eigen/Core>

namespace hil::calibration {

struct CompressedSystem {
  Eigen::MatrixXd R;         ///< min(m, n) x n, upper triangular (Qᵀ A_w)
  Eigen::VectorXd z;         ///< min(m, n): Qᵀ t_w
  double rss_outside = 0.0;  ///< ‖t_w‖² - ‖z‖², computed as the squared norm of the rest of Qᵀ t_w
  Eigen::Index rows = 0;     ///< m, number of weighted equations
};

CompressedSystem compress(const Eigen::Ref<const Eigen::MatrixXd>& A_w, const Eigen::Ref<const Eigen::VectorXd>& t_w);

/// Result of a weighted least-squares solve. Standard deviations and covariance are those of
/// eq. 8, (Σ_j A_jᵀ Σ^-1 A_j)^-1, obtained from the SVD; they are NaN when the free columns are
/// rank deficient (the report then says so).
struct LsqSolution {
  Eigen::VectorXd value;
  Eigen::VectorXd std_dev;
  Eigen::MatrixXd covariance;
  Eigen::VectorXd singular_values;  ///< of the column-scaled weighted observation matrix, descending
  int rank = 0;
  bool full_rank = false;
  double condition = 0.0;  ///< σ_max / σ_min of the column-scaled matrix (∞ if rank deficient)
  double rss = 0.0;        ///< weighted residual sum of squares (χ² if the noise model is right)
  Eigen::Index dof = 0;    ///< rows - rank
  double sigma0_sq = 0.0;  ///< rss / dof: about 1 when the noise model fits the data
};

/// Rank of a column-scaled matrix: singular values above tolerance · σ_max.
struct RankOptions {
  double tolerance = 1e-9;
};

/// Solves for the `free_cols` of the compressed system with the `fixed_cols` held at `fixed_values`.
LsqSolution solve(const CompressedSystem& sys, const std::vector<int>& free_cols, const std::vector<int>& fixed_cols,
                  const Eigen::Ref<const Eigen::VectorXd>& fixed_values, const RankOptions& options = {});
/// All columns free.
LsqSolution solve(const CompressedSystem& sys, const RankOptions& options = {});

/// A column whose norm is below kZeroColumn times the largest one of the selection is zero
/// (rounding noise, e.g. a tool-roll joint under pure forces at a tool point on its axis).
inline constexpr double kZeroColumn = 1e-12;

/// R restricted to `cols` with each column scaled to unit norm (zero columns stay zero).
Eigen::MatrixXd scaled_columns(const CompressedSystem& sys, const std::vector<int>& cols, Eigen::VectorXd* scale = nullptr);
/// Rank and singular values of the column-scaled observation matrix restricted to `cols`.
int rank_of(const CompressedSystem& sys, const std::vector<int>& cols, const RankOptions& options = {},
            Eigen::VectorXd* singular_values = nullptr);

/// Parameter-to-noise ratio |π| / σ (paper eq. 10) and the classes G1+ (≥ high), G1~ (≥ low), G1-.
struct PnrThresholds {
  double low = 2.0;
  double high = 5.0;
};
enum class PnrClass { g1_plus, g1_tilde, g1_minus };
const char* to_string(PnrClass c);
PnrClass classify(double pnr, const PnrThresholds& t);

}  // namespace hil::calibration
