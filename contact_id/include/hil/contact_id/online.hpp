#pragma once
/// \file Online estimation, one sample at a time: instantaneous and running global estimates of
/// θ = (K, μK) at the design geometry. Pure numerics (the DDS worker wraps it).
#include <hil/contact_id/identification.hpp>

namespace hil::contact_id {

struct OnlineEstimate {
  double t_s = 0.0;
  int contacts = 0;
  bool instantaneous_valid = false;
  double K_instant = 0.0;
  double mu_instant = 0.0;  ///< NaN while every contact sticks
  LinearEstimate global;    ///< over every sample in contact so far
};

class OnlineEstimator {
 public:
  /// \pre force_scale_n > 0, moment_scale_nm > 0 (the W_Y weights; fixed up front online).
  OnlineEstimator(Scene scene, double v_tm, double force_scale_n, double moment_scale_nm);
  /// Processes one sample. Not real-time safe on the first calls (buffers grow once).
  OnlineEstimate update(const Measurement& m);
  const LinearEstimate& global() const { return last_; }

 private:
  Scene scene_;
  double v_tm_, wf_, wm_;
  MindistWorkspace ws_;
  std::vector<ContactPoint> contacts_;
  RunningLeastSquares rls_;
  LinearEstimate last_;
};

}  // namespace hil::contact_id
