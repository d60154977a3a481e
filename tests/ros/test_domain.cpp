// The DDS domain: --dds-domain, else $HIL_DDS_DOMAIN (hil's own variable wins), else
// $ROS_DOMAIN_ID, else 0; a bad value is a FormatError naming its variable.
#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <cstdlib>
#include <optional>
#include <string>

#include <hil/dds/bus.hpp>
#include <hil/error/error.hpp>
#include <hil/test/files.hpp>

using hil::dds::domain_from;
using testing::HasSubstr;

namespace {
// Sets (or unsets) an environment variable for one scope.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value) setenv(name, value, 1);
    else unsetenv(name);
  }
  ~ScopedEnv() {
    if (old_) setenv(name_, old_->c_str(), 1);
    else unsetenv(name_);
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

std::string error_of(const char* hil, const char* ros) {
  try {
    domain_from(hil, ros, 0);
  } catch (const hil::error::FormatError& e) {
    return e.what();
  }
  return "no error";
}
}  // namespace

TEST(DdsDomain, HilsVariableWinsOverRosWhichWinsOverTheFallback) {
  EXPECT_EQ(domain_from(nullptr, nullptr, 0), 0);
  EXPECT_EQ(domain_from(nullptr, nullptr, 17), 17);
  EXPECT_EQ(domain_from(nullptr, "7", 0), 7);
  EXPECT_EQ(domain_from("5", nullptr, 0), 5);
  EXPECT_EQ(domain_from("5", "7", 0), 5);
  EXPECT_EQ(domain_from("", "7", 0), 7) << "an empty variable counts as unset";
  EXPECT_EQ(domain_from("", "", 3), 3);
  EXPECT_EQ(domain_from("0", "9", 3), 0);
  EXPECT_EQ(domain_from("232", nullptr, 0), 232);
  EXPECT_EQ(domain_from("12", "not a number", 0), 12) << "ROS_DOMAIN_ID is not read when hil's variable is set";
}

TEST(DdsDomain, ABadValueNamesItsVariable) {
  for (const char* bad : {"233", "-1", "1.5", " 3", "3 ", "+3", "abc", "0x10", "99999999999999999999"}) {
    EXPECT_THAT(error_of(bad, nullptr), HasSubstr("$HIL_DDS_DOMAIN")) << bad;
    EXPECT_THAT(error_of(bad, nullptr), HasSubstr(std::string("'") + bad + "'")) << bad;
    EXPECT_THAT(error_of(bad, nullptr), HasSubstr("0..232")) << bad;
    EXPECT_THAT(error_of(nullptr, bad), HasSubstr("$ROS_DOMAIN_ID")) << bad;
    EXPECT_THAT(error_of("", bad), HasSubstr("$ROS_DOMAIN_ID")) << bad;
  }
}

TEST(DdsDomain, FromTheEnvironmentAndTheCommandLine) {
  {
    ScopedEnv hil("HIL_DDS_DOMAIN", nullptr), ros("ROS_DOMAIN_ID", nullptr);
    EXPECT_EQ(hil::dds::domain_from_env(), 0);
    EXPECT_EQ(hil::dds::resolve_domain(-1), 0);
    EXPECT_EQ(hil::dds::resolve_domain(42), 42);
  }
  {
    ScopedEnv hil("HIL_DDS_DOMAIN", nullptr), ros("ROS_DOMAIN_ID", "31");
    EXPECT_EQ(hil::dds::domain_from_env(), 31);
    EXPECT_EQ(hil::dds::resolve_domain(-1), 31);
    EXPECT_EQ(hil::dds::resolve_domain(4), 4) << "--dds-domain wins over both variables";
  }
  {
    ScopedEnv hil("HIL_DDS_DOMAIN", "21"), ros("ROS_DOMAIN_ID", "31");
    EXPECT_EQ(hil::dds::domain_from_env(), 21);
    EXPECT_EQ(hil::dds::resolve_domain(-1), 21);
  }
  {
    ScopedEnv hil("HIL_DDS_DOMAIN", nullptr), ros("ROS_DOMAIN_ID", "300");
    EXPECT_TRUE(hil::test::fails_with([] { hil::dds::domain_from_env(); }, 0, "",
                                      "$ROS_DOMAIN_ID: expected a DDS domain id, an integer 0..232, found '300'"));
    EXPECT_EQ(hil::dds::resolve_domain(4), 4) << "the variables are not read when --dds-domain is given";
  }
}
