#pragma once
// hil::solver: one bounded Levenberg-Marquardt for the project's nonlinear least-squares fits
// (contact identification's variable projection, the diagnosis engine's separable fits). Pure
// numerics on Eigen; the caller supplies the residual and its Jacobian in scaled units.

#include <Eigen/Core>

#include <functional>
#include <vector>

namespace hil::solver {

/// A least-squares problem min_x ½‖r(x)‖² (the cost is the caller's, usually ‖r‖²) in scaled units
/// u = x / scale: the Jacobian is ∂r/∂u, steps and their norms are in u.
struct Problem {
  /// r(x) into `r`; returns the cost compared between iterates (e.g. ‖r‖²).
  std::function<double(const Eigen::VectorXd& x, Eigen::VectorXd& r)> residual;
  /// ∂r/∂u at the current iterate x, whose residual is r, into J (rows of r, columns of x). Columns
  /// of fixed parameters are not used (the solver sets them to zero).
  std::function<void(const Eigen::VectorXd& x, const Eigen::VectorXd& r, Eigen::MatrixXd& J)> jacobian;
  /// Called when the last point given to `residual` becomes the current iterate (for the caller's
  /// state that goes with it).
  std::function<void()> accepted;
  Eigen::VectorXd scale;         ///< x units per scaled unit; empty: ones
  Eigen::VectorXd lower, upper;  ///< box bounds on x (trial points are clamped); empty: none
  std::vector<bool> fixed;       ///< parameters held at their starting value; empty: none
};

/// How the damping μ starts and changes.
enum class Damping {
  /// Madsen-Nielsen-Tingleff: μ0 = 1e-3 max_j ‖J_j‖², after a success μ·max(1/3, 1-(2ρ-1)³) with
  /// ρ the gain ratio (floor 1e-12 μ0), after a failure ×ν, ν doubling.
  gain_ratio,
  /// μ0 = 1e-3 σ_max(J)², after a success ÷3 (floor 1e-12), after a failure ×4.
  fixed_factors,
};

struct Options {
  int max_iterations = 100;
  Damping damping = Damping::gain_ratio;
  int max_trials = 12;        ///< damped trials per iteration with a freshly computed Jacobian
  int max_trials_secant = 3;  ///< ... with a secant-updated one
  /// Per-parameter damping μ D: D_jj ×8 when ∂f/∂u_j changes sign between accepted iterates (the
  /// step went past a minimum along u_j, e.g. a V-shaped kink), relaxed ÷2 (floor 1) otherwise.
  bool kink_damping = false;
  /// Up to this many Broyden secant updates of J in a row after accepted steps instead of calls to
  /// `jacobian`. A freshly computed Jacobian confirms every stop and replaces a secant one that
  /// gives no descent.
  int secant_updates = 0;
  double singular_cutoff = 1e-9;  ///< singular values of J D^-1/2 below this × the largest are dropped

  // Stopping (each rule on an accepted step; 0 turns a rule off).
  double relative_decrease = 1e-10;  ///< f_old - f_new ≤ this × f_old
  /// Statistically insignificant decrease: f_old - f_new ≤ this × ‖r_new[0:data_rows]‖² / dof,
  /// `statistical_repeats` times in a row.
  double statistical_tolerance = 0.0;
  long data_rows = -1;  ///< leading rows of r that are data (the rest: priors); -1: all
  double degrees_of_freedom = 1.0;
  int statistical_repeats = 1;
  /// Step: ‖step‖ ≤ step_absolute + step_relative ‖u‖ (also ends an iteration's trials when a
  /// rejected step is that small).
  double step_absolute = 0.0;
  double step_relative = 0.0;
  bool stop_on_small_rejected_step = false;  ///< a rejected step that small ends the iteration's trials
  /// Stall: the last `stall_iterations` accepted steps together gained ≤ stall_tolerance × f.
  int stall_iterations = 0;
  double stall_tolerance = 0.0;
  double gradient_tolerance = 0.0;  ///< ‖Jᵀr‖∞ < this × max(1, f)
};

/// Why levenberg_marquardt returned: the rule that stopped it. Every value but max_iterations comes
/// with Result::converged = true.
enum class StopReason {
  /// An accepted step gained ≤ Options::relative_decrease × the cost before it.
  relative_decrease,
  /// Accepted steps gained ≤ Options::statistical_tolerance × noise / dof, `statistical_repeats`
  /// times in a row.
  statistical,
  /// An accepted step was no longer than step_absolute + step_relative ‖u‖.
  step_size,
  /// A rejected step was that small (Options::stop_on_small_rejected_step): the iteration's trials
  /// ended without a decrease.
  small_rejected_step,
  /// None of an iteration's damped trials lowered the cost (a local minimum at the precision of
  /// the residual, or a Jacobian that gives no descent).
  no_decrease,
  /// The last `stall_iterations` accepted steps together gained ≤ stall_tolerance × the cost.
  stall,
  /// ‖Jᵀr‖∞ < gradient_tolerance × max(1, cost) at the start of an iteration.
  gradient,
  /// Options::max_iterations iterations ran without a stopping rule holding (not converged).
  max_iterations,
  /// x0 is empty: nothing to fit.
  no_parameters,
};
/// The stop reason in words, e.g. "relative decrease below tolerance".
const char* to_string(StopReason reason) noexcept;

struct Result {
  Eigen::VectorXd x;
  double cost = 0.0;
  Eigen::VectorXd r;
  int iterations = 0;   ///< iterations before the one that stopped
  int evaluations = 0;  ///< calls to `residual` (the start included)
  int jacobians = 0;    ///< calls to `jacobian`
  bool converged = false;
  /// The rule that stopped the fit. When several hold after the same accepted step, the first of
  /// statistical, relative_decrease, step_size.
  StopReason stop_reason = StopReason::max_iterations;
};

/// Minimises from x0 (clamped to the bounds by the caller). `cost0`/`r0`: the residual at x0 when
/// the caller has it (cost0 < 0: evaluated here).
Result levenberg_marquardt(const Problem& problem, const Eigen::VectorXd& x0, const Options& options, double cost0 = -1.0,
                           const Eigen::VectorXd* r0 = nullptr);

}  // namespace hil::solver
