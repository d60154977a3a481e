#pragma once
/// \file The deflection family: when the rig has no contact geometry, the quantity the model must
/// predict is how the ee (a robot's end effector, or a mobile base standing on the plate) moves away
/// from its rest pose under the measured load. The nominal model is rigid: a constant pose.
///
///   y_k = [p_k - p_0 ; log(R_k R_0ᵀ)]  (world axes; m, rad)
///   nominal           y = d (6 constants)
///   robot_compliance  y = d + C w(t)        C symmetric 6x6 (21 entries, linear; rank-revealing LS
///                                           keeps the identifiable part), w the load the body puts
///                                           on its support (= the plate's wrench) about its rest
///                                           position, world axes
///   time_offset       y = d + C w(t - τ)    the deflection lags the load by τ (with compliance)
///   rest_change       y = d + Σ_e H_e(t) Δ_e (+ the others' terms)   the rest pose steps by Δ_e
///                                           (6 linear entries per event) at events located from
///                                           the data: a body that slips on its support stays where
///                                           it went, which no elastic model follows. H_e is 0
///                                           up to the last searched sample before the change, 1
///                                           from the first after, and a ramp in between: the
///                                           probability that the step has happened by t when the
///                                           data put it anywhere in that interval (uniformly).
///                                           On every sample the interval holds no sample, so H_e
///                                           is a step; a fold whose held-out block holds the
///                                           change predicts that block with the ramp, the least
///                                           mean squared error without knowing where the step is
///                                           (1/6 of Δ² over the block, against 1/4 for a step at
///                                           the middle).
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <hil/contact_id/model.hpp>
#include <hil/diagnose/engine.hpp>

namespace hil::diagnose {

const std::vector<std::string>& deflection_extensions();

/// A change of the rest pose located by rest_change's search. The change happened between two
/// samples: `lower_s` .. `upper_s` is the span of the sample intervals whose split costs at most a
/// χ²₁ 95 % bound (3.84 long-run noise variances) more than the best one; never narrower than the
/// two samples around the change (a fold that did not see them: the whole gap).
struct RestEvent {
  double t_s = 0.0;  ///< the step's time in the model: midway between the samples around the change
  double lower_s = 0.0, upper_s = 0.0;
  int first_sample = 0;  ///< the first sample (index into the observations) at the new rest pose
  /// The searched samples around the change: the last at the old rest pose, the first at the new.
  /// Adjacent samples for a fit on every sample; for a fold whose held-out block holds the change,
  /// the whole gap, across which the model ramps (below).
  double before_s = 0.0, after_s = 0.0;
};

/// The change-point search of rest_change, on a residual (m x 6, one row per searched sample, in
/// time order, times `t_s`; empty: the row index): binary segmentation of a piecewise-constant mean.
/// Each component is standardised by its noise level (median absolute first difference). An event
/// must lower the cost by more than a BIC penalty of (6 + 1) ln(m) noise variances twice over:
/// globally, and locally against a line in time over `window` samples either side (a step is
/// abrupt; a slow deflection the model misses is locally a line). Positions refined by coordinate
/// descent, weak events pruned, at most `max_events`, segments of at least `min_segment` samples.
/// Returns the positions (the row of the first sample after each change, increasing) and, per
/// event, the first and last position whose split is within 3.84 (χ²₁ 95 %) variances of the best:
/// the long-run variance of the residual around the segmentation, at least the noise variance.
/// \throws std::invalid_argument on a residual without 6 columns, non-finite values, times that do
/// not match or do not increase, min_segment or window below 2.
struct ChangePoints {
  std::vector<int> position, lower, upper;
  double inflation = 1.0;  ///< the variance of the intervals, in noise variances (>= 1)
};
ChangePoints locate_changes(const Eigen::MatrixXd& residual, const std::vector<double>& t_s = {}, int max_events = 8, int min_segment = 3,
                            int window = 10);

struct DeflectionData {
  Observations obs;      ///< deflection: dx dy dz (m), rx ry rz (rad)
  Eigen::MatrixXd load;  ///< N x 6: the plate's force (N) and moment (N m) about p_0, world axes
  std::vector<double> speed_m_per_s;
};

/// From poses (ee in world) and plate wrenches (fp frame, about the fp origin).
/// \throws std::runtime_error on too few samples or non-finite values.
DeflectionData make_deflection_data(const std::vector<double>& t_s, const std::vector<contact_id::Kinematics>& kin,
                                    const std::vector<Eigen::Matrix<double, 6, 1>>& w_fp, const Eigen::Isometry3d& T_world_fp);

class DeflectionFamily : public ModelFamily {
 public:
  DeflectionFamily(const DeflectionData& d, std::set<std::string> extensions);
  std::string name() const override;
  std::vector<Param> linear() const override { return linear_; }
  std::vector<Param> nonlinear() const override { return nonlinear_; }
  std::vector<Eigen::VectorXd> starts() const override;
  using ModelFamily::design;
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData&) const override;
  /// C must be symmetric positive semi-definite (within two standard deviations).
  std::string check(const Fit& f) const override;
  /// With rest_change: the same family with its events located from the samples `train` only.
  /// As ModelFamily::report; a fold locates its own events, so its step_k_* are not those of the full fit.
  std::vector<Reported> report(const Fit& f) const override;
  std::unique_ptr<ModelFamily> restricted(const std::vector<int>& train) const override;
  /// rest_change's events (empty without it, or when the search found none: then the family is the
  /// one without rest_change).
  const std::vector<RestEvent>& events() const { return events_; }
  /// events() as event_1_s, event_2_s, ... in time order.
  std::vector<LocatedEvent> located_events() const override;

 private:
  DeflectionFamily(const DeflectionData& d, std::set<std::string> extensions, const std::vector<int>& train);
  /// Locates the events on the samples `train`: on the residual of the model without rest_change
  /// fitted there, then once more on the residual of the joint fit without its steps (a compliance
  /// fitted alone absorbs part of a step that correlates with the load).
  void locate(const std::vector<int>& train);
  void add_steps();

  const DeflectionData& d_;
  std::set<std::string> ext_;
  std::vector<Param> linear_, nonlinear_;
  bool compliance_ = false;
  int i_tau_ = -1;
  std::size_t first_step_ = 0;  ///< the column of the first step's first entry
  std::vector<RestEvent> events_;
};

}  // namespace hil::diagnose
