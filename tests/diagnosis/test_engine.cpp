// The diagnosis' engine, contact family, generator and deflection family on small exact cases.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <numeric>
#include <random>
#include <set>
#include <thread>
#include <typeinfo>

#include <hil/diagnose/contact_family.hpp>
#include <hil/diagnose/deflection_family.hpp>
#include <hil/diagnose/diagnose.hpp>
#include <hil/so3/so3.hpp>
#include <hil/test/eigen.hpp>
#include "scenes.hpp"

namespace hil::diagnose {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

/// y_c(t) = θ_0 sin(2π f t + c) + θ_1, f nonlinear: a small separable family with a known optimum.
class SineFamily : public ModelFamily {
 public:
  explicit SineFamily(const Observations& o) : o_(o) {}
  std::string name() const override { return "sine"; }
  std::vector<Param> linear() const override { return {{"amplitude", "", 1, false}, {"offset", "", 1, true}}; }
  std::vector<Param> nonlinear() const override { return {{"frequency", "Hz", 0.1, true, 0.1, 5}}; }
  std::vector<Eigen::VectorXd> starts() const override { return {Eigen::VectorXd::Constant(1, 1.2)}; }
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData&) const override {
    A.setZero(static_cast<Eigen::Index>(6 * o_.size()), 2);
    for (std::size_t k = 0; k < o_.size(); ++k)
      for (int c = 0; c < 6; ++c) {
        A(static_cast<Eigen::Index>(6 * k) + c, 0) = std::sin(2 * M_PI * phi(0) * o_.t_s[k] + c);
        A(static_cast<Eigen::Index>(6 * k) + c, 1) = 1.0;
      }
  }

 private:
  const Observations& o_;
};

Observations sine_data(double f, double amp, double off, double noise, unsigned seed) {
  Observations o;
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1);
  const int n = 400;
  o.y.resize(n, 6);
  for (int k = 0; k < n; ++k) {
    o.t_s.push_back(0.01 * k);
    for (int c = 0; c < 6; ++c) o.y(k, c) = amp * std::sin(2 * M_PI * f * o.t_s.back() + c) + off + noise * g(rng);
  }
  return o;
}

std::vector<int> all(std::size_t n) {
  std::vector<int> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<int>(i);
  return v;
}

TEST(Engine, RecoversASeparableModelExactlyWithoutNoise) {
  const auto o = sine_data(1.23, 2.5, 0.4, 0.0, 1);
  SineFamily m(o);
  const Fit f = fit(m, o, all(o.size()));
  EXPECT_NEAR(f.phi(0), 1.23, 1e-7);
  EXPECT_NEAR(f.theta(0), 2.5, 1e-6);
  EXPECT_NEAR(f.theta(1), 0.4, 1e-6);
  EXPECT_EQ(f.rank, 3);
  EXPECT_LT(f.rss, 1e-12);
}

TEST(Engine, IntervalsCoverTheTruthAndCrossValidationScoresHeldOutData) {
  const auto o = sine_data(1.23, 2.5, 0.4, 0.05, 2);
  SineFamily m(o);
  const Score s = score(m, o);
  for (const auto& r : s.full.reported) {
    const double truth = r.name == "frequency" ? 1.23 : r.name == "amplitude" ? 2.5 : 0.4;
    EXPECT_LT(std::abs(r.value - truth), 4 * r.std) << r.name;
    EXPECT_GT(r.std, 0.0);
  }
  // Held-out error is about the noise (relative to weight 1), training error slightly below.
  EXPECT_NEAR(s.cv_error, 0.05, 0.01);
  EXPECT_LE(s.train_error, s.cv_error);
  EXPECT_TRUE(s.identifiable);
}

/// The sine family whose design jumps by `jump` on one row when the frequency reaches `edge`: a
/// design discontinuous in φ, as a contact's stick/slip switch at v_tm makes a delayed one.
class JumpingSine : public SineFamily {
 public:
  JumpingSine(const Observations& o, double start, double edge, double jump) : SineFamily(o), start_(start), edge_(edge), jump_(jump) {}
  std::vector<Eigen::VectorXd> starts() const override { return {Eigen::VectorXd::Constant(1, start_)}; }
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData& data) const override {
    SineFamily::design(phi, A, data);
    if (phi(0) >= edge_) A(6 * 17 + 2, 0) += jump_;
  }

 private:
  double start_, edge_, jump_;
};

TEST(Engine, AnIntervalIsNotShrunkByADesignThatJumpsBesideTheOptimum) {
  // Statistics at the true frequency (no iteration), with the design's jump half a difference step
  // (1e-4 of the scale 0.1) above it, then below it: a one-sided difference across the jump
  // measures jump / step (3e3 on one row against slopes of a few units), not the slope.
  const auto o = sine_data(1.0, 1.0, 0.0, 0.1, 5);
  FitOptions once;
  once.max_iterations = 0;
  const double h = 1e-4 * 0.1;
  const Fit smooth = fit(JumpingSine(o, 1.0, 1e300, 0.0), o, all(o.size()), once);
  ASSERT_EQ(smooth.phi(0), 1.0);
  const double sd = std::sqrt(smooth.cov(2, 2));
  ASSERT_GT(sd, 0.0);
  for (double edge : {1.0 + 0.5 * h, 1.0 - 0.5 * h}) {
    const Fit jumping = fit(JumpingSine(o, 1.0, edge, 0.03), o, all(o.size()), once);
    ASSERT_EQ(jumping.phi(0), 1.0);
    EXPECT_NEAR(std::sqrt(jumping.cov(2, 2)), sd, 0.05 * sd) << "jump at " << edge - 1.0 << " from the optimum";
  }
}

/// y_c = θ_0 sin(2π f t + c) + θ_1 + θ_2 g_c(t) + φ_1 θ_0 h(t): `twin` makes g a multiple of the
/// sine (θ_2 cannot be told from the amplitude); φ_1 (bounded ±0.5) scales a signal h that is 0
/// when `flat`, so that nothing determines it.
class CollinearFamily : public ModelFamily {
 public:
  CollinearFamily(const Observations& o, bool twin, bool flat) : o_(o), twin_(twin), flat_(flat) {}
  std::string name() const override { return "collinear"; }
  std::vector<Param> linear() const override { return {{"amplitude", "", 1, false}, {"offset", "", 1, false}, {"twin", "", 1, true}}; }
  std::vector<Param> nonlinear() const override {
    return {{"frequency", "Hz", 0.1, false, 0.1, 5}, {"ghost_gain", "", 0.01, true, -0.5, 0.5}};
  }
  std::vector<Eigen::VectorXd> starts() const override { return {(Eigen::VectorXd(2) << 1.2, 0.0).finished()}; }
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData&) const override {
    A.setZero(static_cast<Eigen::Index>(6 * o_.size()), 3);
    for (std::size_t k = 0; k < o_.size(); ++k)
      for (int c = 0; c < 6; ++c) {
        const double t = o_.t_s[k], s = std::sin(2 * M_PI * phi(0) * t + c);
        const double h = flat_ ? 0.0 : std::cos(7.0 * t);
        const auto r = static_cast<Eigen::Index>(6 * k) + c;
        A(r, 0) = s * (1.0 + phi(1) * h);
        A(r, 1) = 1.0;
        A(r, 2) = twin_ ? 3.0 * s : std::cos(3.1 * t + c);
      }
  }

 private:
  const Observations& o_;
  bool twin_, flat_;
};

bool listed(const Fit& f, const std::string& name) {
  return std::any_of(f.unidentifiable.begin(), f.unidentifiable.end(), [&](const Unidentifiable& u) { return u.name == name; });
}
bool reported(const Fit& f, const std::string& name) {
  return std::any_of(f.reported.begin(), f.reported.end(), [&](const Reported& r) { return r.name == name; });
}

TEST(Engine, InseparableParametersAreFixedListedByNameAndNeverReported) {
  const auto o = sine_data(1.23, 2.5, 0.4, 0.05, 3);
  {
    // The twin column is 3x the amplitude's: fixed at 0 before estimation, collinear with it.
    CollinearFamily m(o, true, false);
    const Fit f = fit(m, o, all(o.size()));
    ASSERT_TRUE(listed(f, "twin"));
    const auto& u = *std::find_if(f.unidentifiable.begin(), f.unidentifiable.end(), [](const auto& x) { return x.name == "twin"; });
    EXPECT_EQ(u.collinear_with, std::vector<std::string>{"amplitude"});
    EXPECT_NE(u.reason.find("collinear with amplitude"), std::string::npos) << u.reason;
    EXPECT_FALSE(reported(f, "twin"));
    EXPECT_EQ(f.theta(2), 0.0);
    EXPECT_NEAR(f.theta(0), 2.5, 0.02);  // the amplitude takes the whole sine
    EXPECT_NEAR(f.phi(0), 1.23, 1e-3);
    // ghost_gain multiplies cos(7t): separable, so fitted (near 0) and reported.
    EXPECT_FALSE(listed(f, "ghost_gain"));
    EXPECT_TRUE(reported(f, "ghost_gain"));
  }
  {
    // ghost_gain scales a zero signal: no effect on the prediction, fixed and said so.
    CollinearFamily m(o, false, true);
    const Fit f = fit(m, o, all(o.size()));
    ASSERT_TRUE(listed(f, "ghost_gain"));
    EXPECT_FALSE(reported(f, "ghost_gain"));
    EXPECT_EQ(f.phi(1), 0.0);
    EXPECT_FALSE(listed(f, "twin"));
    for (const auto& r : f.reported) EXPECT_TRUE(std::isfinite(r.std) && r.std > 0) << r.name;
  }
  {
    // Switched off, the inseparable twin is reported, with an enormous or zero interval: what the
    // check exists to prevent.
    CollinearFamily m(o, true, false);
    FitOptions off;
    off.collinearity_sine = 0;
    const Fit f = fit(m, o, all(o.size()), off);
    EXPECT_TRUE(f.unidentifiable.empty());
    EXPECT_TRUE(reported(f, "twin"));
  }
}

/// y = θ_0 + φ t (one "gain" φ bounded to ±0.05) on data whose slope is 0.3: the fit runs to the
/// bound, which is no estimate.
class BoundedSlope : public ModelFamily {
 public:
  explicit BoundedSlope(const Observations& o) : o_(o) {}
  std::string name() const override { return "bounded"; }
  std::vector<Param> linear() const override { return {{"level", "", 1, false}}; }
  std::vector<Param> nonlinear() const override { return {{"slope", "1/s", 0.01, true, -0.05, 0.05}}; }
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData&) const override {
    A.setZero(static_cast<Eigen::Index>(6 * o_.size()), 1);
    for (std::size_t k = 0; k < o_.size(); ++k)
      for (int c = 0; c < 6; ++c) A(static_cast<Eigen::Index>(6 * k) + c, 0) = 1.0 + phi(0) * o_.t_s[k];
  }

 private:
  const Observations& o_;
};

TEST(Engine, AParameterAtItsBoundIsListedNotPrinted) {
  Observations o;
  for (int k = 0; k < 200; ++k) o.t_s.push_back(0.02 * k);
  o.y.resize(200, 6);
  for (int k = 0; k < 200; ++k) o.y.row(k).setConstant(2.0 * (1.0 + 0.3 * o.t_s[static_cast<std::size_t>(k)]));
  BoundedSlope m(o);
  const Fit f = fit(m, o, all(o.size()));
  ASSERT_TRUE(listed(f, "slope"));
  EXPECT_NE(f.unidentifiable.front().reason.find("bound"), std::string::npos) << f.unidentifiable.front().reason;
  EXPECT_FALSE(reported(f, "slope"));
  EXPECT_EQ(f.phi(0), 0.0);
  FitOptions off;
  off.collinearity_sine = 0;
  const Fit g = fit(m, o, all(o.size()), off);
  EXPECT_NEAR(g.phi(0), 0.05, 1e-9);  // what would have been printed
}

/// SineFamily with its offset bounded below by 0 (`bounded`), or without the offset column.
class NonnegativeOffset : public ModelFamily {
 public:
  NonnegativeOffset(const Observations& o, bool with_offset, double lower = 0.0) : o_(o), offset_(with_offset), lower_(lower) {}
  std::string name() const override { return "nonnegative offset"; }
  std::vector<Param> linear() const override {
    std::vector<Param> v{{"amplitude", "", 1, false}};
    if (offset_) v.push_back({"offset", "", 1, true, lower_});
    return v;
  }
  std::vector<Param> nonlinear() const override { return {{"frequency", "Hz", 0.1, true, 0.1, 5}}; }
  std::vector<Eigen::VectorXd> starts() const override { return {Eigen::VectorXd::Constant(1, 1.2)}; }
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData&) const override {
    A.setZero(static_cast<Eigen::Index>(6 * o_.size()), offset_ ? 2 : 1);
    for (std::size_t k = 0; k < o_.size(); ++k)
      for (int c = 0; c < 6; ++c) {
        A(static_cast<Eigen::Index>(6 * k) + c, 0) = std::sin(2 * M_PI * phi(0) * o_.t_s[k] + c);
        if (offset_) A(static_cast<Eigen::Index>(6 * k) + c, 1) = 1.0;
      }
  }

 private:
  const Observations& o_;
  bool offset_;
  double lower_;
};

// A linear parameter bounded below by 0 (contact_damping's μ_D D, issue 32): where the data put it
// below, the fit holds it at 0 and reports it as having run to its bound, and the other
// parameters are the fit without it (the bounded least squares' solution); where the data put it
// above, the bound changes nothing. A bound other than >= 0 on a linear parameter is refused.
TEST(Engine, ALinearParameterBoundedAtZeroIsHeldThereAndListed) {
  const auto o = sine_data(1.23, 2.5, -0.3, 0.05, 7);
  const Fit unbounded = fit(SineFamily(o), o, all(o.size()));
  ASSERT_LT(unbounded.theta(1), -0.2);  // the data's offset, read where nothing bounds it
  const Fit f = fit(NonnegativeOffset(o, true), o, all(o.size()));
  ASSERT_TRUE(listed(f, "offset"));
  EXPECT_NE(f.unidentifiable.front().reason.find("bound"), std::string::npos) << f.unidentifiable.front().reason;
  EXPECT_FALSE(reported(f, "offset"));
  EXPECT_EQ(f.theta(1), 0.0);
  const Fit without = fit(NonnegativeOffset(o, false), o, all(o.size()));
  EXPECT_NEAR(f.theta(0), without.theta(0), 1e-9 * std::abs(without.theta(0)));
  EXPECT_NEAR(f.phi(0), without.phi(0), 1e-7);
  EXPECT_NEAR(f.rss, without.rss, 1e-9 * without.rss);
  EXPECT_GT(f.rss, unbounded.rss * 1.5);  // the bound costs: the data's offset is far below it

  const auto up = sine_data(1.23, 2.5, 0.4, 0.05, 8);
  const Fit g = fit(NonnegativeOffset(up, true), up, all(up.size()));
  const Fit h = fit(SineFamily(up), up, all(up.size()));
  EXPECT_FALSE(listed(g, "offset"));
  ASSERT_TRUE(reported(g, "offset"));
  EXPECT_NEAR(g.theta(1), h.theta(1), 1e-9);
  EXPECT_NEAR(g.phi(0), h.phi(0), 1e-7);

  EXPECT_THROW(fit(NonnegativeOffset(o, true, -1.0), o, all(o.size())), std::logic_error);
}

/// A plate's normal force f_z = K (h - z): K linear, the plate's height h nonlinear, z the measured
/// ee height, read with an error of known std (a quantiser's). `shift` moves every z by that much.
class PressFamily : public ModelFamily {
 public:
  PressFamily(std::vector<double> z_m, double error_std_m, double shift_m = 0.0)
      : z_(std::move(z_m)), error_(error_std_m), shift_(shift_m) {}
  std::string name() const override { return "press"; }
  std::vector<Param> linear() const override { return {{"K", "N/m", 1.0, false}}; }
  std::vector<Param> nonlinear() const override { return {{"h", "m", 0.01, true, -10.0, 10.0}}; }
  /// Above every z (the plate over the ee): the projected cost has a hump where h crosses z's mean.
  std::vector<Eigen::VectorXd> starts() const override { return {Eigen::VectorXd::Constant(1, 1.2)}; }
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData&) const override {
    A.setZero(static_cast<Eigen::Index>(6 * z_.size()), 1);
    for (std::size_t k = 0; k < z_.size(); ++k) A(static_cast<Eigen::Index>(6 * k) + 2, 0) = phi(0) - (z_[k] + shift_);
  }
  std::vector<ErrorInVariable> errors_in_variables() const override {
    if (!(error_ > 0)) return {};
    std::vector<ErrorInVariable> v(1);
    v[0].variable = "z";
    v[0].std = error_;
    v[0].shifted = [this](double by) { return std::make_unique<PressFamily>(z_, 0.0, shift_ + by); };
    return v;
  }

 private:
  std::vector<double> z_;
  double error_, shift_;
};

/// One press: z of two tones, the force with white noise, z read with a uniform error of std `e`.
struct Press {
  Observations o;
  std::vector<double> z_read;
};
Press press_run(unsigned seed, double K, double h, double error_std_m) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.01);
  const double half = error_std_m * std::sqrt(3.0);  // uniform over ± half has this std
  std::uniform_real_distribution<double> read(-half, half);
  Press p;
  const int n = 1000;
  p.o.y.setZero(n, 6);
  for (int k = 0; k < n; ++k) {
    const double t = 0.01 * k;
    p.o.t_s.push_back(t);
    const double z = 0.5 + 0.2 * std::sin(2 * M_PI * 0.7 * t) + 0.1 * std::sin(2 * M_PI * 2.3 * t + 1.0);
    p.o.y(k, 2) = K * (h - z) + noise(rng);
    p.z_read.push_back(z + read(rng));
  }
  return p;
}

// Errors in a regressor attenuate its slope by var(e) / var(regressor) and move the intercept: the
// correction removes that bias over many seeds. Rule written before the run: the least-squares
// K is more than 10 standard errors (of the mean over the seeds) low, proving the bias is there; the
// corrected K and h are within 3 of the truth.
TEST(Engine, ErrorsInAMeasuredRegressorAreCorrectedToFirstOrderOverManySeeds) {
  const double K = 2.0, h = 1.0, e = 0.02;  // var(e) / var(h - z) = 0.0004 / 0.025: K 1.6 % low
  const int seeds = 100;
  std::vector<double> k_lsq, k_corr, h_corr;
  for (int s = 0; s < seeds; ++s) {
    const Press p = press_run(5100 + static_cast<unsigned>(s), K, h, e);
    PressFamily m(p.z_read, e);
    const Fit f = fit(m, p.o, all(p.o.size()));
    const ErrorsInVariablesBias eiv = errors_in_variables_bias(m, p.o, f, all(p.o.size()), 1);
    ASSERT_TRUE(eiv.applied) << eiv.why_not;
    EXPECT_LT(eiv.mismatch, 1e-6);  // the score is quadratic in z: the ±2σ curvature is the ±σ one
    const Eigen::VectorXd& b = eiv.bias;
    ASSERT_EQ(b.size(), 2);
    k_lsq.push_back(f.theta(0) - K);
    k_corr.push_back(f.theta(0) - b(0) - K);
    h_corr.push_back(f.phi(0) - b(1) - h);
  }
  const auto [kl, kl_se] = hil::test::mean_and_se(k_lsq);
  const auto [kc, kc_se] = hil::test::mean_and_se(k_corr);
  const auto [hc, hc_se] = hil::test::mean_and_se(h_corr);
  std::cout << "K: least squares " << kl << " (se " << kl_se << "), corrected " << kc << " (se " << kc_se << "); h corrected " << hc
            << " (se " << hc_se << ")\n";
  EXPECT_LT(kl, -10 * kl_se) << "least squares " << kl << " (se " << kl_se << ")";
  EXPECT_LT(std::abs(kc), 3 * kc_se) << "corrected K " << kc << " (se " << kc_se << ")";
  EXPECT_LT(std::abs(hc), 3 * hc_se) << "corrected h " << hc << " (se " << hc_se << ")";
}

TEST(Engine, ScoreReportsTheCorrectedValuesAndWhatTheyAreCorrectedFor) {
  const Press p = press_run(77, 2.0, 1.0, 0.02);
  PressFamily m(p.z_read, 0.02);
  const Score s = score(m, p.o);
  CvOptions off;
  off.errors_in_variables = false;
  const Score raw = score(m, p.o, off);
  const Eigen::VectorXd b = errors_in_variables_bias(m, p.o, s.full, all(p.o.size())).bias;
  ASSERT_EQ(s.errors_in_variables.size(), 1u);
  EXPECT_THAT(s.errors_in_variables[0], HasSubstr("z"));
  EXPECT_TRUE(raw.errors_in_variables.empty());
  for (std::size_t i = 0; i < 2; ++i) {
    const Reported& r = s.full.reported[i];
    const Reported& q = raw.full.reported[i];
    EXPECT_NEAR(r.errors_in_variables, -b(static_cast<Eigen::Index>(i)), 1e-12) << r.name;
    EXPECT_NE(r.errors_in_variables, 0.0) << r.name;
    EXPECT_DOUBLE_EQ(r.value, q.value + r.errors_in_variables) << r.name;
    EXPECT_EQ(q.errors_in_variables, 0.0);
    EXPECT_DOUBLE_EQ(r.std, q.std) << r.name;
  }
  // The fit itself stays the least-squares optimum.
  EXPECT_EQ(s.full.theta(0), raw.full.theta(0));
  // No declared error, no correction.
  PressFamily exact(p.z_read, 0.0);
  const ErrorsInVariablesBias none = errors_in_variables_bias(exact, p.o, s.full, all(p.o.size()));
  EXPECT_FALSE(none.applied);
  EXPECT_TRUE(none.bias.isZero(0.0));
}

/// y_z = θ where the measured z exceeds 0.5, else 0: a design that switches with z, whose score
/// is not smooth at any error's scale.
class SwitchFamily : public ModelFamily {
 public:
  SwitchFamily(std::vector<double> z, double error, double shift = 0.0) : z_(std::move(z)), error_(error), shift_(shift) {}
  std::string name() const override { return "switch"; }
  std::vector<Param> linear() const override { return {{"level", "N", 1.0, false}}; }
  void design(const Eigen::VectorXd&, Eigen::MatrixXd& A, FamilyData&) const override {
    A.setZero(static_cast<Eigen::Index>(6 * z_.size()), 1);
    for (std::size_t k = 0; k < z_.size(); ++k) A(static_cast<Eigen::Index>(6 * k) + 2, 0) = z_[k] + shift_ > 0.5 ? 1.0 : 0.0;
  }
  std::vector<ErrorInVariable> errors_in_variables() const override {
    return {{"z", error_, [this](double by) { return std::make_unique<SwitchFamily>(z_, 0.0, shift_ + by); }}};
  }

 private:
  std::vector<double> z_;
  double error_, shift_;
};

TEST(Engine, AScoreThatSwitchesWithinTheErrorsScaleIsNotCorrected) {
  const Press p = press_run(78, 2.0, 1.0, 0.02);
  for (const auto& q : {p.z_read}) {
    SwitchFamily m(q, 0.02);
    Observations o = p.o;
    for (std::size_t k = 0; k < q.size(); ++k) o.y(static_cast<Eigen::Index>(k), 2) = q[k] > 0.5 ? 3.0 : 0.0;
    const Score s = score(m, o);
    const ErrorsInVariablesBias eiv = errors_in_variables_bias(m, o, s.full, all(o.size()));
    EXPECT_FALSE(eiv.applied) << eiv.mismatch;
    EXPECT_GT(eiv.mismatch, kErrorsInVariablesMismatch);
    EXPECT_THAT(eiv.why_not, HasSubstr("not smooth"));
    EXPECT_TRUE(eiv.bias.isZero(0.0));
    ASSERT_EQ(s.errors_in_variables.size(), 1u);
    EXPECT_THAT(s.errors_in_variables[0], HasSubstr("not corrected"));
    EXPECT_EQ(s.full.reported[0].errors_in_variables, 0.0);
  }
}

// The press bench holds its depth at one reported z for 151 of its 325 samples (on the grid: no
// error there at all): z is not declared as an error in the variables, so nothing is corrected
// along it (the correction gave its stiffness exponent 3.7 std of bias before the hold rule).
TEST(ContactFamily, AnAxisTheRunHoldsIsNotDeclaredAsAnErrorInTheVariables) {
  const auto r = test::scene_run("press_slide");
  const ContactData d = test::hidden_contact_data(r, "", 1);
  ASSERT_GT(d.position_quantum_m(2), 0.0);
  const ContactFamily f(d, {});
  for (const auto& v : f.errors_in_variables()) EXPECT_THAT(v.variable, ::testing::Not(HasSubstr("world z"))) << v.variable;
}

/// y_c = a + b s_c x_k: a family linear in a regressor x given per sample, seen at the scale s_c
/// by component c (1 on every component unless given).
class Affine : public ModelFamily {
 public:
  Affine(const Observations& o, std::string name, std::function<double(std::size_t)> x, std::function<double(int)> scale = nullptr)
      : o_(o), name_(std::move(name)), x_(std::move(x)), scale_(std::move(scale)) {}
  std::string name() const override { return name_; }
  std::vector<Param> linear() const override { return {{"a", "", 1, false}, {"b", "", 1, true}}; }
  void design(const Eigen::VectorXd&, Eigen::MatrixXd& A, FamilyData&) const override {
    A.setZero(static_cast<Eigen::Index>(6 * o_.size()), 2);
    for (std::size_t k = 0; k < o_.size(); ++k)
      for (int c = 0; c < 6; ++c) {
        A(static_cast<Eigen::Index>(6 * k) + c, 0) = 1.0;
        A(static_cast<Eigen::Index>(6 * k) + c, 1) = (scale_ ? scale_(c) : 1.0) * x_(k);
      }
  }

 private:
  const Observations& o_;
  std::string name_;
  std::function<double(std::size_t)> x_;
  std::function<double(int)> scale_;
};

/// y_c = a + b (t - 2) with AR(1) noise of correlation 0.98 (a slowly wandering error, the kind a
/// model misfit leaves): the asymptotic interval is far too narrow; the folds' spread is not.
/// (Measured over these 60 seeds: 56 and 53 covered with the folds, 38 without.)
class Line : public Affine {
 public:
  /// \param shift moves the slope's regressor: t - 2 + shift
  explicit Line(const Observations& o, double shift = 0.0)
      : Affine(o, "line", [&o, shift](std::size_t k) { return o.t_s[k] - 2.0 + shift; }) {}
};

TEST(Engine, IntervalsCoverTheTruthUnderStronglyCorrelatedErrorsOverManySeeds) {
  const int seeds = 60;
  const double rho = 0.98;  // correlation length 50 samples, beyond the Bartlett window's 20 lags
  int covered_a = 0, covered_b = 0, covered_a_asymptotic = 0;
  for (int seed = 0; seed < seeds; ++seed) {
    std::mt19937 rng(1000 + static_cast<unsigned>(seed));
    std::normal_distribution<double> g(0, 1);
    Observations o;
    const int n = 400;
    o.y.resize(n, 6);
    Eigen::Matrix<double, 6, 1> e = Eigen::Matrix<double, 6, 1>::Zero();
    for (int c = 0; c < 6; ++c) e(c) = g(rng);  // stationary start
    for (int k = 0; k < n; ++k) {
      o.t_s.push_back(0.01 * k);
      for (int c = 0; c < 6; ++c) {
        e(c) = rho * e(c) + std::sqrt(1 - rho * rho) * g(rng);
        o.y(k, c) = 1.0 + 0.5 * (o.t_s.back() - 2.0) + 0.1 * e(c);
      }
    }
    Line m(o);
    const Score s = score(m, o);
    for (const auto& r : s.full.reported) {
      const double truth = r.name == "a" ? 1.0 : 0.5;
      const bool in = std::abs(r.value - truth) <= 1.96 * r.std;
      EXPECT_GE(r.std, r.std_folds);  // correlated over a fifth of the run: too few blocks for the sandwich alone
      EXPECT_FALSE(r.sandwich);
      if (r.name == "a") {
        covered_a += in;
        // The asymptotic std alone: the std without the folds' (Bartlett-inflated, 20 lags).
        const double asym = std::sqrt(std::max(0.0, s.full.cov(0, 0)));
        covered_a_asymptotic += std::abs(r.value - truth) <= 1.96 * asym;
      } else {
        covered_b += in;
      }
    }
  }
  EXPECT_GE(covered_a, 0.85 * seeds) << covered_a << " of " << seeds;
  EXPECT_GE(covered_b, 0.85 * seeds) << covered_b << " of " << seeds;
  // The white-noise formula would not have covered: the test can tell the two apart.
  EXPECT_LT(covered_a_asymptotic, 0.85 * seeds) << covered_a_asymptotic << " of " << seeds;
}

/// y_c = a + b x(t), x a bump of height 1 inside the run's second fifth and 0.1 elsewhere: one block
/// carries most of what there is to know about b.
class Patch : public Affine {
 public:
  explicit Patch(const Observations& o)
      : Affine(o, "patch", [&o](std::size_t k) { return x(o.t_s[k], o.t_s.back() + (o.t_s[1] - o.t_s[0])); }) {}
  static double x(double t_s, double duration_s) {
    const double u = t_s / duration_s;
    return u >= 0.2 && u < 0.4 ? std::sin(M_PI * (u - 0.2) / 0.2) : 0.1 * std::sin(2 * M_PI * 3 * u);
  }
};

/// n samples at 100 Hz of 1 + 0.5 x(k) on every component, white noise of std 0.1 from `seed`.
template <class F>
Observations bump_data(unsigned seed, int n, F x) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 0.1);
  Observations o;
  o.y.resize(n, 6);
  for (int k = 0; k < n; ++k) {
    o.t_s.push_back(0.01 * k);
    for (int c = 0; c < 6; ++c) o.y(k, c) = 1.0 + 0.5 * x(k) + g(rng);
  }
  return o;
}

TEST(Engine, OneInformativeBlockIsWeighedByTheSandwichNotSwampedByItsFold) {
  // White noise: the residuals are uncorrelated (40 sandwich blocks) and the model is linear, so
  // every fold lies on its linear prediction and the sandwich's std is taken. The fold without the
  // bump reads b with about ten times the others' error, and the jackknife's spread, which assumes
  // equally informative blocks, makes that one fold the interval (ACU 2a's damping; rule written
  // before the test ran: 85-99 % coverage as the issue's band, mean z² at least 0.5, the sandwich
  // taken every time and narrower than the folds' spread on average by at least 2).
  const int seeds = 60;
  int covered = 0, taken = 0;
  double z2 = 0.0, ratio = 0.0;
  for (int seed = 0; seed < seeds; ++seed) {
    const Observations o = bump_data(2000 + static_cast<unsigned>(seed), 500, [](int k) { return Patch::x(0.01 * k, 5.0); });
    const Patch m(o);
    const Score s = score(m, o);
    for (const auto& r : s.full.reported)
      if (r.name == "b") {
        const double z = (r.value - 0.5) / r.std;
        covered += std::abs(z) <= 1.96;
        z2 += z * z / seeds;
        taken += r.sandwich;
        ratio += r.std_folds / r.std / seeds;
        EXPECT_DOUBLE_EQ(r.std, r.std_sandwich);
        EXPECT_GE(r.sandwich_dof, kOneEventDof) << "a fifth of the run is more than one event";
      }
  }
  EXPECT_EQ(taken, seeds);
  EXPECT_GE(covered, 0.85 * seeds) << covered << " of " << seeds;
  EXPECT_LE(covered, 0.99 * seeds) << covered << " of " << seeds;
  EXPECT_GE(z2, 0.5);
  EXPECT_GE(ratio, 2.0) << "the folds' spread over the sandwich's std";
}

/// y_c = a + b x(k), x a bump of 10 samples at samples 100 and 300 of 400, 0 elsewhere: b is
/// informed by two of the sandwich's 40 blocks, and every fold's training samples hold one bump.
class TwoBumps : public Affine {
 public:
  explicit TwoBumps(const Observations& o) : Affine(o, "two bumps", [](std::size_t k) { return x(static_cast<int>(k)); }) {}
  static double x(int k) { return (k >= 100 && k < 110) || (k >= 300 && k < 310) ? std::sin(M_PI * (k % 100 + 0.5) / 10.0) : 0.0; }
};

TEST(Engine, AParameterInformedByTwoBlocksIsReportedWithTheModelsStdAndSaysSo) {
  // Two of the sandwich's 40 blocks inform b (the few stops that inform slow_slip's μ_s K). Each
  // fits its own residual about half way (leverage ~1/2), and two blocks are about one degree of
  // freedom: the plain sandwich (raw residuals, t of 39 degrees of freedom) read such a parameter
  // up to 40 times too narrow (family draw 36,621,358), and the leverage-corrected one, t-widened
  // at Bell-McCaffrey's ν ≈ 1.1, covered 200 of 200 (an independent numpy computation of the same
  // design put the statistic's 95 % point at Student's ν ≈ 1.7: conservative). With no degrees of
  // freedom to measure b's error from the residuals, its std is the model's, said as such (rule
  // written before the test ran: coverage 85-99 % over 200 seeds, model_based every time, the std
  // the asymptotic one, ν below kOneEventDof and equal to the sandwich's own for b, the sandwich's
  // std wider than the model's on average). With the folds' check on the model's std
  // (one_event_agrees): the two folds that each lose a bump fail it at 1 % each under the model,
  // so model_based on at least 95 % of the seeds (about 98 % expected), and where it fails the std
  // is at least the model's. This assertion was changed after the check, tried on a branch, gave
  // 198 of 200 against "every time": this design no longer tests the check blind.
  const int seeds = 200;
  int covered = 0, model = 0;
  double wider = 0.0;
  for (int seed = 0; seed < seeds; ++seed) {
    const Observations o = bump_data(5000 + static_cast<unsigned>(seed), 400, TwoBumps::x);
    const TwoBumps m(o);
    const Score s = score(m, o);
    ASSERT_EQ(s.full.sandwich_dof.size(), 2);
    for (const auto& r : s.full.reported)
      if (r.name == "b") {
        covered += std::abs(r.value - 0.5) <= 1.96 * r.std;
        model += r.model_based && !r.sandwich;
        EXPECT_LT(r.sandwich_dof, kOneEventDof);
        EXPECT_NEAR(r.sandwich_dof, s.full.sandwich_dof(1), 1e-6 * s.full.sandwich_dof(1));
        if (r.model_based) EXPECT_DOUBLE_EQ(r.std, r.std_asymptotic);
        else EXPECT_GE(r.std, r.std_asymptotic);
        wider += r.std_sandwich / r.std_asymptotic / seeds;
      }
  }
  std::cout << "b: " << covered << " of " << seeds << " covered, the sandwich's std " << wider << " times the model's\n";
  EXPECT_GE(model, 0.95 * seeds) << model << " of " << seeds;
  EXPECT_GE(covered, 0.85 * seeds) << covered << " of " << seeds;
  EXPECT_LE(covered, 0.99 * seeds) << covered << " of " << seeds;
  EXPECT_GT(wider, 1.0) << "the sandwich's std over the model's";
}

/// b x(k) with x a bump of 10 samples at 100..109 of 400 and a weak 0.1-amplitude sinusoid
/// elsewhere: one block carries most of b's information (ν ~ 1), the rest of the run knows b too.
class BumpAndWeakSignal : public Affine {
 public:
  explicit BumpAndWeakSignal(const Observations& o)
      : Affine(o, "bump and weak signal", [](std::size_t k) { return x(static_cast<int>(k)); }) {}
  static double x(int k) { return k >= 100 && k < 110 ? std::sin(M_PI * (k - 100 + 0.5) / 10.0) : 0.1 * std::sin(2 * M_PI * k / 37.0); }
};

/// 400 samples at 100 Hz of mean(k, c) plus white noise of std 0.1 from `seed` (drawn sample by
/// sample, component by component).
Observations noisy_samples(unsigned seed, const std::function<double(int, int)>& mean) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 0.1);
  Observations o;
  o.y.resize(400, 6);
  for (int k = 0; k < 400; ++k) {
    o.t_s.push_back(0.01 * k);
    for (int c = 0; c < 6; ++c) o.y(k, c) = mean(k, c) + g(rng);
  }
  return o;
}

TEST(Engine, AOneEventValueTheRestOfTheRunContradictsIsNotReportedWithTheModelsStd) {
  // Issue 32: on a trapezoidal delay draw the stop that carried slow slip carried τ too (ν 1.15),
  // misfit there, and the model's std put the truth 4.7 std away while the fold without the stop
  // read it. Here the bump's response is not the model's (1 + 0.5 x + 0.4 x², a form the line
  // lacks, in the bump only), so the bump pulls b while the weak signal elsewhere reads 0.5. Rule
  // written before the test ran: over 60 seeds, b is one event's (ν below kOneEventDof) every
  // time, model_based on at most 10 % of them, its interval covers 0.5 on at least 85 %; the
  // model's std alone would cover on at most 10 %.
  const int seeds = 60;
  int one_event = 0, model = 0, covered = 0, model_would = 0;
  for (int seed = 0; seed < seeds; ++seed) {
    const Observations o = noisy_samples(7000 + static_cast<unsigned>(seed), [](int k, int) {
      const double x = BumpAndWeakSignal::x(k);
      return 1.0 + 0.5 * x + (k >= 100 && k < 110 ? 0.4 * x * x : 0.0);
    });
    const BumpAndWeakSignal m(o);
    const Score s = score(m, o);
    for (const auto& r : s.full.reported)
      if (r.name == "b") {
        one_event += r.sandwich_dof > 0 && r.sandwich_dof < kOneEventDof;
        model += r.model_based;
        covered += std::abs(r.value - 0.5) <= 1.96 * r.std;
        model_would += std::abs(r.value - 0.5) <= 1.96 * r.std_asymptotic;
      }
  }
  std::cout << "b: one event " << one_event << ", model-based " << model << ", covered " << covered << " (" << model_would
            << " with the model's std) of " << seeds << "\n";
  EXPECT_EQ(one_event, seeds);
  EXPECT_LE(model, 0.10 * seeds);
  EXPECT_GE(covered, 0.85 * seeds);
  EXPECT_LE(model_would, 0.10 * seeds) << "the case does not test the check";
}

/// y = a + b x(k) s_c: three bumps (the first carries most of b), nothing elsewhere; the normal
/// group's components (2, 3, 4) see x at a third of the scale (s_c = 1/3) of the others'.
/// `groups`: whether the family declares the two groups (ModelFamily::component_groups).
class ThreeBumpsTwoGroups : public Affine {
 public:
  ThreeBumpsTwoGroups(const Observations& o, bool groups)
      : Affine(
            o, "three bumps, two groups", [](std::size_t k) { return x(static_cast<int>(k)); },
            [](int c) { return c >= 2 && c <= 4 ? 1.0 / 3.0 : 1.0; }),
        groups_(groups) {}
  std::vector<ComponentGroup> component_groups() const override {
    if (!groups_) return {};
    return {{"normal", {2, 3, 4}}, {"tangential", {0, 1, 5}}};
  }
  static double x(int k) {
    const auto bump = [k](int start, double amplitude) {
      return k >= start && k < start + 10 ? amplitude * std::sin(M_PI * (k - start + 0.5) / 10.0) : 0.0;
    };
    return bump(100, 1.0) + bump(250, 0.35) + bump(330, 0.35);
  }

 private:
  bool groups_;
};

TEST(Engine, AOneEventValueOneGroupOfComponentsContradictsReachesAcrossThatGroupsReading) {
  // Issue 32: on a trapezoidal delay draw one stop's friction torque carried τ (ν 1.19) and read it
  // 32 model std late; every fold keeps some stop with the same misfit, so the folds agreed with
  // it, while fz, mx and my alone read the truth. Here the tangential components respond to
  // every bump with b = 0.9, the normal ones with the truth, 0.5: the model (one b) is wrong where
  // the tangential group looks, and the folds cannot see it. Rule written before the test ran:
  // over 60 seeds, b is one event's on at least 90 %; with the groups declared, a group
  // contradicts it (components_disagree) on at least 90 %, model_based on at most 10 %, its
  // interval covers 0.5 on at least 85 %; without them it is covered on at most 10 % (the
  // case tests the groups' check, not the folds').
  const int seeds = 60;
  int one_event = 0, disagree = 0, model = 0, covered = 0, covered_without = 0;
  for (int seed = 0; seed < seeds; ++seed) {
    const Observations o = noisy_samples(7100 + static_cast<unsigned>(seed), [](int k, int c) {
      const double x = ThreeBumpsTwoGroups::x(k);
      return 1.0 + (c >= 2 && c <= 4 ? 0.5 * x / 3.0 : 0.9 * x);
    });
    const ThreeBumpsTwoGroups with(o, true), without(o, false);
    const Score s = score(with, o), s0 = score(without, o);
    for (const auto& r : s.full.reported)
      if (r.name == "b") {
        one_event += r.sandwich_dof > 0 && r.sandwich_dof < kOneEventDof;
        disagree += !r.components_disagree.empty() && r.std_components > 0 && r.std >= r.std_components;
        model += r.model_based;
        covered += std::abs(r.value - 0.5) <= 1.96 * r.std;
      }
    for (const auto& r : s0.full.reported)
      if (r.name == "b") {
        EXPECT_TRUE(r.components_disagree.empty());
        covered_without += std::abs(r.value - 0.5) <= 1.96 * r.std;
      }
  }
  std::cout << "b: one event " << one_event << ", a group disagrees " << disagree << ", model-based " << model << ", covered " << covered
            << " (" << covered_without << " without the groups) of " << seeds << "\n";
  EXPECT_GE(one_event, 0.90 * seeds);
  EXPECT_GE(disagree, 0.90 * seeds);
  EXPECT_LE(model, 0.10 * seeds);
  EXPECT_GE(covered, 0.85 * seeds);
  EXPECT_LE(covered_without, 0.10 * seeds) << "the case does not test the groups' check";
}

/// A family whose component groups name what the observation does not have.
class BadGroups : public ThreeBumpsTwoGroups {
 public:
  BadGroups(const Observations& o, std::vector<ComponentGroup> groups) : ThreeBumpsTwoGroups(o, true), groups_(std::move(groups)) {}
  std::vector<ComponentGroup> component_groups() const override { return groups_; }

 private:
  std::vector<ComponentGroup> groups_;
};

TEST(Engine, AComponentGroupOutsideTheObservationIsRefusedByName) {
  const Observations o = noisy_samples(7000, [](int k, int) { return 1.0 + ThreeBumpsTwoGroups::x(k); });
  auto message = [&](std::vector<ModelFamily::ComponentGroup> groups) {
    try {
      score(BadGroups(o, std::move(groups)), o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_THAT(message({{"normal", {2, 3, 4}}, {"twist", {0, 6}}}), HasSubstr("component group 'twist' names component 6"));
  EXPECT_THAT(message({{"normal", {2, -1}}}), HasSubstr("names component -1"));
  EXPECT_THAT(message({{"empty", {}}}), HasSubstr("component group 'empty' has no components"));
  EXPECT_EQ(message({{"normal", {2, 3, 4}}, {"tangential", {0, 1, 5}}}), "accepted");
}

/// 400 samples at 100 Hz of 1 + 0.5 (x + bend x²), x = t - 2, on every component, with white noise
/// of std 0.01 from `seed`.
Observations line_data(unsigned seed, double bend = 0.0) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1);
  Observations o;
  for (int k = 0; k < 400; ++k) o.t_s.push_back(0.01 * k);
  o.y.resize(400, 6);
  for (int k = 0; k < 400; ++k) {
    const double x = o.t_s[static_cast<std::size_t>(k)] - 2.0;
    for (int c = 0; c < 6; ++c) o.y(k, c) = 1.0 + 0.5 * (x + bend * x * x) + 0.01 * g(rng);
  }
  return o;
}

/// The line with model forms: the time origin moved by -0.3 and +0.2 moves the intercept by
/// -b shift and leaves the slope alone.
class LineWithForms : public Line {
 public:
  explicit LineWithForms(const Observations& o) : Line(o), o_(o) {}
  std::vector<ModelForm> model_forms() const override {
    std::vector<ModelForm> out;
    for (const double s : {-0.3, 0.2}) out.push_back({"origin moved by " + std::to_string(s), std::make_unique<Line>(o_, s)});
    return out;
  }

 private:
  const Observations& o_;
};

TEST(Engine, ModelFormsWidenTheIntervalsByTheLargestShiftAndKeepThePnr) {
  const Observations o = line_data(5);
  const Line plain(o);
  const LineWithForms with(o);
  const Score a = score(plain, o), b = score(with, o);
  CvOptions off;
  off.model_forms = false;
  const Score c = score(with, o, off);
  ASSERT_EQ(a.full.reported.size(), 2u);
  ASSERT_EQ(b.full.reported.size(), 2u);
  EXPECT_TRUE(a.model_forms.empty());
  EXPECT_TRUE(c.model_forms.empty());
  ASSERT_EQ(b.model_forms.size(), 2u);
  EXPECT_THAT(b.model_forms[0], HasSubstr("origin moved"));
  for (std::size_t i = 0; i < 2; ++i) {
    const Reported &ra = a.full.reported[i], &rb = b.full.reported[i];
    EXPECT_EQ(c.full.reported[i].std, ra.std);
    EXPECT_EQ(ra.std_model_form, 0.0);
    EXPECT_NEAR(rb.value, ra.value, 1e-12);
    EXPECT_NEAR(rb.pnr(), ra.pnr(), 1e-9 * ra.pnr());
    if (ra.name == "a") {
      // The intercept moves by -b shift: the largest shift is 0.3 b = 0.15, uniform over ± 0.15.
      EXPECT_NEAR(rb.std_model_form, 0.3 * 0.5 / std::sqrt(3.0), 2e-3);
      EXPECT_NEAR(rb.std, std::hypot(ra.std, rb.std_model_form), 1e-12);
      EXPECT_GT(rb.std, 10 * ra.std);
    } else {
      EXPECT_LT(rb.std_model_form, 1e-9);  // the slope does not depend on the origin
      EXPECT_NEAR(rb.std, ra.std, 1e-9);
    }
  }
}

/// The line whose slope's regressor bends: t - 2 + curve (t - 2)².
class BentLine : public Line {
 public:
  BentLine(const Observations& o, double curve) : Line(o), o_(o), curve_(curve) {}
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData& data) const override {
    Line::design(phi, A, data);
    for (std::size_t k = 0; k < o_.size(); ++k)
      for (int c = 0; c < 6; ++c) A(static_cast<Eigen::Index>(6 * k) + c, 1) += curve_ * std::pow(o_.t_s[k] - 2.0, 2);
  }

 private:
  const Observations& o_;
  double curve_;
};

/// Forms the run can decide: an origin moved (the same fit), a slight bend (within the noise) and
/// a strong one (far outside it).
class LineWithDecidableForms : public Line {
 public:
  explicit LineWithDecidableForms(const Observations& o) : Line(o), o_(o) {}
  std::vector<ModelForm> model_forms() const override {
    std::vector<ModelForm> out;
    out.push_back({"origin moved by 0.2", std::make_unique<Line>(o_, 0.2), true});
    out.push_back({"slightly bent", std::make_unique<BentLine>(o_, 1e-5), true});
    out.push_back({"strongly bent", std::make_unique<BentLine>(o_, 0.3), true});
    return out;
  }

 private:
  const Observations& o_;
};

TEST(Engine, AModelFormTheRunRejectsWidensNothing) {
  const Observations o = line_data(6);
  const Score s = score(LineWithDecidableForms(o), o);
  ASSERT_EQ(s.model_forms.size(), 2u);
  EXPECT_EQ(s.model_forms[0], "origin moved by 0.2");
  EXPECT_EQ(s.model_forms[1], "slightly bent");
  ASSERT_EQ(s.model_forms_rejected.size(), 1u);
  EXPECT_THAT(s.model_forms_rejected[0], HasSubstr("strongly bent"));
  EXPECT_THAT(s.model_forms_rejected[0], HasSubstr("long-run residual variances above"));
  // The strong bend moves the intercept more than the origin's 0.2 b = 0.1: not counted.
  const Fit bent = fit(BentLine(o, 0.3), o, [] {
    std::vector<int> all(400);
    std::iota(all.begin(), all.end(), 0);
    return all;
  }());
  for (const auto& r : s.full.reported)
    if (r.name == "a") {
      EXPECT_GT(std::abs(bent.theta(0) - r.value), 0.15);
      EXPECT_NEAR(r.std_model_form, 0.2 * 0.5 / std::sqrt(3.0), 2e-3);
    }
  // Without the flag the same strong bend is covered, and widens the intercept's interval by it.
  class Undecided : public Line {
   public:
    explicit Undecided(const Observations& o) : Line(o), o_(o) {}
    std::vector<ModelForm> model_forms() const override {
      std::vector<ModelForm> out;
      out.push_back({"strongly bent", std::make_unique<BentLine>(o_, 0.3)});
      return out;
    }

   private:
    const Observations& o_;
  };
  const Score u = score(Undecided(o), o);
  EXPECT_TRUE(u.model_forms_rejected.empty());
  for (const auto& r : u.full.reported) {
    if (r.name == "a") {
      EXPECT_NEAR(r.std_model_form, std::abs(bent.theta(0) - r.value) / std::sqrt(3.0), 1e-6);
    }
  }
}

TEST(Engine, AModelFormThatFitsBetterOnlyWidens) {
  // The data bend as BentLine(0.3) does; the model is straight, its decided form bent: the form
  // fits far better, and still the values are the model's, the interval widened by the shift.
  const Observations o = line_data(7, 0.3);
  class Straight : public Line {
   public:
    explicit Straight(const Observations& obs) : Line(obs), o_(obs) {}
    std::vector<ModelForm> model_forms() const override {
      std::vector<ModelForm> out;
      out.push_back({"bent", std::make_unique<BentLine>(o_, 0.3), true});
      return out;
    }

   private:
    const Observations& o_;
  };
  const Score s = score(Straight(o), o);
  EXPECT_TRUE(s.model_forms_rejected.empty());
  ASSERT_EQ(s.model_forms.size(), 1u);
  std::vector<int> all(400);
  std::iota(all.begin(), all.end(), 0);
  const Fit straight = fit(Line(o), o, all), bent = fit(BentLine(o, 0.3), o, all);
  EXPECT_LT(bent.rss, 0.1 * straight.rss);
  for (const auto& r : s.full.reported) {
    const Eigen::Index j = r.name == "a" ? 0 : 1;
    EXPECT_NEAR(r.value, straight.theta(j), 1e-9) << r.name;
    EXPECT_NEAR(r.std_model_form, std::abs(bent.theta(j) - straight.theta(j)) / std::sqrt(3.0), 1e-6) << r.name;
  }
}

TEST(Engine, AModelFormThatMayBeTakenGivesItsValuesWhereTheRunPrefersIt) {
  // As above, the form flagged taken_when_preferred: where the data bend, its values are reported
  // (the interval still widened by the shift to the model's); where they do not, the model's.
  class Straight : public Line {
   public:
    explicit Straight(const Observations& obs) : Line(obs), o_(obs) {}
    std::vector<ModelForm> model_forms() const override {
      std::vector<ModelForm> out;
      out.push_back({"bent", std::make_unique<BentLine>(o_, 0.3), true, {}, true});
      return out;
    }

   private:
    const Observations& o_;
  };
  std::vector<int> all(400);
  std::iota(all.begin(), all.end(), 0);
  for (const bool bends : {true, false}) {
    const Observations o = line_data(7, bends ? 0.3 : 0.0);
    const Score s = score(Straight(o), o);
    const Fit straight = fit(Line(o), o, all), bent = fit(BentLine(o, 0.3), o, all);
    if (bends) {
      EXPECT_THAT(s.model_form_taken, HasSubstr("bent"));
      EXPECT_THAT(s.model_form_taken, HasSubstr("long-run residual variances below"));
    } else {
      EXPECT_EQ(s.model_form_taken, "");  // the bend rejected: it fits far worse
    }
    for (const auto& r : s.full.reported) {
      const Eigen::Index j = r.name == "a" ? 0 : 1;
      EXPECT_NEAR(r.value, (bends ? bent : straight).theta(j), 1e-9) << r.name;
      if (bends) {
        EXPECT_NEAR(r.std_model_form, std::abs(bent.theta(j) - straight.theta(j)) / std::sqrt(3.0), 1e-6) << r.name;
      }
    }
  }
}

TEST(Engine, WeightedModelFormsAverageTheValuesByTheRunsLikelihoods) {
  // A slightly bent form flagged weighted (issue 32: the friction's lever): the values are the
  // model's and the form's averaged with weights 1 : exp(-excess / 2), excess the form's weighted
  // RSS less the model's in long-run residual variances. Data bent by a few ten-thousandths put the
  // excess on both sides of zero; at least one bend must be preferred by less than the margin that
  // takes a form (there the old rule reported the model's values alone) and one by more.
  class Straight : public Line {
   public:
    explicit Straight(const Observations& obs) : Line(obs), o_(obs) {}
    std::vector<ModelForm> model_forms() const override {
      std::vector<ModelForm> out;
      out.push_back({"bent a little", std::make_unique<BentLine>(o_, 1e-3), false, {}, true, true});
      return out;
    }

   private:
    const Observations& o_;
  };
  std::vector<int> all(400);
  std::iota(all.begin(), all.end(), 0);
  bool undecided = false, taken = false;
  for (const double bend : {0.0, 4e-4, 6e-4, 7e-4, 8e-4, 1e-3, 1.5e-3}) {
    const Observations o = line_data(11, bend);
    const Score s = score(Straight(o), o);
    const Fit straight = fit(Line(o), o, all), bent = fit(BentLine(o, 1e-3), o, all);
    const double excess = (bent.rss - straight.rss) / (s.full.sigma2 * s.full.variance_inflation);
    const double w = std::exp(-excess / 2) / (1.0 + std::exp(-excess / 2));
    undecided = undecided || (excess < -1.0 && excess > -kFormRejection);
    taken = taken || excess < -kFormRejection;
    ASSERT_EQ(s.model_form_weights.size(), 2u) << bend;
    EXPECT_THAT(s.model_form_weights[1], HasSubstr("bent a little"));
    EXPECT_EQ(s.model_form_taken.empty(), !(excess < -kFormRejection)) << bend << ": excess " << excess;
    for (const auto& r : s.full.reported) {
      const Eigen::Index j = r.name == "a" ? 0 : 1;
      EXPECT_NEAR(r.value, (1 - w) * straight.theta(j) + w * bent.theta(j), 1e-9 * (1 + std::abs(straight.theta(j))))
          << r.name << " " << bend;
      EXPECT_NEAR(r.std_model_form, std::abs(bent.theta(j) - straight.theta(j)) / std::sqrt(3.0), 1e-6) << r.name;
    }
  }
  EXPECT_TRUE(undecided);
  EXPECT_TRUE(taken);
}

TEST(Engine, AScreenAfterTheFullFitSkipsTheFolds) {
  const auto o = sine_data(1.23, 2.5, 0.4, 0.05, 2);
  SineFamily m(o);
  CvOptions cv;
  int calls = 0;
  cv.screen = [&calls](const Score& s) {
    ++calls;
    return s.bic < 0 ? std::string("test screen") : std::string();
  };
  const Score s = score(m, o, cv);
  EXPECT_EQ(calls, 1);
  EXPECT_FALSE(s.held_out());
  EXPECT_EQ(s.screened, "test screen");
  EXPECT_TRUE(std::isnan(s.cv_error));
  EXPECT_EQ(s.cv_prediction.size(), 0);
  EXPECT_NEAR(s.full.phi(0), 1.23, 1e-2);  // the full fit and its statistics are still there
  EXPECT_TRUE(s.identifiable);
  cv.screen = [](const Score&) { return std::string(); };
  const Score t = score(m, o, cv);
  EXPECT_TRUE(t.held_out());
  EXPECT_NEAR(t.cv_error, 0.05, 0.01);
}

/// y_c(t) = θ_0 exp(-a t) sin(2π f t + c) + θ_1, φ = (a, f): two coupled nonlinear parameters.
class DecayFamily : public ModelFamily {
 public:
  explicit DecayFamily(const Observations& o) : o_(o) {}
  std::string name() const override { return "decay"; }
  std::vector<Param> linear() const override { return {{"amplitude", "", 1, false}, {"offset", "", 1, true}}; }
  std::vector<Param> nonlinear() const override { return {{"rate", "1/s", 0.1, true, 0, 10}, {"frequency", "Hz", 0.1, true, 0.1, 5}}; }
  std::vector<Eigen::VectorXd> starts() const override { return {Eigen::Vector2d(0.2, 1.15)}; }
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData&) const override {
    A.setZero(static_cast<Eigen::Index>(6 * o_.size()), 2);
    for (std::size_t k = 0; k < o_.size(); ++k)
      for (int c = 0; c < 6; ++c) {
        A(static_cast<Eigen::Index>(6 * k) + c, 0) = std::exp(-phi(0) * o_.t_s[k]) * std::sin(2 * M_PI * phi(1) * o_.t_s[k] + c);
        A(static_cast<Eigen::Index>(6 * k) + c, 1) = 1.0;
      }
  }

 private:
  const Observations& o_;
};

/// n samples at 100 Hz, y(k, c) = f(k, t_k, c).
template <class F>
Observations noiseless(int n, F f) {
  Observations o;
  o.y.resize(n, 6);
  for (int k = 0; k < n; ++k) {
    o.t_s.push_back(0.01 * k);
    for (int c = 0; c < 6; ++c) o.y(k, c) = f(k, o.t_s.back(), c);
  }
  return o;
}

TEST(Engine, SecantUpdatesReachTheSameOptimumWithFewerDesigns) {
  const Observations o = noiseless(400,
                                   [](int, double t, int c) { return 2.0 * std::exp(-0.5 * t) * std::sin(2 * M_PI * 1.23 * t + c) + 0.3; });
  DecayFamily m(o);
  FitOptions fd, secant;
  fd.secant_updates = 0;
  fd.tolerance = secant.tolerance = 1e-12;
  const Fit a = fit(m, o, all(o.size()), fd);
  const Fit b = fit(m, o, all(o.size()), secant);
  for (const Fit* f : {&a, &b}) {
    EXPECT_TRUE(f->converged);
    EXPECT_NEAR(f->phi(0), 0.5, 1e-6);
    EXPECT_NEAR(f->phi(1), 1.23, 1e-6);
    EXPECT_NEAR(f->theta(0), 2.0, 1e-5);
  }
  EXPECT_LT(b.evaluations, a.evaluations);
}

/// The sine plus, with `with_step`, a step θ_2 H(t - t_e) at a nonlinear event time t_e. Its
/// folds' models drop the step (as a rest-change search may find no event in a training set), so
/// a fold's φ has fewer entries than the full fit's.
class SineStepFamily : public ModelFamily {
 public:
  SineStepFamily(const Observations& o, bool with_step) : o_(o), step_(with_step) {}
  std::string name() const override { return step_ ? "sine+step" : "sine"; }
  std::vector<Param> linear() const override {
    std::vector<Param> p{{"amplitude", "", 1, false}, {"offset", "", 1, true}};
    if (step_) p.push_back({"step", "", 1, true});
    return p;
  }
  std::vector<Param> nonlinear() const override {
    std::vector<Param> p{{"frequency", "Hz", 0.1, true, 0.1, 5}};
    if (step_) p.push_back({"event_s", "s", 0.1, true, 0.0, 4.0});
    return p;
  }
  std::vector<Eigen::VectorXd> starts() const override {
    Eigen::VectorXd s = Eigen::VectorXd::Constant(step_ ? 2 : 1, 1.2);
    if (step_) s(1) = 2.0;
    return {s};
  }
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData&) const override {
    A.setZero(static_cast<Eigen::Index>(6 * o_.size()), step_ ? 3 : 2);
    for (std::size_t k = 0; k < o_.size(); ++k)
      for (int c = 0; c < 6; ++c) {
        const Eigen::Index row = static_cast<Eigen::Index>(6 * k) + c;
        A(row, 0) = std::sin(2 * M_PI * phi(0) * o_.t_s[k] + c);
        A(row, 1) = 1.0;
        if (step_) A(row, 2) = o_.t_s[k] >= phi(1) ? 1.0 : 0.0;
      }
  }
  std::unique_ptr<ModelFamily> restricted(const std::vector<int>&) const override {
    return step_ ? std::make_unique<SineStepFamily>(o_, false) : nullptr;
  }

 private:
  const Observations& o_;
  bool step_;
};

TEST(Engine, ASecondStepWhoseFoldsHaveOtherParametersStartsThemByName) {
  const auto o = sine_data(1.23, 2.5, 0.4, 0.05, 3);
  const SineStepFamily base(o, false), ext(o, true);
  const Score first = score(base, o);
  const Score second = score(ext, o, {}, &first);  // was a read past φ's bounds (ASan)
  ASSERT_EQ(second.full.phi.size(), 2);
  ASSERT_FALSE(second.fold_phi.empty());
  ASSERT_EQ(second.fold_phi.size(), second.fold_phi_names.size());
  for (std::size_t k = 0; k < second.fold_phi.size(); ++k) {
    ASSERT_EQ(second.fold_phi[k].size(), 1);
    EXPECT_EQ(second.fold_phi_names[k], std::vector<std::string>{"frequency"});
    EXPECT_NEAR(second.fold_phi[k](0), 1.23, 1e-2);
  }
  EXPECT_NEAR(second.cv_error, 0.05, 0.01);
}

TEST(Engine, TimeBlocksPartitionTheSamplesInOrder) {
  const auto b = time_blocks(103, 5);
  ASSERT_EQ(b.size(), 5u);
  int next = 0;
  for (const auto& blk : b)
    for (int k : blk) EXPECT_EQ(k, next++);
  EXPECT_EQ(next, 103);
}

TEST(Engine, ShiftedTimeBlocksWrapTheRunsEndOntoItsStart) {
  EXPECT_EQ(time_blocks(103, 5, 0.0), time_blocks(103, 5));
  const auto b = time_blocks(100, 5, 0.5);
  ASSERT_EQ(b.size(), 5u);
  std::vector<int> seen;
  for (const auto& blk : b) seen.insert(seen.end(), blk.begin(), blk.end());
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(seen, all(100));  // a partition
  std::vector<int> wrapped;
  for (int k = 0; k < 10; ++k) wrapped.push_back(k);
  for (int k = 90; k < 100; ++k) wrapped.push_back(k);
  EXPECT_EQ(b[0], wrapped);  // half a block at the start, half at the end
  for (std::size_t i = 1; i < 5; ++i) {
    ASSERT_EQ(b[i].size(), 20u);
    EXPECT_EQ(b[i].front(), 10 + 20 * static_cast<int>(i - 1));
  }
  for (double bad : {1.0, -0.1, std::numeric_limits<double>::quiet_NaN()})
    EXPECT_THAT([&] { time_blocks(100, 5, bad); },
                ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("is outside [0, 1) of a block")));
}

/// y_c = θ_c: each held-out prediction is the mean of the fold's training samples, which the test
/// computes on its own.
class MeanFamily : public ModelFamily {
 public:
  explicit MeanFamily(const Observations& o) : o_(o) {}
  std::string name() const override { return "mean"; }
  std::vector<Param> linear() const override {
    std::vector<Param> p;
    for (int c = 0; c < 6; ++c) p.push_back({"mean_" + std::to_string(c), "", 1, false});
    return p;
  }
  void design(const Eigen::VectorXd&, Eigen::MatrixXd& A, FamilyData&) const override {
    A.setZero(static_cast<Eigen::Index>(6 * o_.size()), 6);
    for (std::size_t k = 0; k < o_.size(); ++k)
      for (int c = 0; c < 6; ++c) A(static_cast<Eigen::Index>(6 * k) + c, c) = 1.0;
  }

 private:
  const Observations& o_;
};

TEST(Engine, RepeatedCvHoldsOutEveryShiftedBlockAndPoolsTheErrors) {
  const int n = 200;
  const Observations o = noiseless(n, [](int k, double, int c) { return 1e-4 * k * k + c + std::sin(0.37 * k * (c + 1)); });
  const MeanFamily m(o);
  CvOptions cv;
  cv.offsets = 4;
  const Score plain = score(m, o), repeated = score(m, o, cv);
  ASSERT_TRUE(plain.cv_shifted.empty());
  ASSERT_EQ(repeated.cv_shifted.size(), 3u);
  // The unshifted grid is plain blocked CV, its intervals included.
  EXPECT_EQ(repeated.cv_prediction, plain.cv_prediction);
  ASSERT_EQ(repeated.full.reported.size(), plain.full.reported.size());
  for (std::size_t i = 0; i < plain.full.reported.size(); ++i) EXPECT_EQ(repeated.full.reported[i].std, plain.full.reported[i].std);
  // Each shifted block is predicted by the mean of the samples farther than gap_samples from it.
  double pooled = 0.0;
  for (int shift = 0; shift < 4; ++shift) {
    const Eigen::MatrixXd& pred = shift == 0 ? repeated.cv_prediction : repeated.cv_shifted[static_cast<std::size_t>(shift - 1)];
    for (const auto& block : time_blocks(n, cv.folds, shift / 4.0)) {
      Eigen::Matrix<double, 1, 6> mean = Eigen::Matrix<double, 1, 6>::Zero();
      int count = 0;
      for (int k = 0; k < n; ++k) {
        const bool near = std::any_of(block.begin(), block.end(), [&](int h) { return std::abs(h - k) <= cv.gap_samples; });
        if (near) continue;
        mean += o.y.row(k);
        ++count;
      }
      mean /= count;
      for (int k : block) EXPECT_LT((pred.row(k) - mean).norm(), 1e-9) << "offset " << shift << "/4, sample " << k;
    }
    const double e = relative_error(o, pred, all(n));
    pooled += e * e / 4.0;
  }
  EXPECT_NEAR(repeated.cv_error, std::sqrt(pooled), 1e-12);
  EXPECT_NE(repeated.cv_error, plain.cv_error);
  // Scores held out on different grids are not compared.
  EXPECT_THAT([&] { paired_z(o, plain, repeated); },
              ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("held out on 1 and 4 grid offsets")));
  EXPECT_EQ(paired_z(o, repeated, repeated), 0.0);
}

/// y_c = θ (1 + φ b(t)), b = 1 on the samples `bump` and 0 elsewhere: φ is seen only there.
/// Its one start is φ = 0.5.
class Bump : public ModelFamily {
 public:
  Bump(const Observations& o, std::vector<int> bump) : o_(o), bump_(std::move(bump)) {}
  std::string name() const override { return "bump"; }
  std::vector<Param> linear() const override { return {{"level", "", 1, false}}; }
  std::vector<Param> nonlinear() const override { return {{"bump", "", 0.1, true, -5, 5}}; }
  std::vector<Eigen::VectorXd> starts() const override { return {Eigen::VectorXd::Constant(1, 0.5)}; }
  void design(const Eigen::VectorXd& phi, Eigen::MatrixXd& A, FamilyData&) const override {
    A.setOnes(static_cast<Eigen::Index>(6 * o_.size()), 1);
    for (int k : bump_) A.middleRows(6 * k, 6).array() += phi(0);
  }

 private:
  const Observations& o_;
  std::vector<int> bump_;
};

TEST(Engine, AFoldFixesWhatItsOwnTrainingSamplesCannotTell) {
  const int n = 200;
  const CvOptions cv;
  const auto blocks = time_blocks(n, cv.folds);
  const std::vector<int>& middle = blocks[2];
  const std::set<int> in(middle.begin(), middle.end());
  Observations o = noiseless(n,
                             [&](int k, double, int c) { return 2.0 * (1.0 + (in.count(k) ? 0.8 : 0.0)) + 0.001 * std::sin(0.9 * k + c); });
  const Bump m(o, middle);
  const Score s = score(m, o, cv);
  EXPECT_NEAR(s.full.phi(0), 0.8, 1e-3);  // the whole run sees the bump
  ASSERT_EQ(s.fold_phi.size(), blocks.size());
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    if (b == 2) {
      // Its training samples never see the bump: fixed at its nominal value, not left at the start
      // (the full fit's flags would have left it free there, at 0.5).
      EXPECT_EQ(s.fold_phi[b](0), 0.0);
      for (int k : middle) EXPECT_NEAR(s.cv_prediction(k, 0), 2.0, 1e-3) << "sample " << k;
    } else {
      EXPECT_NEAR(s.fold_phi[b](0), 0.8, 1e-3) << "fold " << b;
    }
  }
  // A fold whose fit runs to a bound fixes that parameter too, as the full fit does.
  Observations r;
  for (int k = 0; k < 200; ++k) r.t_s.push_back(0.02 * k);
  r.y.resize(200, 6);
  for (int k = 0; k < 200; ++k) r.y.row(k).setConstant(2.0 * (1.0 + 0.3 * r.t_s[static_cast<std::size_t>(k)]));
  const BoundedSlope bs(r);
  const Score t = score(bs, r, cv);
  ASSERT_TRUE(listed(t.full, "slope"));
  for (const auto& phi : t.fold_phi) EXPECT_EQ(phi(0), 0.0);
}

TEST(Engine, PairedZIsZeroForEqualPredictionsAndLargeForAConsistentGain) {
  const auto o = sine_data(1.0, 1.0, 0.0, 0.1, 3);
  Eigen::MatrixXd truth(static_cast<Eigen::Index>(o.size()), 6), off = truth;
  for (Eigen::Index k = 0; k < truth.rows(); ++k)
    for (int c = 0; c < 6; ++c) truth(k, c) = std::sin(2 * M_PI * o.t_s[static_cast<std::size_t>(k)] + c);
  off = truth.array() + 0.2;
  EXPECT_EQ(paired_z(o, truth, truth), 0.0);
  EXPECT_GT(paired_z(o, off, truth), 5.0);
  EXPECT_LT(paired_z(o, truth, off), -5.0);
}

// --- the contact family against the generator --------------------------------------------------

ContactData data_of(const test::SceneRun& r, const Effects& e, bool noise = false) {
  // Without noise the generator's twist is the truth's: the family takes its rates from it.
  return make_contact_data(r.scene, r.model.v_tm, test::measure(r, e, 1, noise), r.force_scale_n, r.moment_scale_nm,
                           noise ? RateSource::automatic : RateSource::twist);
}

TEST(ContactFamily, NominalDesignTimesThetaIsTheForwardSimulation) {
  const auto r = test::scene_run("press_slide");
  const auto d = data_of(r, {});
  ContactFamily m(d, {});
  Fit f;
  f.theta = r.model.theta();
  f.phi.resize(0);
  const Eigen::MatrixXd pred = predict(m, f, d.obs.size());
  cid::MindistWorkspace ws;
  std::vector<cid::ContactPoint> cs;
  double peak = 0;
  for (std::size_t k = 0; k < d.obs.size(); ++k) {
    const Eigen::Matrix<double, 6, 1> w = cid::plate_wrench(r.scene, r.model, r.scene.design(), r.kin[k], ws, cs);
    EXPECT_LT((pred.row(static_cast<Eigen::Index>(k)).transpose() - w).norm(), 1e-9 * (1 + w.norm())) << k;
    peak = std::max(peak, w.norm());
  }
  EXPECT_GT(peak, 10.0);  // the scene is in contact
}

TEST(FirstOrderLag, FollowsARampsAndASinusoidsClosedFormsAndRestartsOnANewRun) {
  // Two columns, three rows per sample: a ramp, a constant, a sinusoid on the rows.
  const double tau = 0.012, h = 0.001;
  const int n = 2000;
  std::vector<double> t(n);
  for (int k = 0; k < n; ++k) t[static_cast<std::size_t>(k)] = 0.3 + h * k;
  const double slope = 2.5, w = 2 * M_PI * 7.0;
  Eigen::MatrixXd A(3 * n, 2);
  for (int k = 0; k < n; ++k) {
    const double tk = t[static_cast<std::size_t>(k)];
    A(3 * k, 0) = slope * tk;
    A(3 * k, 1) = 4.0;
    A(3 * k + 1, 0) = std::sin(w * tk);
    A(3 * k + 1, 1) = -1.0;
    A(3 * k + 2, 0) = 0.0;
    A(3 * k + 2, 1) = slope * tk;
  }
  const Eigen::MatrixXd x = A;
  first_order_lag(t, tau, A);
  const double gain = 1 / std::hypot(1.0, w * tau), phase = std::atan(w * tau);
  for (int k = 0; k < n; ++k) {
    const double s = t[static_cast<std::size_t>(k)] - t[0];
    // The ramp from a settled start: y = x - slope τ (1 - e^(-s/τ)), exact for a first-order hold.
    const double ramp = x(3 * k, 0) - slope * tau * (1 - std::exp(-s / tau));
    EXPECT_NEAR(A(3 * k, 0), ramp, 1e-12 * (1 + std::abs(ramp))) << k;
    EXPECT_NEAR(A(3 * k + 2, 1), ramp, 1e-12 * (1 + std::abs(ramp))) << k;
    EXPECT_EQ(A(3 * k, 1), 4.0);
    EXPECT_EQ(A(3 * k + 1, 1), -1.0);
    EXPECT_EQ(A(3 * k + 2, 0), 0.0);
    // The sinusoid, settled after 10 τ: gain 1/√(1 + ω²τ²), phase -atan(ωτ); the hold's error O(ω²h²).
    if (s > 10 * tau) {
      EXPECT_NEAR(A(3 * k + 1, 0), gain * std::sin(w * t[static_cast<std::size_t>(k)] - phase), 2e-4) << k;
    }
  }
  // A lag of 0 or less changes nothing; a time that does not advance restarts the filter settled.
  Eigen::MatrixXd B = x;
  first_order_lag(t, 0.0, B);
  EXPECT_EQ(B, x);
  first_order_lag(t, -0.01, B);
  EXPECT_EQ(B, x);
  std::vector<double> two_runs = t;
  for (int k = n / 2; k < n; ++k) two_runs[static_cast<std::size_t>(k)] -= 0.5 * n * h;
  first_order_lag(two_runs, tau, B);
  EXPECT_EQ(B.row(3 * (n / 2)), x.row(3 * (n / 2)));
  EXPECT_NE(B.row(3 * (n / 2) - 3), x.row(3 * (n / 2) - 3));
  Eigen::MatrixXd odd(3 * n + 1, 2);
  EXPECT_THROW(first_order_lag(t, tau, odd), std::invalid_argument);
}

TEST(ContactFamily, TheDelaysLagFormFiltersTheDelayedDesignAndReportsTheSumOfBothLags) {
  const auto r = test::scene_run("press_slide");
  const auto d = data_of(r, {});
  EXPECT_EQ(ContactFamily(d, {"viscous_friction"}).model_forms().size(), 2u);  // no delay: no lag form
  const ContactFamily m(d, {"time_offset"});
  auto forms = m.model_forms();
  ASSERT_EQ(forms.size(), 3u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_FALSE(forms[i].decided_by_fit);
    EXPECT_FALSE(forms[i].refit_from);
  }
  EXPECT_TRUE(forms[2].decided_by_fit);
  const auto* lag = dynamic_cast<const ContactFamily*>(forms[2].model.get());
  ASSERT_NE(lag, nullptr);
  EXPECT_TRUE(lag->has_lag_filter());
  EXPECT_EQ(lag->model_forms().size(), 2u);  // no filter after a filter
  EXPECT_EQ(lag->friction_lever(), 0.0);
  EXPECT_THAT(forms[2].assumption, HasSubstr("first-order low-pass filter"));
  const auto nl = lag->nonlinear();
  ASSERT_EQ(nl.size(), 2u);
  EXPECT_EQ(nl[0].name, "time_offset_s");
  EXPECT_EQ(nl[1].name, ContactFamily::kLagFilter);
  EXPECT_EQ(nl[1].lower, 0.0);
  EXPECT_EQ(nl[1].upper, nl[0].upper);
  auto design = [](const ModelFamily& f, const Eigen::VectorXd& p) {
    Eigen::MatrixXd A;
    f.design(p, A);
    return A;
  };
  auto filtered = [&](double delay, double lag_s) {
    Eigen::MatrixXd A = design(m, Eigen::VectorXd::Constant(1, delay));
    first_order_lag(d.obs.t_s, lag_s, A);
    return A;
  };
  // All a filter, half of it, none of it; a lead without a filter is the pure lead.
  const Eigen::MatrixXd all = filtered(0.0, 0.008), half = filtered(0.004, 0.004), none = filtered(0.008, 0.0);
  ASSERT_GT(all.norm(), 0.0);
  EXPECT_LT((design(*lag, Eigen::Vector2d(0.0, 0.008)) - all).norm(), 1e-12 * all.norm());
  EXPECT_LT((design(*lag, Eigen::Vector2d(0.004, 0.004)) - half).norm(), 1e-12 * all.norm());
  EXPECT_LT((design(*lag, Eigen::Vector2d(0.008, 0.0)) - none).norm(), 1e-12 * all.norm());
  EXPECT_GT((all - none).norm(), 1e-3 * all.norm());  // the forms differ on this run
  EXPECT_EQ(design(*lag, Eigen::Vector2d(-0.004, 0.0)), design(m, Eigen::VectorXd::Constant(1, -0.004)));
  // Reported: the group delay, the sum of both.
  Fit f;
  f.theta = Eigen::Vector2d(1e5, 2e4);
  f.phi = Eigen::Vector2d(0.003, 0.005);
  f.cov = Eigen::MatrixXd::Zero(4, 4);
  bool seen = false;
  for (const auto& q : lag->report(f))
    if (q.name == "time_offset_s") {
      EXPECT_DOUBLE_EQ(q.value, 0.008);
      seen = true;
    }
  EXPECT_TRUE(seen);
  // The refit's starts: about the pure delay's reading of a delay and a filter; none from a lead.
  const auto starts = forms[2].refit_from(Eigen::Vector2d(0.008, 0.0));
  ASSERT_FALSE(starts.empty());
  for (const auto& x : starts) {
    EXPECT_GT(x(1), 0.0);
    // The delay a pure-delay fit would read: between the filter's step reading (ln 2) and its ramp's (1).
    EXPECT_GE(x(0) + x(1), 0.008 + 0.05 * x(1));
    EXPECT_LE(x(0) + 0.5 * x(1), 0.008);
  }
  EXPECT_TRUE(forms[2].refit_from(Eigen::Vector2d(-0.004, 0.0)).empty());
}

TEST(ContactFamily, TheFrictionsModelFormsMoveItsLineOfActionAlongTheNormalOnly) {
  const auto r = test::scene_run("press_slide");
  const auto d = data_of(r, {});
  const ContactFamily m(d, {"viscous_friction"});
  const auto forms = m.model_forms();
  ASSERT_EQ(forms.size(), 2u);
  Eigen::MatrixXd A0;
  m.design(Eigen::VectorXd(0), A0);
  const Eigen::Matrix3d R_fp_world = d.scene.T_world_fp.linear().transpose();
  double moved = 0.0;
  for (const auto& form : forms) {
    const auto* f = dynamic_cast<const ContactFamily*>(form.model.get());
    ASSERT_NE(f, nullptr);
    EXPECT_EQ(std::abs(f->friction_lever()), 0.75) << form.assumption;
    EXPECT_EQ(f->linear().size(), m.linear().size());
    Eigen::MatrixXd A;
    f->design(Eigen::VectorXd(0), A);
    ASSERT_EQ(A.rows(), A0.rows());
    EXPECT_EQ((A.col(0) - A0.col(0)).norm(), 0.0);  // the normal force stays at the centroid
    for (std::size_t k = 0; k < d.obs.size(); ++k) {
      // The tangential forces' moment about the new point: the plate feels -f at p + κ δ n.
      Eigen::Vector3d dm_friction = Eigen::Vector3d::Zero(), dm_viscous = Eigen::Vector3d::Zero();
      for (const auto& c : d.contacts[k]) {
        const Eigen::Vector3d lever = f->friction_lever() * c.delta * c.normal;
        dm_friction += R_fp_world * lever.cross(-c.delta * c.tangent);
        dm_viscous += R_fp_world * lever.cross(-c.slip_speed * c.tangent);
      }
      const Eigen::Index row = static_cast<Eigen::Index>(6 * k);
      for (int j = 1; j <= 2; ++j) {
        const Eigen::Vector3d want = j == 1 ? dm_friction : dm_viscous;
        EXPECT_LT((A.block(row, j, 3, 1) - A0.block(row, j, 3, 1)).norm(), 1e-15) << k;  // forces unchanged
        EXPECT_LT((A.block(row + 3, j, 3, 1) - A0.block(row + 3, j, 3, 1) - want).norm(), 1e-12 * (1 + want.norm())) << k;
      }
      moved = std::max(moved, dm_friction.norm());
    }
  }
  EXPECT_GT(moved, 0.0);  // the run slides: the forms change something
}

TEST(ContactFamily, PrunedAndIncrementalContactsAreMindistsOnEveryPair) {
  // The design skips pairs provably apart and copies the pairs of unmoved features from the last
  // evaluation (docs/diagnosis.md, "Cost"): the result must be mindist's on every pair, bit for bit.
  const auto r = test::scene_run("acu_2a");
  Effects e;
  draw_effect("geometric_offset", 19, r.scene, e);
  const auto d = make_contact_data(r.scene, r.model.v_tm, test::measure(r, e, 19), r.force_scale_n, r.moment_scale_nm);
  ContactFamily m(d, {"geometric_offset", "time_offset"});
  const auto nl = m.nonlinear();
  const Eigen::Index q = static_cast<Eigen::Index>(nl.size());
  std::vector<Eigen::VectorXd> phis{Eigen::VectorXd::Zero(q)};
  Eigen::VectorXd phi(q);
  for (Eigen::Index j = 0; j < q; ++j) phi(j) = (j % 2 ? -2.0 : 3.0) * nl[static_cast<std::size_t>(j)].scale;
  phis.push_back(phi);
  for (Eigen::Index j = 0; j < q; ++j) {  // finite-difference steps: one feature (or the delay) at a time
    phis.push_back(phi);
    phis.back()(j) += 1e-4 * nl[static_cast<std::size_t>(j)].scale;
  }
  phis.push_back(Eigen::VectorXd::Zero(q));
  phis.back()(q - 1) = 0.3;  // a delay of 0.3 s moves the ee by more than the pair table covers
  cid::MindistWorkspace ws;
  std::vector<cid::ContactPoint> cs;
  const auto data = m.make_data();  // one evaluator's: each design steps from the last one's contacts
  for (const auto& ph : phis) {
    Eigen::MatrixXd A;
    m.design(ph, A, *data);
    Eigen::VectorXd x = r.scene.design();
    for (std::size_t j = 0; j < d.fit_uncertainties.size(); ++j) x(d.fit_uncertainties[j]) += ph(static_cast<Eigen::Index>(j));
    for (std::size_t k = 0; k < d.obs.size(); ++k) {
      const double tau = ph(q - 1);
      cid::Kinematics kin = d.kin[k];
      if (tau != 0.0) kin = m.kinematics_at(d.obs.t_s[k] - tau);  // the pose at t - τ (its own test below)
      cid::mindist(r.scene, kin, x, d.v_tm, cs, ws);
      Eigen::Matrix<double, 6, 2> expected = Eigen::Matrix<double, 6, 2>::Zero();
      for (const auto& c : cs) {
        expected.col(0) += plate_wrench_of(r.scene.T_world_fp, c.delta * c.normal, c.point);
        expected.col(1) += plate_wrench_of(r.scene.T_world_fp, c.delta * c.tangent, c.point);
      }
      ASSERT_EQ(Eigen::MatrixXd(A.block(static_cast<Eigen::Index>(6 * k), 0, 6, 2)), Eigen::MatrixXd(expected))
          << "sample " << k << ", phi " << ph.transpose();
    }
  }
}

/// φ values a fit visits: the start, a point, one finite-difference step per entry, and a delay
/// beyond the pair table.
std::vector<Eigen::VectorXd> visited_phis(const ContactFamily& m) {
  const auto nl = m.nonlinear();
  const Eigen::Index q = static_cast<Eigen::Index>(nl.size());
  std::vector<Eigen::VectorXd> phis{Eigen::VectorXd::Zero(q)};
  Eigen::VectorXd phi(q);
  for (Eigen::Index j = 0; j < q; ++j) phi(j) = (j % 2 ? 2.0 : -1.5) * nl[static_cast<std::size_t>(j)].scale;
  for (Eigen::Index j = 0; j < q; ++j) {
    phis.push_back(phi);
    phis.back()(j) += 1e-4 * nl[static_cast<std::size_t>(j)].scale;
  }
  phis.push_back(Eigen::VectorXd::Zero(q));
  phis.back()(q - 1) = 0.3;
  return phis;
}

TEST(ContactFamily, OneFamilyDesignsOnTwoThreadsEachWithItsOwnDataAsOnOne) {
  // The family is the model, shared; its scratch and the base a design steps from are each
  // evaluator's (FamilyData). Two threads walk the same φ in opposite orders on one family: every
  // design must equal the one-off design (fresh data) bit for bit. TSan (tools/sanitize.sh) sees a
  // shared write here if the family kept any.
  const auto r = test::scene_run("acu_2a");
  Effects e;
  draw_effect("geometric_offset", 23, r.scene, e);
  const auto d = make_contact_data(r.scene, r.model.v_tm, test::measure(r, e, 23), r.force_scale_n, r.moment_scale_nm);
  const ContactFamily m(d, {"geometric_offset", "time_offset"});
  const auto phis = visited_phis(m);
  std::vector<Eigen::MatrixXd> expected(phis.size());
  for (std::size_t i = 0; i < phis.size(); ++i) m.design(phis[i], expected[i]);
  std::array<std::vector<Eigen::MatrixXd>, 2> got;
  auto walk = [&](int t) {
    const auto data = m.make_data();
    got[static_cast<std::size_t>(t)].resize(phis.size());
    for (std::size_t a = 0; a < phis.size(); ++a) {
      const std::size_t i = t == 0 ? a : phis.size() - 1 - a;
      m.design(phis[i], got[static_cast<std::size_t>(t)][i], *data);
    }
  };
  std::thread other(walk, 1);
  walk(0);
  other.join();
  for (int t = 0; t < 2; ++t)
    for (std::size_t i = 0; i < phis.size(); ++i)
      ASSERT_EQ(got[static_cast<std::size_t>(t)][i], expected[i]) << "thread " << t << ", phi " << i;
  // Another family's data is refused, not misread.
  Eigen::MatrixXd A;
  auto foreign = std::make_unique<FamilyData>();
  EXPECT_THROW(m.design(phis[1], A, *foreign), std::bad_cast);
}

TEST(Engine, FoldsOnTwoThreadsScoreExactlyAsOnOne) {
  // CvOptions::threads spreads the folds over the cores; each result goes to its fold's slot, so
  // the score (held-out predictions, fold estimates, intervals) is the serial one bit for bit. A
  // family that derives choices from its folds' data (sensor_gain's reference) and one whose
  // contacts move with φ (time_offset) are both run.
  const auto r = test::scene_run("press_slide");
  Effects e;
  draw_effect("time_offset", 31, r.scene, e);
  const auto d = make_contact_data(r.scene, r.model.v_tm, test::measure(r, e, 31), r.force_scale_n, r.moment_scale_nm);
  for (const auto& ext : {std::set<std::string>{"time_offset"}, std::set<std::string>{"sensor_gain"}}) {
    const ContactFamily m(d, ext);
    CvOptions one, two;
    one.threads = 1;
    two.threads = 2;
    one.offsets = two.offsets = 2;  // the shifted grid's folds too
    const Score a = score(m, d.obs, one), b = score(m, d.obs, two);
    ASSERT_EQ(a.fold_phi.size(), 10u) << *ext.begin();
    ASSERT_EQ(b.fold_phi.size(), a.fold_phi.size());
    for (std::size_t i = 0; i < a.fold_phi.size(); ++i) EXPECT_EQ(a.fold_phi[i], b.fold_phi[i]) << *ext.begin() << " fold " << i;
    EXPECT_EQ(a.cv_prediction, b.cv_prediction) << *ext.begin();
    ASSERT_EQ(a.cv_shifted.size(), 1u);
    EXPECT_EQ(a.cv_shifted[0], b.cv_shifted[0]) << *ext.begin();
    EXPECT_EQ(a.cv_error, b.cv_error) << *ext.begin();
    ASSERT_EQ(a.full.reported.size(), b.full.reported.size());
    for (std::size_t j = 0; j < a.full.reported.size(); ++j) {
      EXPECT_EQ(a.full.reported[j].value, b.full.reported[j].value) << a.full.reported[j].name;
      EXPECT_EQ(a.full.reported[j].std, b.full.reported[j].std) << a.full.reported[j].name;
      EXPECT_EQ(a.full.reported[j].std_folds, b.full.reported[j].std_folds) << a.full.reported[j].name;
    }
  }
}

TEST(Engine, ModelsSideBySideDiagnoseExactlyAsOneAfterAnother) {
  // DiagnoseOptions::model_threads scores a step's candidates side by side; each result goes to
  // its candidate's slot, so the diagnosis is the serial one bit for bit, and the progress calls
  // still come one at a time with the steps in order.
  const auto d = test::hidden_contact_data(test::scene_run("press_slide"), "sensor_bias", 12);
  const ModelFactory make = test::contact_factory(d);
  const std::vector<std::string> candidates{"sensor_gain", "sensor_bias", "time_offset", "viscous_friction"};
  DiagnoseOptions serial, side_by_side;
  serial.model_threads = 1;
  side_by_side.model_threads = 2;
  serial.cv.threads = side_by_side.cv.threads = 1;
  std::vector<int> steps;
  std::atomic<int> inside{0};
  bool overlapped = false;
  const Progress record = [&](int step, int, const std::string&) {
    overlapped = overlapped || ++inside > 1;
    steps.push_back(step);
    --inside;
  };
  const Diagnosis a = diagnose(make, candidates, d.obs, {}, serial);
  const Diagnosis b = diagnose(make, candidates, d.obs, {}, side_by_side, record);
  EXPECT_EQ(a.cause, "sensor_bias");
  EXPECT_EQ(b.cause, a.cause);
  EXPECT_EQ(b.second_cause, a.second_cause);
  EXPECT_EQ(b.gain_percent, a.gain_percent);
  for (const auto& [x, y] : {std::pair{&a.candidates, &b.candidates}, std::pair{&a.second_step, &b.second_step}}) {
    ASSERT_EQ(x->size(), y->size());
    for (std::size_t i = 0; i < x->size(); ++i) {
      EXPECT_EQ((*x)[i].name, (*y)[i].name) << i;
      const double ex = (*x)[i].score.cv_error, ey = (*y)[i].score.cv_error;  // NaN: screened (no folds run)
      EXPECT_TRUE(ex == ey || (std::isnan(ex) && std::isnan(ey))) << (*x)[i].name << ": " << ex << " vs " << ey;
      EXPECT_EQ((*x)[i].score.held_out(), (*y)[i].score.held_out()) << (*x)[i].name;
      EXPECT_EQ((*x)[i].score.full.phi, (*y)[i].score.full.phi) << (*x)[i].name;
      EXPECT_EQ((*x)[i].verdict, (*y)[i].verdict) << (*x)[i].name;
    }
  }
  EXPECT_FALSE(overlapped);
  const int total = 1 + static_cast<int>(candidates.size()) + side_by_side.second_candidates;
  ASSERT_EQ(steps.size(), 1 + candidates.size() + b.second_step.size() + 1);  // + the final "done"
  for (std::size_t i = 0; i + 1 < steps.size(); ++i) EXPECT_EQ(steps[i], static_cast<int>(i) + 1);
  EXPECT_EQ(steps.back(), total);

  // A callback that throws (Ctrl-C in Python) stops the steps not yet started; its exception leaves.
  struct Stop {};
  std::vector<int> seen;
  const Progress stop_at_3 = [&](int step, int, const std::string&) {
    seen.push_back(step);
    if (step == 3) throw Stop{};
  };
  EXPECT_THROW(diagnose(make, candidates, d.obs, {}, side_by_side, stop_at_3), Stop);
  EXPECT_EQ(seen, (std::vector<int>{1, 2, 3}));
}

/// Noise-free recovery: the family with the injected extension fits the generator's data exactly.
struct Exact {
  const char* effect;
  const char* param;
  double truth;
  double rel_tol;
  const char* scene = "press_slide";
};

class ExactRecovery : public ::testing::TestWithParam<Exact> {};

TEST_P(ExactRecovery, OfTheInjectedParameter) {
  const auto c = GetParam();
  const auto r = test::scene_run(c.scene);
  Effects e;
  const std::string eff = c.effect;
  // The injected effect's true value under the name the fit reports it (ContactEffect::inject).
  TruthValues injected{{c.param, c.truth}};
  if (eff == "contact_damping" && std::string(c.param) == "damping_friction_n_s_per_m")
    injected = {{"damping_n_s_per_m", c.truth}, {"damping_friction", 1.0}};
  if (eff == "nonlinear_stiffness") injected["delta_ref_m"] = data_of(r, {}).delta_ref_m;  // the family's reference interference
  inject_effect(eff, injected, e);
  const auto d = data_of(r, e);
  ContactFamily m(d, {eff});
  const Fit f = fit(m, d.obs, all(d.obs.size()));
  for (const auto& u : f.unidentifiable)
    if (u.name == c.param) ADD_FAILURE() << u.name << " not identifiable: " << u.reason;
  bool found = false;
  for (const auto& q : f.reported)
    if (q.name == c.param) {
      found = true;
      // With the friction on the total normal force the friction coefficient of the damping
      // force is μ: its term is μ D.
      const double truth = q.name == "damping_friction_n_s_per_m" ? r.model.mu * c.truth : c.truth;
      EXPECT_NEAR(q.value, truth, c.rel_tol * std::abs(truth)) << c.param;
    }
  // Friction on the elastic force only: the damping's friction term is fitted as 0.
  if (eff == "contact_damping" && std::string(c.param) == "damping_n_s_per_m") {
    for (const auto& q : f.reported) {
      if (q.name == "damping_friction_n_s_per_m") {
        EXPECT_NEAR(q.value, 0.0, 1e-6 * c.truth);
      }
    }
  }
  EXPECT_TRUE(found) << c.param;
  EXPECT_NEAR(f.reported[0].value, r.model.K, (eff == "time_offset" ? 1e-2 : 1e-6) * r.model.K);
}

INSTANTIATE_TEST_SUITE_P(
    Effects, ExactRecovery,
    ::testing::Values(Exact{"viscous_friction", "viscous_n_s_per_m", 3000.0, 1e-6},
                      Exact{"contact_damping", "damping_n_s_per_m", 4000.0, 1e-6},
                      // press_slide never slides while the penetration changes
                      Exact{"contact_damping", "damping_friction_n_s_per_m", 4000.0, 1e-6, "acu_2a"},
                      Exact{"sensor_bias", "bias_fx", 3.0,
                            1e-6},  // fz and fx are the references (the largest signal of the normal and of the friction group)
                      Exact{"sensor_gain", "gain_my", 0.1, 1e-6}, Exact{"nonlinear_stiffness", "stiffness_exponent", 1.4, 1e-6},
                      Exact{"geometric_offset", "block_top_z", 1.5e-4, 1e-4},
                      // the generator delays the 50 Hz wrench by interpolation,
                      // the family re-evaluates the contact at interpolated poses
                      Exact{"time_offset", "time_offset_s", 0.03, 0.1}),
    [](const auto& i) { return std::string(i.param.param); });

// sensor_gain's gains are relative to the component with the largest signal (its scale is K's).
// Where the normal force loads fx (ACU 2a's V-guide) or the friction loads my (the press bench's
// block, above the plate's origin), the friction's common scale is seen apart from μ: one
// reference, and the note says so. (On a level plate each group has one: test_unexplained.cpp.)
TEST(SensorGain, HasOneReferenceWhereTheNormalForceAndTheFrictionShareComponents) {
  for (const char* scene : {"press_slide", "acu_2a"}) {
    const auto r = test::scene_run(scene);
    const auto d = data_of(r, {});
    const ContactFamily m(d, {"sensor_gain"});
    std::vector<std::string> gains;
    for (const auto& q : m.nonlinear())
      if (q.name.rfind("gain_", 0) == 0) gains.push_back(q.name);
    EXPECT_EQ(gains, (std::vector<std::string>{"gain_fx", "gain_fy", "gain_mx", "gain_my", "gain_mz"})) << scene;
    ASSERT_EQ(m.notes().size(), 1u) << scene;
    EXPECT_THAT(m.notes()[0], HasSubstr("sensor_gain's gains are relative to fz, the largest signal")) << scene;
  }
}

// time_offset's pose at t - τ (ContactFamily::kinematics_at): exact at the samples, a smooth
// motion to 2e-8 m between them (a linear blend of the neighbours is 5e-6 m off on this one), and a
// quantised pose stream's noise kept at a half-sample shift (a linear blend halves its variance:
// the fitted delay then drifts towards fractional shifts, docs/diagnosis.md).
TEST(ContactFamily, KinematicsBetweenSamplesFollowTheMotionAndKeepTheNoiseLevel) {
  const auto r = test::scene_run("acu_2a");
  Effects none;
  ContactData d = make_contact_data(r.scene, r.model.v_tm, test::measure(r, none, 3), r.force_scale_n, r.moment_scale_nm);
  const std::size_t n = d.obs.size();
  ASSERT_GT(n, 100u);
  const double dt = (d.obs.t_s.back() - d.obs.t_s.front()) / static_cast<double>(n - 1);
  // A smooth motion (0.3-0.5 Hz, as the runs' presses) with its twist.
  constexpr double pi = 3.14159265358979323846;
  const auto pose = [&](double t) {
    cid::Kinematics k;
    const double w1 = 2 * pi * 0.5, w2 = 2 * pi * 0.3;
    k.T_world_ee.translation() = Eigen::Vector3d(0.4 + 0.01 * std::sin(w1 * t), 0.005 * std::cos(w2 * t), 0.1 + 0.002 * t);
    k.v_world_ee = Eigen::Vector3d(0.01 * w1 * std::cos(w1 * t), -0.005 * w2 * std::sin(w2 * t), 0.002);
    const Eigen::Vector3d rv(0.2 * std::sin(w2 * t), 0.1 * t, 0.05);
    k.T_world_ee.linear() = so3::exp(rv);
    k.w_world_ee = Eigen::Vector3d(0.2 * w2 * std::cos(w2 * t), 0.1, 0.0);  // not the exact ω: only blended here
    return k;
  };
  for (std::size_t k = 0; k < n; ++k) d.kin[k] = pose(d.obs.t_s[k]);
  const ContactFamily m(d, {});
  for (std::size_t k = 0; k < n; k += 7) {
    const cid::Kinematics at = m.kinematics_at(d.obs.t_s[k]);
    EXPECT_EQ(at.T_world_ee.matrix(), d.kin[k].T_world_ee.matrix()) << "sample " << k;
  }
  double worst_m = 0.0, worst_rad = 0.0, worst_v = 0.0;
  for (std::size_t k = 8; k + 9 < n; ++k)
    for (double f : {0.1, 0.25, 0.5, 0.8}) {
      const double t = d.obs.t_s[k] + f * (d.obs.t_s[k + 1] - d.obs.t_s[k]);
      const cid::Kinematics at = m.kinematics_at(t), truth = pose(t);
      worst_m = std::max(worst_m, (at.T_world_ee.translation() - truth.T_world_ee.translation()).norm());
      worst_rad = std::max(worst_rad, so3::angle(at.T_world_ee.linear() * truth.T_world_ee.linear().transpose()));
      worst_v = std::max(worst_v, (at.v_world_ee - truth.v_world_ee).norm());
    }
  EXPECT_LT(worst_m, 2e-8) << "dt " << dt;
  EXPECT_LT(worst_rad, 1e-7);
  EXPECT_LT(worst_v, 1e-7);

  // A still pose, quantised: white noise of std q/√12 per coordinate. Its variance half a sample
  // from the samples, against at the samples.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.5e-6, 0.5e-6);
  for (auto& k : d.kin) {
    k = cid::Kinematics{};
    k.T_world_ee.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng));
  }
  const ContactFamily still(d, {});
  double at_samples = 0.0, halfway = 0.0;
  std::size_t count = 0;
  for (std::size_t k = 8; k + 9 < n; ++k, ++count) {
    at_samples += d.kin[k].T_world_ee.translation().squaredNorm();
    halfway += still.kinematics_at(0.5 * (d.obs.t_s[k] + d.obs.t_s[k + 1])).T_world_ee.translation().squaredNorm();
  }
  ASSERT_GT(count, 100u);
  EXPECT_GT(halfway / at_samples, 0.85) << "over " << count << " samples";
  EXPECT_LT(halfway / at_samples, 1.15) << "over " << count << " samples";
}

TEST(ContactFamily, AQuantumIsSeenOnlyWhenEveryValueLiesOnItsGrid) {
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 3e-6);
  std::vector<double> quantised, continuous;
  for (int k = 0; k < 500; ++k) {
    const double x = 0.1234567 + 1e-5 * std::sin(0.01 * k) + noise(rng);
    quantised.push_back(2e-6 * std::round(x / 2e-6));
    continuous.push_back(x);
  }
  EXPECT_NEAR(quantum_of(quantised), 2e-6, 1e-15);
  EXPECT_EQ(quantum_of(continuous), 0.0);
  EXPECT_EQ(quantum_of({1.0, 1.0, 1.0}), 0.0);   // one level: no step to see
  EXPECT_EQ(quantum_of({0.0, 2e-4, 0.0}), 0.0);  // two levels
  EXPECT_NEAR(quantum_of({0.0, 2e-4, 4e-4, -2e-4}), 2e-4, 1e-18);
  EXPECT_EQ(quantum_of({0.0, 2e-4, 4e-4, 5e-4}, 5), 0.0);  // fewer levels than asked for
  EXPECT_EQ(quantum_of({0.0, 2e-4, 5e-4}), 0.0);           // 5e-4 is off the 2e-4 grid
}

// A signal that never takes two adjacent levels (a slow move's normal twist on a fine grid): its
// step is a fraction of the smallest gap. Found 2026-12-03: the smallest gap (4e-5) was off the
// grid of the other values and no quantum was seen at all.
TEST(ContactFamily, AQuantumIsSeenWhenNoTwoLevelsAreAdjacent) {
  // Levels 3, 5, 7, 11, 26 and -26 steps of 2e-5: the smallest gap is two steps, 26 - 3 is odd.
  std::vector<double> twist;
  for (const int level : {3, 5, 7, 11, 26, -26, 5, 3}) twist.push_back(2e-5 * level);
  EXPECT_NEAR(quantum_of(twist), 2e-5, 1e-18);
  // Every gap even: the coarsest grid holding the values is the smallest gap, 4e-5.
  EXPECT_NEAR(quantum_of({0.0, 4e-5, 8e-5, 2e-4, -1.2e-4}), 4e-5, 1e-18);
  // Below five distinct values a finer grid is not inferred: 0, 2, 5 fit a grid of 1 by chance.
  EXPECT_EQ(quantum_of({0.0, 2e-4, 5e-4, 7e-4}), 0.0);
  EXPECT_NEAR(quantum_of({0.0, 2e-4, 5e-4, 7e-4, 1.1e-3}), 1e-4, 1e-18);
  // At most a tenth of the smallest gap: 0, 11, 23, 34, 47 steps is no grid of the gap's tenths.
  std::vector<double> sparse;
  for (const int level : {0, 11, 23, 34, 47}) sparse.push_back(1e-5 * level);
  EXPECT_EQ(quantum_of(sparse), 0.0);
}

// touching_probability against a direct simulation of the reported positions' quantum: the true
// interference is δ + n · e, e uniform over each axis's step. Rule written before it ran: within
// 0.01 of the simulated share (200,000 draws: its own error under 0.0012) at every δ across the
// errors' reach, for a tilted plate's normal (the suite's: one axis dominant) and a 45° one (three
// comparable axes; measured afterwards with 2e6 draws: 0.0005 and 0.003 off at worst, 0.006
// with three equal axes); 1 far beyond the reach, a pure ramp with one axis,
// a step with exact positions.
TEST(ContactFamily, TheTouchingProbabilityIsTheShareOfTruePositionsWithinTheQuantumThatTouch) {
  std::mt19937_64 rng(29);
  const Eigen::Vector3d q(2e-6, 2e-6, 2e-6);
  for (const Eigen::Vector3d& n : {Eigen::Vector3d(0.05, -0.03, 1.0).normalized(), Eigen::Vector3d(0.5, 0.5, 0.7071).normalized()}) {
    std::uniform_real_distribution<double> ex(-q(0) / 2, q(0) / 2), ey(-q(1) / 2, q(1) / 2), ez(-q(2) / 2, q(2) / 2);
    const double reach = 0.5 * n.cwiseAbs().dot(q);
    for (double delta = -reach; delta <= reach; delta += reach / 8) {
      int touching = 0;
      const int draws = 200000;
      for (int k = 0; k < draws; ++k) touching += delta + n.dot(Eigen::Vector3d(ex(rng), ey(rng), ez(rng))) > 0.0 ? 1 : 0;
      EXPECT_NEAR(touching_probability(delta, n, q), static_cast<double>(touching) / draws, 0.01) << n.transpose() << " at " << delta;
    }
    EXPECT_NEAR(touching_probability(1.01 * reach, n, q), 1.0, 0.01);
    EXPECT_NEAR(touching_probability(-1.01 * reach, n, q), 0.0, 0.01);
    EXPECT_EQ(touching_probability(10 * reach, n, q), 1.0);
  }
  EXPECT_NEAR(touching_probability(0.5e-6, Eigen::Vector3d::UnitZ(), q), 0.75, 1e-12);
  EXPECT_EQ(touching_probability(1e-9, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero()), 1.0);
  EXPECT_EQ(touching_probability(-1e-9, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero()), 0.0);
}

// The bias a quantiser leaves in a mean, against its direct simulation: a constant at an unknown
// place on the grid, dithered by Gaussian noise, its quantised mean's error squared over the places.
TEST(ContactFamily, TheQuantisationBiasFloorShrinksWithTheDitherTheNoiseGives) {
  const double step = 0.1;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> place(0.0, step);
  auto simulated = [&](double sigma) {  // E over places of (mean quantised - x)², 20,000 samples each
    double sum = 0.0;
    for (int i = 0; i < 200; ++i) {
      const double x = place(rng);
      double mean = 0.0;
      for (int k = 0; k < 20000; ++k) mean += step * std::round((x + sigma * unit(rng)) / step) / 20000.0;
      sum += (mean - x) * (mean - x) / 200.0;
    }
    return sum;
  };
  EXPECT_NEAR(quantisation_bias_variance(step, 0.0), step * step / 12.0, 1e-15);
  EXPECT_NEAR(simulated(0.0), step * step / 12.0, 0.2 * step * step / 12.0);
  // σ = step/4 and step/6: the floor falls to 5 % and 26 % of step²/12, as simulated (the
  // simulation's own sampling error is 5e-7 step² per place, far below).
  for (const double sigma : {step / 4, step / 6}) {
    const double v = quantisation_bias_variance(step, sigma);
    EXPECT_NEAR(v, simulated(sigma), 0.25 * v) << sigma;
  }
  EXPECT_NEAR(quantisation_bias_variance(step, step / 4) / (step * step / 12.0), 0.0515, 0.001);
  EXPECT_LT(quantisation_bias_variance(step, step), 1e-18);
  EXPECT_EQ(quantisation_bias_variance(0.0, 0.0), 0.0);

  // From a series: a signal sweeping the grid (fz-like, 2 N at 0.7 Hz) plus noise, quantised; the
  // floor no larger than 0.9 σ would give at σ = step/2 and step; no dither seen on a noiseless constant; a few
  // jumps (a friction's sign flips) do not spoil it.
  auto series = [&](double sigma, double sweep_n, int jumps) {
    std::vector<double> y;
    for (int k = 0; k < 1500; ++k) {
      double x = 0.0123 + sweep_n * std::sin(2 * M_PI * 0.7 * 0.01 * k) + sigma * unit(rng);
      if (jumps > 0 && (k / (1500 / (jumps + 1))) % 2 == 1) x += 5.0;
      y.push_back(step * std::round(x / step));
    }
    return y;
  };
  for (const double sigma : {step / 2, step})
    EXPECT_NEAR(quantisation_bias_variance(series(sigma, 2.0, 8), step), quantisation_bias_variance(step, sigma),
                quantisation_bias_variance(step, 0.9 * sigma) - quantisation_bias_variance(step, sigma))
        << sigma;
  EXPECT_NEAR(quantisation_bias_variance(series(0.0, 0.0, 0), step), step * step / 12.0, 1e-15);
  EXPECT_NEAR(quantisation_bias_variance(std::vector<double>{}, step), step * step / 12.0, 1e-15);
  EXPECT_EQ(quantisation_bias_variance(std::vector<double>{1.0, 2.0, 3.0}, 0.0), 0.0);  // not quantised
}

TEST(ContactFamily, AWindowedSlopeIsExactOnQuadraticsAndAveragesQuantisationNoise) {
  std::vector<double> t, x;
  for (int k = 0; k < 200; ++k) {
    t.push_back(0.01 * k);
    x.push_back(0.3 + 0.02 * t.back() - 0.5 * t.back() * t.back());
  }
  const auto slope = windowed_slope(t, x, 8);
  for (std::size_t k = 8; k + 8 < t.size(); ++k) EXPECT_NEAR(slope[k], 0.02 - 1.0 * t[k], 1e-12) << k;
  // A ramp quantised at 2 µm: the slope's error has the std (q/√12)/√Σt² of white noise, 2.9e-6 m/s.
  std::vector<double> tq, xq;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> phase(0.0, 2e-6);
  const double x0 = phase(rng);
  for (int k = 0; k < 4000; ++k) {
    tq.push_back(0.01 * k);
    xq.push_back(2e-6 * std::round((x0 + 1.234e-4 * tq.back()) / 2e-6));
  }
  const auto sq = windowed_slope(tq, xq, 8);
  double ss = 0.0;
  for (std::size_t k = 8; k + 8 < tq.size(); ++k) ss += (sq[k] - 1.234e-4) * (sq[k] - 1.234e-4);
  const double rms = std::sqrt(ss / static_cast<double>(tq.size() - 16));
  EXPECT_LT(rms, 1.5 * 2e-6 / std::sqrt(12.0 * 0.01 * 0.01 * 408.0)) << rms;
  EXPECT_LT(rms, 0.1 * 2e-4 / std::sqrt(12.0));  // a tenth of a 2e-4 m/s twist step's noise
}

// A robot's moves: the velocity steps between two samples (a start, a stop, a turn). rate_steps
// finds the steps, and only them, and places them from the quantised positions to a small part of a
// sample; a smooth motion and a quantised smooth velocity have none.
TEST(ContactFamily, RateStepsFindAndPlaceAMovesStepsAndNothingElse) {
  using Vec3 = Eigen::Vector3d;
  const double h = 0.01, q_p = 2e-6, q_v = 2e-5;
  // Piecewise-constant velocity: 8 mm/s along (1, 0.5, 0) from 0.0423 s, a stop at 0.5177 s, back
  // at 4 mm/s from 0.8031 s. Exact positions at the samples, then quantised.
  const std::vector<double> kinks{0.0423, 0.5177, 0.8031};
  const std::vector<Vec3> vel{Vec3::Zero(), Vec3(8e-3, 4e-3, 0.0), Vec3::Zero(), Vec3(-4e-3, -2e-3, 0.0)};
  const auto segment = [&](double t) {
    std::size_t i = 0;
    while (i < kinks.size() && t >= kinks[i]) ++i;
    return i;
  };
  const auto position = [&](double t) {
    Vec3 p = Vec3(0.1, 0.2, 0.05);
    double from = 0.0;
    for (std::size_t i = 0; i < kinks.size() && kinks[i] < t; ++i) {
      p += vel[i] * (kinks[i] - from);
      from = kinks[i];
    }
    return Vec3(p + vel[segment(t)] * (t - from));
  };
  std::vector<double> t;
  std::vector<Vec3> v, dp;
  Vec3 last;
  for (int k = 0; k < 120; ++k) {
    t.push_back(h * k);
    Vec3 p = position(t.back());
    for (int a = 0; a < 3; ++a) p(a) = q_p * std::round(p(a) / q_p);
    Vec3 vk = vel[segment(t.back())];
    for (int a = 0; a < 3; ++a) vk(a) = q_v * std::round(vk(a) / q_v);
    v.push_back(vk);
    if (k > 0) dp.push_back(p - last);
    last = p;
  }
  const auto steps = rate_steps(t, v, dp, std::sqrt(3.0) * q_v, std::sqrt(3.0) * q_p);
  ASSERT_EQ(steps.size(), t.size() - 1);
  for (std::size_t j = 0; j < steps.size(); ++j) {
    bool kink = false;
    double fraction = 0.0;
    for (const double tk : kinks)
      if (tk > t[j] && tk < t[j + 1]) {
        kink = true;
        fraction = (tk - t[j]) / h;
      }
    if (!kink) {
      EXPECT_TRUE(std::isnan(steps[j])) << "a step found at interval " << j;
      continue;
    }
    ASSERT_FALSE(std::isnan(steps[j])) << "the step at interval " << j << " not found";
    // One quantum of position over the slowest jump (4 mm/s) is half a millisecond: the span of
    // samples on each side brings the error well under it.
    EXPECT_NEAR(steps[j], fraction, 0.02) << "interval " << j;
  }
  // A smooth motion (two tones) with its velocity quantised: no step anywhere.
  std::vector<Vec3> vs, dps;
  Vec3 prev;
  for (std::size_t k = 0; k < t.size(); ++k) {
    const double tk = t[k];
    const Vec3 p(1e-3 * std::sin(2 * M_PI * 0.7 * tk), 4e-4 * std::sin(2 * M_PI * 2.3 * tk), 0.0);
    Vec3 vk(1e-3 * 2 * M_PI * 0.7 * std::cos(2 * M_PI * 0.7 * tk), 4e-4 * 2 * M_PI * 2.3 * std::cos(2 * M_PI * 2.3 * tk), 0.0);
    for (int a = 0; a < 3; ++a) vk(a) = q_v * std::round(vk(a) / q_v);
    vs.push_back(vk);
    if (k > 0) dps.push_back(p - prev);
    prev = p;
  }
  for (const double s : rate_steps(t, vs, dps, std::sqrt(3.0) * q_v, 0.0)) EXPECT_TRUE(std::isnan(s));
  EXPECT_THROW(rate_steps(t, v, v, 0.0, 0.0), std::invalid_argument);  // increments: one fewer
}

// time_offset's plateaus: a delay τ moves sample k's instant to t_k - τ, which crosses a placed step
// at t_j + f h when τ = t_k - t_j - f h, and a sample instant near a step at τ = t_k - t_j (the
// delayed twist switches there between its step-aware and its sinc interpolation). delay_crossings
// lists exactly those within the bounds, merges the close ones, and nothing when nothing steps.
TEST(ContactFamily, DelayCrossingsAreWhereADelayedInstantMeetsAStep) {
  const double h = 0.01;
  ContactData d;
  for (int k = 0; k < 100; ++k) d.obs.t_s.push_back(h * k);
  d.v_step.assign(99, std::numeric_limits<double>::quiet_NaN());
  d.v_step[40] = 0.3;  // a step at 0.403 s
  d.rate_step.assign(99, std::numeric_limits<double>::quiet_NaN());
  d.rate_step[40] = 0.3004;  // the same step placed from the rates, 4 µs later: merged with it
  d.w_step.clear();          // no angular step
  const double lim = 0.025;
  const auto c = delay_crossings(d, -lim, lim, 1e-5);
  // From the step: t_k - 0.403 for t_k in [0.378, 0.428]: k = 38..42 -> -0.023, -0.013, -0.003, 0.007, 0.017.
  // From the sample instants within the step's window (t_24 .. t_57): every whole sample, -0.02 .. 0.02.
  std::vector<double> want{-0.023, -0.02, -0.013, -0.01, -0.003, 0.0, 0.007, 0.01, 0.017, 0.02};
  ASSERT_EQ(c.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_NEAR(c[i], want[i], 3e-6) << i;
  // Merged: the two placements 4 µs apart are one crossing at their mean.
  EXPECT_NEAR(c[0], -0.02300 - 2e-6, 1e-9);
  // Nothing steps: no crossings; a step list of the wrong length is refused with the sizes.
  ContactData smooth;
  smooth.obs.t_s = d.obs.t_s;
  EXPECT_TRUE(delay_crossings(smooth, -lim, lim, 1e-5).empty());
  d.w_step.assign(50, 0.5);
  EXPECT_THROW(delay_crossings(d, -lim, lim, 1e-5), std::invalid_argument);
}

// contact_damping's penetration rates: from the pose slope on an axis only where it has less error
// than the reported twist (a coarse twist on a smooth motion), from the twist where the twist is
// finer, unquantised, or the motion turns within the slope's window.
TEST(ContactFamily, DampingRatesComeFromThePosesOnlyWhereTheyBeatTheTwist) {
  constexpr double pi = 3.14159265358979323846;
  // 4000 samples at 100 Hz of a smooth press (0.3 Hz, 1 mm) plus, optionally, a fast zig-zag.
  std::vector<double> t, truth_v;
  std::vector<double> x_exact;
  const auto motion = [&](double zigzag_m_per_s) {
    t.clear();
    truth_v.clear();
    x_exact.clear();
    double x = 0.0123;
    for (int k = 0; k < 4000; ++k) {
      t.push_back(0.01 * k);
      const double zz = zigzag_m_per_s * ((k / 5) % 2 == 0 ? 1.0 : -1.0);
      const double v = 1e-3 * 2 * pi * 0.3 * std::cos(2 * pi * 0.3 * t.back()) + zz;
      if (k > 0) x += 0.5 * (v + truth_v.back()) * 0.01;  // trapezoid: the slope's truth is the mean
      x_exact.push_back(x);
      truth_v.push_back(v);
    }
  };
  const auto quantise_all = [](std::vector<double> s, double q) {
    if (q > 0)
      for (auto& e : s) e = q * std::round(e / q);
    return s;
  };
  const auto rms_error = [&](const std::vector<double>& v) {
    double ss = 0.0;
    for (std::size_t k = 8; k + 8 < v.size(); ++k) ss += (v[k] - truth_v[k]) * (v[k] - truth_v[k]);
    return std::sqrt(ss / static_cast<double>(v.size() - 16));
  };
  motion(0.0);
  const auto x = quantise_all(x_exact, 2e-6);
  // A 2e-4 m/s twist (the paper's sensor): the slope, with a tenth of the twist's error.
  const RateChoice coarse = choose_rate(t, x, quantise_all(truth_v, 2e-4));
  EXPECT_TRUE(coarse.from_poses) << coarse.mse_ratio;
  EXPECT_NEAR(coarse.position_quantum_m, 2e-6, 1e-15);
  EXPECT_NEAR(coarse.velocity_quantum_m_per_s, 2e-4, 1e-15);
  EXPECT_LT(coarse.mse_ratio, 0.05);
  EXPECT_LT(rms_error(coarse.v_m_per_s), 0.1 * rms_error(quantise_all(truth_v, 2e-4)));
  // A 2e-5 m/s twist (the fine one): the estimated ratio is the slope's actual mean square error
  // over q²/12 (the twist's, as this motion crosses its levels). Quantisation is not white noise
  // where the motion turns slowly: the slope's error is 0.57 of the twist's, not the 0.25 of white
  // noise, so the estimate is taken from the data, not from the step.
  const RateChoice fine = choose_rate(t, x, quantise_all(truth_v, 2e-5), RateSource::poses);
  const double var_fine = 2e-5 * 2e-5 / 12.0;
  EXPECT_NEAR(fine.mse_ratio, std::pow(rms_error(fine.v_m_per_s), 2) / var_fine, 0.1);  // measured 0.59 for 0.57
  EXPECT_NEAR(std::pow(rms_error(quantise_all(truth_v, 2e-5)), 2) / var_fine, 1.0, 0.1);
  // Above half the twist's: left to the twist (the margin the choice keeps).
  EXPECT_FALSE(choose_rate(t, x, quantise_all(truth_v, 2e-5)).from_poses);
  EXPECT_NEAR(coarse.mse_ratio, std::pow(rms_error(coarse.v_m_per_s), 2) / (2e-4 * 2e-4 / 12.0), 0.02);
  // A 1e-6 m/s twist is finer than the slope's noise (2.9e-6 m/s): the twist, as reported.
  const auto v_finest = quantise_all(truth_v, 1e-6);
  const RateChoice finest = choose_rate(t, x, v_finest);
  EXPECT_FALSE(finest.from_poses);
  EXPECT_EQ(finest.v_m_per_s, v_finest);
  // An unquantised twist or unquantised positions: the noise is unknown, the twist stays.
  EXPECT_FALSE(choose_rate(t, x, truth_v).from_poses);
  EXPECT_FALSE(choose_rate(t, x_exact, quantise_all(truth_v, 2e-4)).from_poses);
  // A fast zig-zag (4 mm/s, reversing every 5 samples) the ± 8-sample window smooths away: the
  // smoothing bias is seen and the coarse twist, which follows it, stays.
  motion(4e-3);
  const auto zx = quantise_all(x_exact, 2e-6);
  const auto zv = quantise_all(truth_v, 2e-4);
  const RateChoice zigzag = choose_rate(t, zx, zv);
  EXPECT_FALSE(zigzag.from_poses) << zigzag.mse_ratio;
  EXPECT_GT(zigzag.mse_ratio, 0.5);
  EXPECT_GT(rms_error(windowed_slope(t, zx, kRateHalfWindow)), rms_error(zv));  // and rightly so
  // Forced either way.
  EXPECT_FALSE(choose_rate(t, x, quantise_all(truth_v, 2e-4), RateSource::twist).from_poses);
  EXPECT_TRUE(choose_rate(t, x, v_finest, RateSource::poses).from_poses);
  EXPECT_THROW(choose_rate(t, x, {1.0}), std::invalid_argument);
  EXPECT_THROW(choose_rate(t, x, truth_v, RateSource::automatic, 1), std::invalid_argument);
  auto bad = x;
  bad[17] = std::nan("");
  EXPECT_THAT([&] { (void)choose_rate(t, bad, truth_v); }, ThrowsMessage<std::invalid_argument>(HasSubstr("sample 17")));
  EXPECT_EQ(quantum_of(bad), 0.0);
  auto stalled = t;
  stalled[23] = stalled[22];  // a repeated time stamp: no slope can be taken across it
  EXPECT_THAT([&] { (void)choose_rate(stalled, x, truth_v); }, ThrowsMessage<std::invalid_argument>(HasSubstr("sample 23")));
}

// The same choice inside make_contact_data, per axis, on the ACU press: its commanded speeds sit on
// the 2e-4 m/s grid (the reported twist is nearly exact) and stop and reverse within the window, so
// the twist stays; forced, the slope is used, and the report says which.
TEST(ContactFamily, TheContactDataTakeTheirDampingRatesPerAxis) {
  const auto r = test::scene_run("acu_2a");
  auto m = test::measure(r, Effects{}, 1, false);
  const auto exact = m;
  for (auto& s : m)
    for (int a = 0; a < 3; ++a) {
      s.kin.T_world_ee.translation()(a) = 2e-6 * std::round(s.kin.T_world_ee.translation()(a) / 2e-6);
      s.kin.v_world_ee(a) = 2e-4 * std::round(s.kin.v_world_ee(a) / 2e-4);
    }
  const ContactData d = make_contact_data(r.scene, r.model.v_tm, m);
  EXPECT_EQ(d.rate_source(), "penetration rates from the reported twist");
  double twist_ss = 0.0, slope_ss = 0.0;
  const ContactData forced = make_contact_data(r.scene, r.model.v_tm, m, 0, 0, RateSource::poses);
  for (std::size_t k = 0; k < m.size(); ++k) {
    EXPECT_EQ(d.v_rate_world[k], d.kin[k].v_world_ee);
    twist_ss += (d.v_rate_world[k] - exact[k].kin.v_world_ee).squaredNorm();
    slope_ss += (forced.v_rate_world[k] - exact[k].kin.v_world_ee).squaredNorm();
  }
  EXPECT_LT(twist_ss, slope_ss);  // the choice was right
  for (std::size_t a = 0; a < 3; ++a) EXPECT_TRUE(forced.rate_from_poses[a]);
  EXPECT_THAT(forced.rate_source(), HasSubstr("penetration rates along x, y, z from the slope of the reported positions over +-8 samples"));
}

TEST(ContactFamily, ComplianceOfTheGeneratorIsSelfConsistent) {
  // The generator's deflected pose and the load it carries agree (fixed point), and a compliant
  // robot pushes less hard than a rigid one into the same commanded pose.
  const auto r = test::scene_run("press_slide");
  Effects e;
  inject_effect("robot_compliance", {{"C_z_z", 2e-6}}, e);
  const auto rigid = test::measure(r, {}, 1, false);
  const auto soft = test::measure(r, e, 1, false);
  double fz_rigid = 0, fz_soft = 0;
  for (std::size_t k = 0; k < rigid.size(); ++k) {
    fz_rigid = std::min(fz_rigid, rigid[k].w_fp(2));
    fz_soft = std::min(fz_soft, soft[k].w_fp(2));
  }
  // Springs in series: K_eff = K / (1 + K c).
  EXPECT_NEAR(fz_soft / fz_rigid, 1.0 / (1.0 + r.model.K * 2e-6), 0.02);
}

TEST(ContactFamily, UnknownExtensionsAndRunsWithoutContactAreClearErrors) {
  const auto r = test::scene_run("press_slide");
  const auto d = data_of(r, {});
  EXPECT_THAT([&] { ContactFamily(d, {"gravity"}); }, ThrowsMessage<std::invalid_argument>(HasSubstr("unknown extension 'gravity'")));
  auto m = test::measure(r, {}, 1, false);
  for (auto& s : m) s.kin.T_world_ee.translation().z() += 0.5;  // far above the block
  try {
    (void)make_contact_data(r.scene, r.model.v_tm, m);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& err) {
    EXPECT_NE(std::string(err.what()).find("no sample brings the objects into contact"), std::string::npos) << err.what();
  }
  m = test::measure(r, {}, 1, false);
  m[7].w_fp(1) = std::nan("");
  try {
    (void)make_contact_data(r.scene, r.model.v_tm, m);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& err) {
    EXPECT_NE(std::string(err.what()).find("sample 7"), std::string::npos) << err.what();
  }
  m = test::measure(r, {}, 1, false);
  m[9].kin.v_world_ee.z() = std::numeric_limits<double>::infinity();  // the twist too (the damping's rates read it)
  try {
    (void)make_contact_data(r.scene, r.model.v_tm, m);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& err) {
    EXPECT_NE(std::string(err.what()).find("sample 9"), std::string::npos) << err.what();
    EXPECT_NE(std::string(err.what()).find("non-finite value"), std::string::npos) << err.what();
  }
  m = test::measure(r, {}, 1, false);
  m[12].t_s = m[11].t_s;  // (the strict run reader refuses this first; the library says so too)
  try {
    (void)make_contact_data(r.scene, r.model.v_tm, m);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& err) {
    EXPECT_NE(std::string(err.what()).find("sample 12: time does not increase"), std::string::npos) << err.what();
  }
}

TEST(ContactFamily, ACompliancesFreeDirectionsCanMakeItPositiveSemiDefinite) {
  // Fitted coordinates C_xy = 2 with the diagonal unidentified (0): not PSD as it stands, but the
  // free diagonal can make it so. With nothing free, or only off-diagonal freedom against a
  // negative diagonal (the trace stays negative), it cannot.
  Matrix6d C = Matrix6d::Zero();
  C(0, 1) = C(1, 0) = 2.0;
  std::vector<Matrix6d> diag, off;
  for (int i = 0; i < 6; ++i) {
    Matrix6d E = Matrix6d::Zero();
    E(i, i) = 1.0;
    diag.push_back(E);
    for (int j = i + 1; j < 6; ++j) {
      Matrix6d F = Matrix6d::Zero();
      F(i, j) = F(j, i) = 1.0;
      off.push_back(F);
    }
  }
  EXPECT_NEAR(max_min_eigenvalue(C, {}), -2.0, 1e-12);
  EXPECT_GE(max_min_eigenvalue(C, diag), 0.0);
  EXPECT_LT(max_min_eigenvalue(-Matrix6d::Identity(), off), -0.5);
}

TEST(Generator, DrawsSeededEffectsAndRefusesUnknownOnes) {
  const auto r = test::scene_run("press_slide");
  Effects a, b, c;
  draw_effect("viscous_friction", 5, r.scene, a);
  draw_effect("viscous_friction", 5, r.scene, b);
  draw_effect("viscous_friction", 6, r.scene, c);
  EXPECT_EQ(a.truth_of("viscous_n_s_per_m", r.scene), b.truth_of("viscous_n_s_per_m", r.scene));
  EXPECT_NE(a.truth_of("viscous_n_s_per_m", r.scene), c.truth_of("viscous_n_s_per_m", r.scene));
  EXPECT_EQ(a.names(), std::vector<std::string>{"viscous_friction"});
  EXPECT_THAT([&] { draw_effect("magnetism", 1, r.scene, a); },
              ThrowsMessage<std::invalid_argument>(HasSubstr("unknown effect 'magnetism' (expected one of the diagnosis' candidates)")));
  // A candidate the generator cannot hide is said to be one, not called unknown.
  EXPECT_THAT([&] { draw_effect("slow_slip", 1, r.scene, a); },
              ThrowsMessage<std::invalid_argument>(
                  HasSubstr("effect 'slow_slip' is a diagnosis candidate the hidden-effect generator cannot hide")));
  EXPECT_THAT([&] { inject_effect("slow_slip", {}, a); }, ThrowsMessage<std::invalid_argument>(HasSubstr("cannot hide (it hides ")));
}

TEST(Diagnose, CandidatesFailingWithoutHeldOutDataAreScreenedAndSaySo) {
  // A clean press run: most candidates' parameters are not practically identifiable or their BIC
  // is not lower; their folds are skipped, the verdict says why, and nothing else changes.
  const auto r = test::scene_run("press_slide");
  const auto data = make_contact_data(r.scene, r.model.v_tm, test::measure(r, Effects{}, 31), r.force_scale_n, r.moment_scale_nm);
  const ModelFactory make = [&data](const std::set<std::string>& x) { return std::make_unique<ContactFamily>(data, x); };
  const Diagnosis d = diagnose(make, contact_extensions(), data.obs, {});
  EXPECT_EQ(d.cause, "none");
  int screened = 0;
  for (const auto& c : d.candidates) {
    if (!c.applicable) continue;  // never fitted (slow_slip: nothing slips below the threshold here)
    if (c.score.held_out()) {
      EXPECT_TRUE(std::isfinite(c.score.cv_error)) << c.name;
      continue;
    }
    ++screened;
    EXPECT_FALSE(c.supported);
    EXPECT_TRUE(std::isnan(c.gain_percent));
    EXPECT_NE(c.verdict.find("not scored on held-out data"), std::string::npos) << c.verdict;
    const bool fails = !(c.score.bic < d.nominal.bic) || c.pnr < 5.0 || !c.score.full.invalid.empty();
    EXPECT_TRUE(fails) << c.name << ": " << c.verdict;
  }
  EXPECT_GE(screened, 1);
  // Screened candidates rank after the scored ones.
  bool seen_screened = false;
  for (const auto& c : d.candidates) {
    if (!c.applicable) continue;
    if (!c.score.held_out()) seen_screened = true;
    else EXPECT_FALSE(seen_screened) << c.name << " ranked after a screened candidate";
  }
}

/// y = offset + α u + β v on every component, with the extensions "a" (α) and "b" (β) as asked.
class ConfoundedFamily : public ModelFamily {
 public:
  ConfoundedFamily(const Observations& o, std::set<std::string> ext) : o_(o), ext_(std::move(ext)) {}
  static double u(double t, int c) { return std::sin(2 * M_PI * 0.3 * t + c); }
  static double w(double t, int c) { return 0.245 * std::sin(2 * M_PI * 1.1 * t + 2 * c); }
  static double v(double t, int c) { return -u(t, c) + w(t, c); }  // mostly -u: confounded with "a"
  std::string name() const override { return "confounded"; }
  std::vector<Param> linear() const override {
    std::vector<Param> p{{"offset", "", 1, false}};
    if (ext_.count("a")) p.push_back({"alpha", "", 1, true});
    if (ext_.count("b")) p.push_back({"beta", "", 1, true});
    if (ext_.count("c"))
      for (Eigen::Index j = 0; j < patches(); ++j) p.push_back({"c" + std::to_string(j), "", 1, true});
    return p;
  }
  /// "c": one coefficient per 3 of the run's rows (row r belongs to coefficient r mod patches()),
  /// an extension that can fit a third of the noise on any run.
  Eigen::Index patches() const { return static_cast<Eigen::Index>(2 * o_.size()); }
  void design(const Eigen::VectorXd&, Eigen::MatrixXd& A, FamilyData&) const override {
    A.setZero(static_cast<Eigen::Index>(6 * o_.size()), static_cast<Eigen::Index>(linear().size()));
    for (std::size_t k = 0; k < o_.size(); ++k)
      for (int c = 0; c < 6; ++c) {
        const auto r = static_cast<Eigen::Index>(6 * k) + c;
        Eigen::Index j = 0;
        A(r, j++) = 1.0;
        if (ext_.count("a")) A(r, j++) = u(o_.t_s[k], c);
        if (ext_.count("b")) A(r, j++) = v(o_.t_s[k], c);
        if (ext_.count("c")) A(r, j + r % patches()) = 1.0;
      }
  }

 private:
  const Observations& o_;
  std::set<std::string> ext_;
};

/// y = 0.7 + u - s w + noise (σ 0.5): with s = 0.5, "a" (α u) and "b" (β v, v = -u + w) each leave
/// ±0.5 w and explain the run equally; with s = 0, "a" is exact and "b" leaves w.
/// `n` samples `dt_s` apart.
Observations confounded_data(double s, unsigned seed, int n = 2000, double dt_s = 0.01) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 0.5);
  Observations o;
  o.y.resize(n, 6);
  for (int k = 0; k < n; ++k) {
    const double t = dt_s * k;
    o.t_s.push_back(t);
    for (int c = 0; c < 6; ++c) o.y(k, c) = 0.7 + ConfoundedFamily::u(t, c) - s * ConfoundedFamily::w(t, c) + g(rng);
  }
  return o;
}

TEST(Diagnose, TwoCandidatesThatExplainTheRunEquallyAreSaidConfoundedWithTheEvidenceForEach) {
  {
    const Observations o = confounded_data(0.5, 23);
    const ModelFactory make = [&o](const std::set<std::string>& x) { return std::make_unique<ConfoundedFamily>(o, x); };
    const Diagnosis d = diagnose(make, {"a", "b"}, o, {});
    ASSERT_TRUE(d.cause == "a" || d.cause == "b") << d.cause;
    EXPECT_EQ(d.second_cause, "") << "the joint fit adds only 0.5 w, below the noise";
    ASSERT_EQ(d.confounded.size(), 1u);
    const Confounded& c = d.confounded.front();
    EXPECT_EQ(std::set<std::string>({c.cause, c.rival}), std::set<std::string>({"a", "b"}));
    EXPECT_LT(std::abs(c.z), 2.0);
    EXPECT_GT(c.cosine, 0.9);
    EXPECT_THAT(c.evidence, HasSubstr("alpha"));
    EXPECT_THAT(c.evidence, HasSubstr("beta"));
    EXPECT_THAT(c.experiment, HasSubstr("excites a and b differently"));  // neither toy effect knows one
  }
  {
    // "a" is the truth's form: "b" predicts worse beyond the paired test's reach.
    const Observations o = confounded_data(0.0, 23);
    const ModelFactory make = [&o](const std::set<std::string>& x) { return std::make_unique<ConfoundedFamily>(o, x); };
    const Diagnosis d = diagnose(make, {"a", "b"}, o, {});
    EXPECT_EQ(d.cause, "a");
    EXPECT_TRUE(d.confounded.empty()) << d.confounded.front().evidence;
  }
}

TEST(Diagnose, DelayAndDampingNameTheExperimentThatSeparatesThem) {
  EXPECT_THAT(separating_experiment("time_offset", "contact_damping"), HasSubstr("piecewise-linear"));
  EXPECT_EQ(separating_experiment("contact_damping", "time_offset"), separating_experiment("time_offset", "contact_damping"));
}

TEST(Diagnose, ASecondCauseConfoundedWithTheFirstIsSizedByItsHeldOutEffectInTheJointModel) {
  // Truth: α = 2, β = 1, i.e. y = 0.7 + u + w. "a" alone takes u (α = 1); "b" added to it moves α
  // to 2 and explains only w held out (0.12 noise variances, below the 0.25 a cause must explain),
  // but its effect in the joint model is β v, mostly the u that "a" had absorbed (2.1 noise
  // variances): each fold's held-out error grows by that much when β goes to 0 with α kept.
  const double sigma = 0.5;
  std::mt19937 rng(17);
  std::normal_distribution<double> g(0, sigma);
  Observations o;
  const int n = 2000;
  o.y.resize(n, 6);
  double v2 = 0.0;
  for (int k = 0; k < n; ++k) {
    const double t = 0.01 * k;
    o.t_s.push_back(t);
    for (int c = 0; c < 6; ++c) {
      o.y(k, c) = 0.7 + 2 * ConfoundedFamily::u(t, c) + ConfoundedFamily::v(t, c) + g(rng);
      v2 += ConfoundedFamily::v(t, c) * ConfoundedFamily::v(t, c) / (6.0 * n);
    }
  }
  const ModelFactory make = [&o](const std::set<std::string>& x) { return std::make_unique<ConfoundedFamily>(o, x); };
  const Diagnosis d = diagnose(make, {"a", "b"}, o, {});
  ASSERT_EQ(d.cause, "a");
  ASSERT_EQ(d.second_step.size(), 1u);
  const CandidateResult& b = d.second_step.front();
  EXPECT_TRUE(std::isnan(d.candidates.front().effect_fraction)) << "the first step is sized by its held-out reduction";
  EXPECT_LT(b.noise_fraction, 0.25) << b.verdict;
  EXPECT_NEAR(b.effect_fraction, v2 / (d.noise_relative * d.noise_relative), 0.1 * b.effect_fraction) << b.verdict;
  EXPECT_NEAR(b.effect_fraction_in_sample, v2 / (d.noise_relative * d.noise_relative), 0.1 * b.effect_fraction) << b.verdict;
  EXPECT_GT(b.effect_fraction, 1.0);
  EXPECT_EQ(d.second_cause, "b") << b.verdict;
  EXPECT_THAT(b.verdict, HasSubstr("its held-out effect in the joint model"));
  ASSERT_TRUE(d.extended.has_value());
  for (const auto& q : d.extended->full.reported) {
    if (q.name == "alpha") {
      EXPECT_NEAR(q.value, 2.0, 3 * q.std);
    }
    if (q.name == "beta") {
      EXPECT_NEAR(q.value, 1.0, 3 * q.std);
    }
  }
}

TEST(Score, AnEffectThatFitsTheNoiseHasANegativeHeldOutEffect) {
  // Truth: y = 0.7 + u + noise. Added to "a", "c" moves the fit's prediction by a third of the noise
  // variance on its own samples (each coefficient the mean of 3 rows' noise), more than the 0.25 a
  // cause must explain; on each fold's held-out rows it predicts worse, by about as much.
  const double sigma = 0.5;  // confounded_data's
  const int n = 300;
  const Observations o = confounded_data(0.0, 29, n, 0.05);
  const ConfoundedFamily m(o, {"a", "c"});
  CvOptions cv;
  for (const auto& p : m.linear())
    if (p.name != "offset" && p.name != "alpha") cv.effect_of.insert(p.name);
  ASSERT_EQ(cv.effect_of.size(), static_cast<std::size_t>(2 * n));
  const Score s = score(m, o, cv);
  // In-sample: the change of the full fit's prediction without "c", the offset re-solved.
  Eigen::VectorXd x(6 * n);
  for (Eigen::Index r = 0; r < x.size(); ++r) x(r) = s.full.theta(2 + r % m.patches());
  const double in_sample = (x.array() - x.mean()).square().mean() / (sigma * sigma);
  EXPECT_GT(in_sample, 0.25) << "in-sample it would pass as a cause's size";
  ASSERT_TRUE(std::isfinite(s.held_out_effect));
  EXPECT_LT(s.held_out_effect / (sigma * sigma), -0.25);
  // Without effect_of the folds size nothing.
  EXPECT_TRUE(std::isnan(score(ConfoundedFamily(o, {"a"}), o, {}).held_out_effect));
}

// --- the deflection family ----------------------------------------------------------------------

TEST(DeflectionFamily, NamesACompliantBaseAndNoneForARigidOne) {
  std::mt19937 rng(4);
  std::normal_distribution<double> g(0, 1);
  const int n = 1500;
  std::vector<double> t;
  std::vector<cid::Kinematics> kin_soft, kin_rigid;
  std::vector<Eigen::Matrix<double, 6, 1>> w;
  Matrix6d C = Matrix6d::Zero();
  C(3, 4) = C(4, 3) = 0;
  C(3, 3) = 4e-5;  // rad/(N m): tilt about x under a moment about x
  C(4, 4) = 2.5e-5;
  for (int k = 0; k < n; ++k) {
    const double tk = 0.01 * k;
    t.push_back(tk);
    Eigen::Matrix<double, 6, 1> wk;  // plate wrench: weight plus a swinging arm's moment
    wk << 2 * std::sin(tk), 1.5 * std::cos(0.7 * tk), -700, 40 * std::sin(0.9 * tk), 30 * std::cos(0.4 * tk), 3 * std::sin(tk);
    w.push_back(wk);
    // The load the body puts on its support: the plate's wrench (the plate is at the rest position).
    const Eigen::Matrix<double, 6, 1> load = wk;
    const Eigen::Matrix<double, 6, 1> dflt = C * load;
    cid::Kinematics ks, kr;
    Eigen::Matrix<double, 6, 1> noise;
    for (int i = 0; i < 6; ++i) noise(i) = (i < 3 ? 1e-5 : 1e-5) * g(rng);
    ks.T_world_ee.translation() = dflt.head<3>() + noise.head<3>();
    ks.T_world_ee.linear() =
        Eigen::AngleAxisd((dflt.tail<3>() + noise.tail<3>()).norm(), (dflt.tail<3>() + noise.tail<3>()).normalized()).toRotationMatrix();
    kr.T_world_ee.translation() = noise.head<3>();
    kr.T_world_ee.linear() = Eigen::AngleAxisd(noise.tail<3>().norm(), noise.tail<3>().normalized()).toRotationMatrix();
    kin_soft.push_back(ks);
    kin_rigid.push_back(kr);
  }
  const auto soft = make_deflection_data(t, kin_soft, w, Eigen::Isometry3d::Identity());
  const auto rigid = make_deflection_data(t, kin_rigid, w, Eigen::Isometry3d::Identity());
  auto factory = [](const DeflectionData& d) {
    return [&d](const std::set<std::string>& e) { return std::make_unique<DeflectionFamily>(d, e); };
  };
  const auto ds = diagnose(factory(soft), deflection_extensions(), soft.obs, {});
  EXPECT_EQ(ds.cause, "robot_compliance");
  EXPECT_GT(ds.gain_percent, 10.0);  // the translations are pure noise here: the gain is in the tilts
  for (const auto& q : ds.extended->full.reported)
    if (q.name == "C_rx_rx" || q.name == "C_ry_ry") {
      const double truth = q.name == "C_rx_rx" ? 4e-5 : 2.5e-5;
      EXPECT_LT(std::abs(q.value - truth), 3 * q.std) << q.name << " " << q.value << " ± " << q.std;
    }
  const auto dr = diagnose(factory(rigid), deflection_extensions(), rigid.obs, {});
  EXPECT_EQ(dr.cause, "none");
}

}  // namespace
}  // namespace hil::diagnose
