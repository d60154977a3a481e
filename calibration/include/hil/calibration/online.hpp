#pragma once
/// \file Online identification: the weighted system is kept compressed (R, z) and updated by Givens
/// rotations with each new measurement, O(rows · n²), never re-factorised from the data. An estimate
/// (values, standard deviations, parameter-to-noise ratios, classes, rank, residual RMS per axis)
/// is available after every update. Pure numerics: the DDS worker in tools/hil/stiffness feeds it.
#include <array>
#include <vector>

#include <hil/calibration/reduction.hpp>

namespace hil::calibration {

struct OnlineEstimate {
  std::size_t measurements = 0;
  std::size_t configurations = 0;  ///< distinct configuration ids seen
  int rank = 0;
  bool full_rank = false;
  std::vector<KeptParameter> kept;
  std::vector<FixedParameter> fixed;
  std::array<double, 6> residual_rms{};  ///< dx dy dz rx ry rz (m, rad); NaN where nothing measured
};

class OnlineIdentifier {
 public:
  /// Identifies `free` with `fixed` held at `fixed_values` (e.g. a model reduced offline), or, with
  /// `reduce` set, runs M4-M6 on the compressed system at each estimate over `free` (e.g. the
  /// physical set after M1-M3). \pre noise entries > 0 for the measured quantities.
  OnlineIdentifier(VjmModel model, ParameterSet free, ParameterSet fixed, Eigen::VectorXd fixed_values, NoiseModel noise,
                   PipelineOptions options = {}, bool reduce = false);

  /// Adds one measurement: builds its weighted rows and rotates them into R (and into its axis's
  /// system). Workspaces are kept between calls, but small temporaries are still allocated: not
  /// real-time safe.
  void add(const Measurement& m);
  /// Solves from the compressed system. With `reduce`, the last reduction is re-verified on the
  /// updated system (reverify_algebraic) and M4-M6 re-run in full only when a decision changed or is
  /// too close to its threshold to confirm; the estimate is the full reduction's either way.
  /// Not safe to call concurrently on one identifier: it updates that cache (the stiffness worker
  /// calls it from its one thread).
  OnlineEstimate estimate() const;

  /// How the reductions of estimate() were obtained.
  struct ReductionStats {
    std::size_t full = 0;      ///< reduce_algebraic runs
    std::size_t verified = 0;  ///< cached structures confirmed by reverify_algebraic
  };
  const ReductionStats& reduction_stats() const { return stats_; }
  /// false: run the full reduction at every estimate (no cache), e.g. to compare timings.
  void set_reuse_reduction(bool reuse) { reuse_ = reuse; }
  /// The options estimate() uses: the given ones, with the rank tolerance raised to rows·ε when the
  /// accumulated rounding of that many Givens updates exceeds it (after ~4.5 million rows at 1e-9).
  PipelineOptions effective_options() const;

  std::size_t measurements() const { return measurements_; }
  Eigen::Index equations() const { return rows_; }
  const CompressedSystem& compressed() const { return sys_; }
  const ParameterSet& parameters() const { return params_; }
  const VjmModel& model() const { return model_; }

 private:
  void rotate_in(Eigen::MatrixXd& R, Eigen::VectorXd& z, double& rss, const Eigen::Ref<const Eigen::RowVectorXd>& a, double b);

  VjmModel model_;
  ParameterSet params_;  ///< free then fixed
  std::size_t n_free_ = 0;
  Eigen::VectorXd fixed_values_;
  NoiseModel noise_;
  PipelineOptions options_;
  bool reduce_ = false;
  CompressedSystem sys_;
  std::array<CompressedSystem, 6> axis_sys_;  ///< per axis, for residual RMS
  std::array<double, 6> axis_sigma_{};
  std::size_t measurements_ = 0;
  Eigen::Index rows_ = 0;
  std::vector<int> configs_;
  VjmWorkspace ws_;
  Eigen::MatrixXd A6_, A_;
  Eigen::RowVectorXd row_;
  std::vector<int> axes_;
  bool reuse_ = true;
  // Cache of estimate() (logically const: it only decides how the same answer is computed).
  mutable bool have_reduction_ = false;
  mutable AlgebraicResult reduction_;
  mutable ReductionStats stats_;
};

}  // namespace hil::calibration
