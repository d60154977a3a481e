// The truth's tripod as a hil rig (tripod_scene.hpp): before the blind suite trusts it, the scene
// and the converter must reproduce the truth's own law where the two models agree, and the nominal
// fit of a clean run must return the truth's K and μ.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include <hil/diagnose/contact_family.hpp>
#include <hil/diagnose/engine.hpp>
#include "tripod_scene.hpp"

namespace hil::diagnose::test {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// A run with no sensor chain at all: the measured wrench is the true one.
ct::Scenario noiseless(double duration_s) {
  ct::Scenario s = pressing_and_sliding(duration_s);
  s.sensor.noise_std.setZero();
  s.sensor.resolution.setZero();
  return s;
}

TEST(TripodScene, TheNominalModelOnTheSceneIsTheTruthsLawPerSample) {
  const ct::Scenario sc = noiseless(10.0);
  const auto samples = ct::simulate(sc);
  const cid::Scene scene = tripod_scene(sc.plate, sc.tripod);
  const auto m = to_measurements(samples);
  cid::ContactModel model;
  model.K = sc.law.stiffness_n_per_m;
  model.mu = sc.law.mu;
  model.v_tm = kVtm_m_per_s;
  cid::MindistWorkspace ws;
  std::vector<cid::ContactPoint> contacts;
  int in_contact = 0, lifted = 0;
  double max_force_n = 0.0;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Vector6d w = cid::plate_wrench(scene, model, scene.design(), m[k].kin, ws, contacts);
    const Vector6d truth = samples[k].wrench_true;
    SCOPED_TRACE("sample " + std::to_string(k));
    // Same feet in contact (the tetrahedra's apexes are the truth's points).
    ASSERT_EQ(static_cast<int>(contacts.size()), samples[k].feet_in_contact);
    (samples[k].feet_in_contact == 3 ? in_contact : lifted) += 1;
    max_force_n = std::max(max_force_n, truth.head<3>().norm());
    // Forces: the truth's friction is μN u / sqrt(u² + ε²), hil's μN: with every foot sliding at
    // >= 4 mm/s and ε = 0.1 mm/s, 1 - u/sqrt(u² + ε²) <= 3.2e-4, i.e. < 0.01 N on <= 30 N of friction.
    EXPECT_LT((w.head<3>() - truth.head<3>()).norm(), 0.01) << w.transpose() << "\n" << truth.transpose();
    // Moments: hil puts each contact at the volume centroid of the clipped tip (a tetrahedron: the
    // mean of its vertices), 3δ/4 <= 105 µm above the apex; the friction (<= 0.3 · 3 · K · 140 µm
    // = 25 N in all) then has that much more lever about o_P: < 3e-3 N m.
    EXPECT_LT((w.tail<3>() - truth.tail<3>()).norm(), 3e-3) << w.transpose() << "\n" << truth.transpose();
  }
  // The run presses, slides and lifts off.
  EXPECT_GT(in_contact, 500);
  EXPECT_GT(lifted, 100);
  EXPECT_GT(max_force_n, 40.0);
}

TEST(TripodScene, TheForcePlateFrameIsThePlatesAndTheWrenchIsAboutItsOrigin) {
  // One foot's force applied through hil's plate_wrench_of in the scene's fp frame gives the
  // truth's reported wrench of that foot.
  const ct::Scenario sc = noiseless(1.0);
  const cid::Scene scene = tripod_scene(sc.plate, sc.tripod);
  const ct::BodyState b = ct::true_state(sc, 0.3);
  std::vector<ct::FootContact> feet;
  const ct::Vector6d truth = ct::plate_wrench(sc.plate, sc.tripod, sc.law, b, &feet);
  Vector6d sum = Vector6d::Zero();
  for (const auto& f : feet) {
    ASSERT_TRUE(f.in_contact);
    const Eigen::Vector3d n = sc.plate.T_world_plate().linear().col(2);
    sum += plate_wrench_of(scene.T_world_fp, f.normal_n * n + f.friction_world_n, f.point_world_m);
  }
  EXPECT_LT((sum - truth).norm(), 1e-9 * truth.norm()) << sum.transpose() << "\n" << truth.transpose();
}

TEST(TripodScene, TheConverterQuantisesTheReportedPositionAndVelocityOnly) {
  const ct::Scenario sc = noiseless(0.5);
  const auto samples = ct::simulate(sc);
  const auto exact = to_measurements(samples);
  const auto q = to_measurements(samples, {2e-6, 2e-4});
  ASSERT_EQ(q.size(), samples.size());
  bool moved = false;
  for (std::size_t k = 0; k < q.size(); ++k) {
    EXPECT_EQ(q[k].t_s, samples[k].t_s);
    EXPECT_EQ(q[k].w_fp, samples[k].wrench_measured);
    EXPECT_EQ(exact[k].kin.T_world_ee.matrix(), samples[k].reported.T_world_body.matrix());
    EXPECT_EQ(q[k].kin.T_world_ee.linear(), samples[k].reported.T_world_body.linear());
    EXPECT_EQ(q[k].kin.w_world_ee, samples[k].reported.w_world_rad_per_s);
    for (int i = 0; i < 3; ++i) {
      const double p = q[k].kin.T_world_ee.translation()[i], v = q[k].kin.v_world_ee[i];
      EXPECT_NEAR(p / 2e-6, std::round(p / 2e-6), 1e-6);
      EXPECT_NEAR(v / 2e-4, std::round(v / 2e-4), 1e-6);
      EXPECT_LE(std::abs(p - samples[k].reported.T_world_body.translation()[i]), 1e-6 + 1e-15);
      EXPECT_LE(std::abs(v - samples[k].reported.v_world_m_per_s[i]), 1e-4 + 1e-15);
      moved = moved || v != samples[k].reported.v_world_m_per_s[i];
    }
  }
  EXPECT_TRUE(moved);
  EXPECT_THAT(
      [&] {
        to_measurements(samples, {-1.0, 0.0});
      },
      ThrowsMessage<std::invalid_argument>(HasSubstr("to_measurements: resolutions must be finite and >= 0")));
}

TEST(TripodScene, ACleanRunsNominalFitReturnsTheTruthsStiffnessAndFriction) {
  // No wrench noise or quantisation; the reported pose at the fine resolution (2 µm, 2e-5 m/s).
  const ct::Scenario sc = noiseless(16.0);
  const cid::Scene scene = tripod_scene(sc.plate, sc.tripod);
  const auto data = make_contact_data(scene, kVtm_m_per_s, to_measurements(ct::simulate(sc), {2e-6, 2e-5}));
  const ContactFamily nominal(data, {});
  std::vector<int> all(data.obs.size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = static_cast<int>(k);
  const Fit f = fit(nominal, data.obs, all);
  double K = 0, mu = 0;
  for (const auto& r : f.reported) {
    if (r.name == "K") K = r.value;
    if (r.name == "mu") mu = r.value;
  }
  // What separates the models here: the 2 µm position steps (1-2 % of a foot's 35-140 µm
  // interference, unbiased over the run), hil's contact point δ/4 above the tip and the truth's
  // regularised friction (3e-4 relative, see above): 1 % on K and μ is ample, a wrong frame, foot
  // or sign is not within it.
  EXPECT_NEAR(K, sc.law.stiffness_n_per_m, 0.01 * sc.law.stiffness_n_per_m);
  EXPECT_NEAR(mu, sc.law.mu, 0.01 * sc.law.mu);
  // The weighted residual (relative to the largest component): the pose steps alone, < 1 %.
  const double err = relative_error(data.obs, predict(nominal, f, data.obs.size()), all);
  EXPECT_LT(err, 0.01);
  RecordProperty("K", std::to_string(K));
  RecordProperty("mu", std::to_string(mu));
  RecordProperty("relative_error", std::to_string(err));
  std::cout << "clean nominal fit: K = " << K << " N/m, mu = " << mu << ", relative error = " << err << "\n";
}

}  // namespace
}  // namespace hil::diagnose::test
