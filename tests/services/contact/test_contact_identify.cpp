// hil::services::contact: the whole identification of a run (`hil contact identify`, the demo and
// the Python module), as JSON and HTML, on the re-created ACU experiment.
#include <gtest/gtest.h>

#include <fstream>

#include <hil/services/contact_identify.hpp>
#include <hil/test/acu.hpp>
#include <hil/test/files.hpp>

namespace hil::contact_id::test {
namespace {

TEST(AcuCommand, IdentifyJsonAndReport) {
  hil::test::TempDir dir;
  const auto r = acu_run("2a", 40);
  ContactProblem p(r.scene, r.data, r.options);
  hil::services::contact::IdentifyOptions o;
  o.geometric = true;
  o.lambda = "auto";
  o.lcurve_points = 8;
  const auto res = hil::services::contact::identify(p, o);
  const auto j = hil::services::contact::to_json(p, res);
  for (const char* key : {"K", "K_std", "mu", "mu_std", "geometric", "lambda", "relative_force_error"}) EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["geometric"].size(), 9u);
  EXPECT_LT(j["relative_force_error"].get<double>(), j["relative_force_error_nominal"].get<double>());
  hil::services::contact::write_report(dir.path(), "2a", p, res);
  std::ifstream f(dir.path() + "/index.html");
  const std::string html((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_NE(html.find("L-curve"), std::string::npos);
  EXPECT_NE(html.find("Number of contact points"), std::string::npos);
}

TEST(AcuCommand, GeometricWithNothingObservableIsRefused) {
  // Test 2a with only the (weak) rotations declared: nothing to fit unless asked.
  auto r = acu_run("2a", 40);
  std::vector<Uncertainty> rot;
  for (const auto& u : r.scene.uncertainties)
    if (u.kind == Uncertainty::Kind::rotation) rot.push_back(u);
  r.scene.uncertainties = rot;
  ContactProblem p(r.scene, r.data, r.options);
  hil::services::contact::IdentifyOptions o;
  o.geometric = true;
  o.lambda = "0.01";
  try {
    hil::services::contact::identify(p, o);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no geometric uncertainty is observable"), std::string::npos) << e.what();
  }
  o.include_weak = true;
  EXPECT_NO_THROW(hil::services::contact::identify(p, o));
}

}  // namespace
}  // namespace hil::contact_id::test
