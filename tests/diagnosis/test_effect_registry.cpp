// The effect registry (issue 26, item 2): an effect is one file. This fixture defines a toy effect
// here and nowhere else — a constant offset of the plate's fz — and shows it registered, listed,
// injected into a simulation, fitted, reported and checked by the contact family and named by the
// diagnosis; and that the built-in effects' lists (the CLI's, the hidden-effects schema's) and
// their injections are the registry's.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include <hil/diagnose/contact_family.hpp>
#include <hil/diagnose/deflection_family.hpp>
#include <hil/diagnose/diagnose.hpp>
#include <hil/diagnose/effect.hpp>
#include "scenes.hpp"

namespace hil::diagnose {
namespace {

using ::testing::HasSubstr;

// --- the toy effect: the whole of it -------------------------------------------------------------

/// fz_meas = fz + b: one linear parameter, a constant column in the fz rows.
class ToyFzOffsetTerm : public ContactTerm {
 public:
  std::vector<Param> linear() const override { return {{"toy_offset_fz_n", "N", 1.0, true}}; }
  void finish(const ContactSlots& s, const Eigen::VectorXd&, Eigen::MatrixXd& A) const override {
    for (Eigen::Index k = 0; k < A.rows() / 6; ++k) A(6 * k + 2, s.linear) = 1.0;
  }
  void report_derived(const ContactSlots& s, Eigen::Index, const Fit& f, std::vector<Reported>& out) const override {
    out.push_back({"toy_offset_fz_kn", "kN", f.theta(s.linear) / 1e3, std::sqrt(std::max(0.0, f.cov(s.linear, s.linear))) / 1e3, false});
  }
  std::string check_line(const Reported& q) const override {
    return q.name == "toy_offset_fz_n" && std::abs(q.value) > 1e3 ? "a toy offset beyond 1 kN is not physical" : "";
  }
};

/// Its part of the hidden-effect generator: the plate's fz reads b too much.
class ToyFzOffsetInjection : public ScalarInjection {
 public:
  explicit ToyFzOffsetInjection(double b) : ScalarInjection("toy_offset_fz_n", b, "the toy's fz offset, N") {}
  void sensor(hil::Vector6d& w) const override { w(2) += value(); }
};

class ToyFzOffset : public ContactEffect {
 public:
  std::string name() const override { return "toy_fz_offset"; }
  std::string description() const override { return "the plate's fz reads a constant too much (a toy)"; }
  std::shared_ptr<const ContactTerm> bind(const ContactBinding&) const override { return std::make_shared<ToyFzOffsetTerm>(); }
  bool injectable() const override { return true; }
  std::shared_ptr<const Injection> draw(unsigned seed, const contact_id::Scene&) const override {
    EffectDraw r(seed, name());
    return inject({{"toy_offset_fz_n", r.magnitude(4.0, 8.0)}});
  }
  std::shared_ptr<const Injection> inject(const TruthValues& v) const override {
    check_truth_keys(name(), v, {"toy_offset_fz_n"});
    return std::make_shared<ToyFzOffsetInjection>(truth_value(v, "toy_offset_fz_n"));
  }
};

const bool toy_registered = register_effect(std::make_shared<ToyFzOffset>());

// --- what the registry gives it ------------------------------------------------------------------

TEST(EffectRegistry, ATestFixtureEffectIsRegisteredAndListedAfterTheBuiltInOnes) {
  ASSERT_TRUE(toy_registered);
  const auto& contact = contact_extensions();
  ASSERT_FALSE(contact.empty());
  EXPECT_EQ(contact.front(), "geometric_offset");
  EXPECT_EQ(contact.back(), "toy_fz_offset");
  EXPECT_EQ(describe_extension("toy_fz_offset"), "the plate's fz reads a constant too much (a toy)");
  const auto& deflection = deflection_extensions();
  EXPECT_EQ(std::count(deflection.begin(), deflection.end(), "toy_fz_offset"), 0);
  ASSERT_NE(find_effect("toy_fz_offset"), nullptr);
  EXPECT_EQ(find_effect("toy_fz_offset")->cv_offsets(), 1);
  EXPECT_THAT([] { register_effect(std::make_shared<ToyFzOffset>()); },
              ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("'toy_fz_offset' is registered already")));
  // Injectable from its file alone: drawn by seed, its truth by the name the fit reports.
  Effects e;
  draw_effect("toy_fz_offset", 1, {}, e);
  EXPECT_EQ(e.names(), std::vector<std::string>{"toy_fz_offset"});
  const auto b = e.truth_of("toy_offset_fz_n", {});
  ASSERT_TRUE(b);
  EXPECT_GE(std::abs(*b), 4.0);
  EXPECT_LT(std::abs(*b), 8.0);
  EXPECT_THROW(draw_effect("gravity", 1, {}, e), std::invalid_argument);
}

TEST(EffectRegistry, TheBuiltInListsAreTheRegistrys) {
  EXPECT_EQ(std::vector<std::string>(contact_extensions().begin(), contact_extensions().end() - 1),
            (std::vector<std::string>{"geometric_offset", "robot_compliance", "time_offset", "sensor_bias", "sensor_gain",
                                      "viscous_friction", "slow_slip", "contact_damping", "nonlinear_stiffness"}));
  EXPECT_EQ(deflection_extensions(), (std::vector<std::string>{"robot_compliance", "time_offset", "rest_change"}));
  // Repeated blocked CV: asked for by rest_change (its events), by nothing else.
  EXPECT_EQ(default_cv_offsets({"robot_compliance", "time_offset"}), 1);
  EXPECT_EQ(default_cv_offsets({"robot_compliance", "rest_change"}), 8);
  EXPECT_TRUE(find_effect("rest_change")->locates_events());
  EXPECT_EQ(describe_extension("none"), "no extension predicts held-out data better than the nominal model beyond the noise");
  EXPECT_EQ(describe_extension("gravity"), "");
}

TEST(EffectRegistry, EveryFileOfTheEffectsFolderIsABuiltInEffectOfItsName) {
  // A built-in effect is its file: the build lists diagnosis/src/effects/ and generates the
  // built-ins from it, so the registry holds exactly one effect per file, named after it, in the
  // effects' own list order.
  std::vector<std::string> files;
  for (const auto& f : std::filesystem::directory_iterator(std::string(HIL_SOURCE_DIR) + "/diagnosis/src/effects"))
    if (f.path().extension() == ".cpp") files.push_back(f.path().stem().string());
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 11u);
  std::vector<std::string> built_in;
  for (const auto& e : builtin_effects()) built_in.push_back(e->name());
  std::sort(built_in.begin(), built_in.end());
  EXPECT_EQ(built_in, files);
  const auto all = registered_effects();
  ASSERT_GE(all.size(), files.size());
  for (std::size_t i = 0; i + 1 < files.size(); ++i)
    EXPECT_LT(std::make_pair(all[i]->list_order(), all[i]->name()), std::make_pair(all[i + 1]->list_order(), all[i + 1]->name()))
        << all[i]->name() << " before " << all[i + 1]->name();
}

TEST(EffectRegistry, TheHiddenEffectsSchemaListsTheInjectableEffectsAndTheirFields) {
  std::ifstream in(std::string(HIL_SOURCE_DIR) + "/docs/schemas/hil.hidden_effects.schema.json");
  ASSERT_TRUE(in) << "docs/schemas/hil.hidden_effects.schema.json";
  const auto schema = nlohmann::json::parse(in);
  const auto listed = schema["properties"]["effects"]["items"]["enum"].get<std::vector<std::string>>();
  std::vector<std::string> injectable;  // the built-in ones (this file's toy is not in the schema)
  for (const Effect* e : registered_effects())
    if (e->contact() && e->contact()->injectable() && e->name() != "toy_fz_offset") injectable.push_back(e->name());
  EXPECT_EQ(listed, injectable);
  // Every field an effect writes, drawn or absent, is a required property of the schema.
  const auto required = schema["required"].get<std::vector<std::string>>();
  auto check = [&](const Effects& e) {
    for (const auto& f : truth_file_fields(e)) {
      if (f.key == "toy_offset_fz_n") continue;
      EXPECT_TRUE(schema["properties"].contains(f.key)) << f.key;
      EXPECT_NE(std::find(required.begin(), required.end(), f.key), required.end()) << f.key;
    }
  };
  check(Effects{});
  Effects all;
  const auto r = test::scene_run("acu_2a");
  for (const auto& n : injectable) draw_effect(n, 3, r.scene, all);
  check(all);
  EXPECT_EQ(all.names(), injectable);
}

TEST(EffectRegistry, AnEffectInjectedAtZeroMagnitudeChangesNoSimulatedSample) {
  // Each injection's hooks are its own: at zero magnitude (inject({})) every effect leaves the
  // generator's output as it is without it, bit for bit; drawn, each changes it.
  const auto r = test::scene_run("acu_2a");
  const auto none = test::measure(r, {}, 5);
  Effects zero;
  for (const Effect* x : registered_effects())
    if (x->contact() && x->contact()->injectable()) inject_effect(x->name(), {}, zero);
  const auto same = test::measure(r, zero, 5);
  ASSERT_EQ(same.size(), none.size());
  for (std::size_t k = 0; k < none.size(); ++k) {
    ASSERT_EQ(same[k].w_fp, none[k].w_fp) << "sample " << k;
    ASSERT_EQ(same[k].kin.T_world_ee.matrix(), none[k].kin.T_world_ee.matrix()) << "sample " << k;
  }
  for (const Effect* x : registered_effects()) {
    if (!x->contact() || !x->contact()->injectable()) continue;
    Effects one;
    draw_effect(x->name(), 9, r.scene, one);
    const auto drawn = test::measure(r, one, 5);
    double moved = 0.0;
    for (std::size_t k = 0; k < none.size(); ++k) moved = std::max(moved, (drawn[k].w_fp - none[k].w_fp).cwiseAbs().maxCoeff());
    EXPECT_GT(moved, 0.0) << x->name();
  }
  // A true value it does not know is refused with its name.
  Effects e;
  EXPECT_THAT(
      [&] {
        inject_effect("time_offset", {{"time_ofset_s", 0.01}}, e);
      },
      ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("time_offset: no true value 'time_ofset_s'")));
}

// --- fitted, reported, checked, named ------------------------------------------------------------

// --- physical validity of the built-in candidates' fits --------------------------------------------

/// The fit of `candidate` on a scene's run with `injected` hidden in it (hil's own injection:
/// the check's own inputs, not a blind test).
struct Checked {
  ContactData data;
  Fit fit;
};
Checked fitted(const std::string& scene, const std::string& candidate, const std::string& injected, const TruthValues& truth) {
  const auto r = test::scene_run(scene);
  Effects e;
  inject_effect(injected, truth, e);
  Checked c{make_contact_data(r.scene, r.model.v_tm, test::measure(r, e, 11), r.force_scale_n, r.moment_scale_nm), {}};
  std::vector<int> all(c.data.obs.size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = static_cast<int>(k);
  c.fit = fit(ContactFamily(c.data, {candidate}), c.data.obs, all);
  return c;
}
Reported& line_of(Fit& f, const std::string& name) {
  const auto it = std::find_if(f.reported.begin(), f.reported.end(), [&](const Reported& q) { return q.name == name; });
  if (it == f.reported.end()) throw std::runtime_error("no line " + name);
  return *it;
}

// The friction the damping adds is μ_D D with μ_D >= 0, and none without a damping force: a fit of
// a real damping whose friction follows the total normal force passes; the same fit with no
// damping force (D ~ 0) behind the friction is refused. μ_D D >= 0 is a bound of the fit, not a
// check: a damping whose friction follows the elastic force only (μ_D D = 0) is fitted with it
// held at 0 (listed as having run to its bound) or read above 0, never below.
TEST(EffectChecks, TheDampingsFrictionIsNotNegativeAndNeedsADampingForce) {
  // ACU test 2a: its feet slide while they press (press_slide's do not, and its friction column is
  // not identifiable).
  auto c = fitted("acu_2a", "contact_damping", "contact_damping", {{"damping_n_s_per_m", 4000.0}, {"damping_friction", 1.0}});
  const ContactFamily fam(c.data, {"contact_damping"});
  Fit& f = c.fit;
  Reported& D = line_of(f, "damping_n_s_per_m");
  Reported& df = line_of(f, "damping_friction_n_s_per_m");
  EXPECT_NEAR(D.value, 4000.0, 400.0);
  EXPECT_GT(df.value, 4.0 * df.std);
  EXPECT_EQ(fam.check(f), "") << "df " << df.value << ", D " << D.value;
  df.value = 0.0;  // friction on the elastic force only
  EXPECT_EQ(fam.check(f), "");
  df.value = 3000.0;
  D.value = 0.5 * D.std;  // friction without a damping force
  EXPECT_THAT(fam.check(f), HasSubstr("with no damping force to carry it"));
  D.value = 3.0 * D.std;
  EXPECT_EQ(fam.check(f), "");

  auto e = fitted("acu_2a", "contact_damping", "contact_damping", {{"damping_n_s_per_m", 4000.0}, {"damping_friction", 0.0}});
  bool held = false;
  for (const auto& u : e.fit.unidentifiable)
    held = held || (u.name == "damping_friction_n_s_per_m" && u.reason.find("bound") != std::string::npos);
  for (const auto& q : e.fit.reported)
    if (q.name == "damping_friction_n_s_per_m") {
      EXPECT_FALSE(held);
      EXPECT_GE(q.value, 0.0);
    }
  const ContactFamily elastic(e.data, {"contact_damping"});
  const auto lin = elastic.linear();
  for (std::size_t j = 0; j < lin.size(); ++j) {
    if (lin[j].name == "damping_friction_n_s_per_m") {
      EXPECT_GE(e.fit.theta(static_cast<Eigen::Index>(j)), 0.0);  // never below its bound
    }
  }
  EXPECT_EQ(elastic.check(e.fit), "");
}

// A gain beyond the plate's calibration tolerance (ContactData::plate_gain_tolerance) by more than
// two of its reported std is not physical; within it, or with the tolerance declared wider, it is.
TEST(EffectChecks, APlateGainBeyondItsCalibrationToleranceIsRefused) {
  auto c = fitted("press_slide", "sensor_gain", "sensor_gain", {{"gain_fx", 0.05}});
  Fit& f = c.fit;
  EXPECT_EQ(ContactFamily(c.data, {"sensor_gain"}).check(f), "");
  Reported* g = nullptr;
  for (auto& q : f.reported)
    if (q.name.rfind("gain_", 0) == 0 && !g) g = &q;
  ASSERT_NE(g, nullptr);
  g->value = -(0.15 + 2.0 * g->std + 0.01);
  // In the candidates' screen (no folds yet: std_folds 0) the bound is not checked; on the reported
  // std, once the folds' spread is in it, it is.
  ASSERT_EQ(g->std_folds, 0.0);
  EXPECT_EQ(ContactFamily(c.data, {"sensor_gain"}).check(f), "");
  g->std_folds = g->std;
  EXPECT_THAT(ContactFamily(c.data, {"sensor_gain"}).check(f), HasSubstr("beyond the plate's calibration tolerance ± 0.15"));
  g->value = -(0.15 + 2.0 * g->std - 0.01);
  EXPECT_EQ(ContactFamily(c.data, {"sensor_gain"}).check(f), "");
  g->value = -0.4;
  c.data.plate_gain_tolerance = 0.5;
  EXPECT_EQ(ContactFamily(c.data, {"sensor_gain"}).check(f), "");
}

TEST(EffectRegistry, AToyEffectIsFittedReportedCheckedAndNamed) {
  const auto r = test::scene_run("press_slide");
  Effects e;
  inject_effect("toy_fz_offset", {{"toy_offset_fz_n", 6.0}}, e);  // fz reads 6 N too much: its own injection
  const auto data = make_contact_data(r.scene, r.model.v_tm, test::measure(r, e, 7), r.force_scale_n, r.moment_scale_nm);

  const ContactFamily fam(data, {"toy_fz_offset"});
  EXPECT_EQ(fam.name(), "toy_fz_offset");
  ASSERT_EQ(fam.linear().size(), 3u);
  EXPECT_EQ(fam.linear()[2].name, "toy_offset_fz_n");
  std::vector<int> all(data.obs.size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = static_cast<int>(k);
  Fit f = fit(fam, data.obs, all);
  const auto line = [&](const std::string& name) {
    const auto it = std::find_if(f.reported.begin(), f.reported.end(), [&](const Reported& q) { return q.name == name; });
    return it == f.reported.end() ? std::optional<Reported>{} : std::optional<Reported>{*it};
  };
  ASSERT_TRUE(line("toy_offset_fz_n"));
  EXPECT_NEAR(line("toy_offset_fz_n")->value, 6.0, 3 * line("toy_offset_fz_n")->std + 0.05);
  EXPECT_TRUE(line("toy_offset_fz_n")->extension);
  ASSERT_TRUE(line("toy_offset_fz_kn"));  // its derived line, after the parameters
  EXPECT_DOUBLE_EQ(line("toy_offset_fz_kn")->value, line("toy_offset_fz_n")->value / 1e3);
  EXPECT_EQ(fam.check(f), "");
  for (auto& q : f.reported)
    if (q.name == "toy_offset_fz_n") q.value = 2e3;
  EXPECT_EQ(fam.check(f), "a toy offset beyond 1 kN is not physical");

  // With another effect: the layout puts the toy after the built-in ones.
  const ContactFamily both(data, {"viscous_friction", "toy_fz_offset"});
  EXPECT_EQ(both.name(), "viscous_friction+toy_fz_offset");
  ASSERT_EQ(both.linear().size(), 4u);
  EXPECT_EQ(both.linear()[3].name, "toy_offset_fz_n");

  const ModelFactory make = [&data](const std::set<std::string>& x) { return std::make_unique<ContactFamily>(data, x); };
  const Diagnosis d = diagnose(make, {"viscous_friction", "toy_fz_offset"}, data.obs, {});
  EXPECT_EQ(d.cause, "toy_fz_offset");
  ASSERT_TRUE(d.extended);
  EXPECT_GT(d.gain_percent, 2.0);
}

}  // namespace
}  // namespace hil::diagnose
