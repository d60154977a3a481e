// hil: hardware-in-the-loop acquisition and identification for robotics labs.
#include <spdlog/cfg/helpers.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <exception>
#include <iostream>

#include <hil/cli/commands.hpp>
#include <hil/error/error.hpp>
#include "usage.hpp"

int main(int argc, char** argv) {
  using namespace hil::cli;
  CLI::App app{"hil: hardware-in-the-loop acquisition and identification for robotics labs\n"
               "Force plate over CAN, robot over Modbus, synchronized samples on DDS, stiffness and\n"
               "contact identification, and diagnosis of what a simulation gets wrong.",
               "hil"};
  app.set_version_flag("--version", std::string("hil ") + HIL_VERSION);
  app.require_subcommand(1);
  auto& g = globals();
  app.add_option("--log-level", g.log_level, "trace, debug, info, warn, error, critical or off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}))
      ->capture_default_str();
  app.add_option("--dds-profile", g.dds_profile, "Fast DDS XML profile file (default: hil's host-only profile)");
  app.add_option("--dds-profile-name", g.dds_profile_name, "participant profile in that file")->capture_default_str();
  app.add_option("--dds-domain", g.dds_domain, "DDS domain id (default: $HIL_DDS_DOMAIN, else $ROS_DOMAIN_ID, else 0)")
      ->check(CLI::Range(0, 232));
  app.add_option("--secure", g.secure, "DDS Security: keystore directory[:participant] (hil keystore; docs/security.md)");
  app.add_option("--secure-name", g.secure_name, "keystore participant for --secure (default: the command's role, e.g. replay)");

  add_validate(app);
  add_demo(app);
  add_stiffness(app);
  add_calibrate(app);
  add_contact(app);
  add_rig(app);
  add_echo(app);
  add_replay(app);
  add_acquire(app);
  add_import(app);
  add_diagnose(app);
  add_export(app);
  add_keystore(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return report_parse_error(app, e, std::cerr);  // 2, naming the bad word (0 for --help)
  }
  auto logger = spdlog::stderr_color_mt("hil");
  spdlog::set_default_logger(logger);
  spdlog::set_level(spdlog::level::from_str(g.log_level));
  spdlog::set_pattern("[%H:%M:%S.%e] [%^%l%$] %v");
  try {
    const auto& run = action();
    return run ? run() : 1;
  } catch (const hil::error::FormatError& e) {
    std::cerr << "error: " << e.what() << '\n';
    return kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
}
