// hil: hardware-in-the-loop acquisition and identification for robotics labs.
#include <spdlog/cfg/helpers.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <exception>
#include <functional>
#include <iostream>

#include <hil/allocator/retain.hpp>
#include <hil/cli/commands.hpp>
#include <hil/error/error.hpp>
#include "usage.hpp"

int main(int argc, char** argv) {
  hil::allocator::retain_freed_memory();  // before any thread: the diagnosis' matrices (core/allocator)
  using namespace hil::cli;
  CLI::App app{"hil: hardware-in-the-loop acquisition and identification for robotics labs\n"
               "Force plate over CAN, robot over Modbus, synchronized samples on DDS, stiffness and\n"
               "contact identification, and diagnosis of what a simulation gets wrong.",
               "hil"};
  app.set_version_flag("--version", std::string("hil ") + HIL_VERSION);
  app.require_subcommand(1);
  auto& g = globals();
  // The global options, on `hil` itself and (below) on every subcommand at every depth, bound to
  // the same variables: they may come before or after the subcommand and each --help lists them.
  auto add_globals = [&g](CLI::App& a) {
    a.add_option("--log-level", g.log_level, "trace, debug, info, warn, error, critical or off")
        ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}))
        ->capture_default_str();
    a.add_option("--dds-profile", g.dds_profile, "Fast DDS XML profile file (default: hil's host-only profile)");
    a.add_option("--dds-profile-name", g.dds_profile_name, "participant profile in that file")->capture_default_str();
    a.add_option("--dds-domain", g.dds_domain, "DDS domain id (default: $HIL_DDS_DOMAIN, else $ROS_DOMAIN_ID, else 0)")
        ->check(CLI::Range(0, 232));
    a.add_option("--dds-partition", g.dds_partition,
                 "DDS partition of every writer and reader: only participants in the same partition exchange data (default: none, "
                 "as ROS 2 nodes; hil demo: a private one)");
    a.add_option("--secure", g.secure, "DDS Security: keystore directory[:participant] (hil keystore; docs/security.md)");
    a.add_option("--secure-name", g.secure_name, "keystore participant for --secure (default: the command's role, e.g. replay)");
  };
  add_globals(app);

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
  std::function<void(CLI::App&)> globals_everywhere = [&](CLI::App& a) {
    // Option groups are subcommands to CLI11 too: only the commands get the globals.
    const auto commands = a.get_subcommands([](CLI::App* s) { return dynamic_cast<CLI::Option_group*>(s) == nullptr; });
    for (CLI::App* sub : commands) {
      add_globals(*sub->add_option_group("Global options", "also accepted before the subcommand"));
      globals_everywhere(*sub);
    }
  };
  globals_everywhere(app);

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
