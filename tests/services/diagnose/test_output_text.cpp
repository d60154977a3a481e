// What `hil diagnose` prints beside a value carried by one event (issue 32): the model's std where
// nothing contradicts it, the group of components that does where one does, nothing otherwise.
#include <gtest/gtest.h>

#include <hil/services/diagnose_output.hpp>

namespace hil::services::diagnose {
namespace {

TEST(SummaryText, SaysWhyAOneEventValueKeepsOrLosesTheModelsStd) {
  hil::diagnose::Reported q;
  q.name = "slow_slip_mu_k_n_per_m";
  q.sandwich_dof = 1.31;
  EXPECT_EQ(one_event_text(q), "");  // the residuals measured its interval: nothing to say
  q.model_based = true;
  EXPECT_EQ(one_event_text(q), "  one event's worth (ν 1.3): the model's std, which the folds and the component groups do not contradict");
  q.model_based = false;
  q.components_disagree = "fz, mx, my alone read 5.9e+04 ± 900";
  q.std_components = 1200.0;
  EXPECT_EQ(one_event_text(q), "  one event's worth (ν 1.3), but fz, mx, my alone read 5.9e+04 ± 900: the interval reaches across theirs");
}

}  // namespace
}  // namespace hil::services::diagnose
