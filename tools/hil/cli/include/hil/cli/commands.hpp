#pragma once
// The command framework (hil_cli): each subcommand group registers itself on the root app. A handler returns the exit status;
// bad input is reported by throwing hil::error::FormatError (or std::runtime_error), which
// main() turns into one clear line on stderr and exit status 2.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace hil::cli {

/// Options every subcommand may use.
struct GlobalOptions {
  std::string log_level = "info";
  std::string dds_profile;
  std::string dds_profile_name = "hil_localhost";
  std::string dds_partition;  ///< --dds-partition: empty = none
  int dds_domain = -1;        ///< -1: $HIL_DDS_DOMAIN, else $ROS_DOMAIN_ID, else 0
  std::string secure;         ///< --secure KEYSTORE[:NAME]: DDS Security (participant.hpp)
  std::string secure_name;    ///< --secure-name: keystore participant (default: the command's role)
};
GlobalOptions& globals();

/// Set by the chosen subcommand; run by main() after parsing.
using Action = std::function<int()>;
void set_action(Action a);
/// The action set by the chosen subcommand (empty if none was).
const Action& action();

void add_validate(CLI::App& app);
void add_demo(CLI::App& app);
void add_stiffness(CLI::App& app);  // calibration (issue 4)
void add_calibrate(CLI::App& app);  // point calibration of a calibration run (issue 28)
void add_contact(CLI::App& app);    // contact identification (issue 5)
void add_rig(CLI::App& app);        // fake-rig, acquire (issue 3)
void add_echo(CLI::App& app);       // bus: print a topic
void add_replay(CLI::App& app);     // bus: publish a recorded run
void add_acquire(CLI::App& app);    // the rig service
void add_import(CLI::App& app);     // marker + force-plate CSV -> run (issue 6)
void add_diagnose(CLI::App& app);   // the diagnosis (issue 6)
void add_export(CLI::App& app);     // run -> MCAP (issue 13)
void add_keystore(CLI::App& app);   // DDS Security keystore (issue 15)

}  // namespace hil::cli
