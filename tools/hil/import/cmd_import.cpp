// `hil import DATA --config MAP.yaml --out RUN`: marker-plus-force-plate CSV -> a run folder; with a
// config of `kind: calibration_run` and --rig, a lab's calibration table -> a calibration run (CSV).
// `hil import BAG --rig RIG --out RUN [--wrench T --pose T --joints T]`: an MCAP file or a ros2 bag
// folder of standard ROS 2 topics -> a run folder, synchronised as an acquisition is.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <fstream>
#include <iostream>

#include <fmt/ranges.h>

#include <hil/acquisition/ros_import.hpp>
#include <hil/cli/commands.hpp>
#include <hil/error/error.hpp>
#include <hil/format/calibration_run.hpp>
#include <hil/format/rig.hpp>
#include <hil/format/run.hpp>
#include <hil/import/calibration_import.hpp>
#include <hil/import/config.hpp>
#include <hil/import/importer.hpp>

namespace hil::cli {
namespace fs = std::filesystem;

namespace {

struct ImportArgs {
  std::string data, config, out, rig_name, rig;
  bool force = false;
  acquisition::RosImportOptions ros;
};

bool is_ros_recording(const std::string& path) {
  return fs::path(path).extension() == ".mcap" || (fs::is_directory(path) && fs::exists(fs::path(path) / "metadata.yaml"));
}

int import_ros(const ImportArgs& a) {
  if (!a.config.empty()) throw error::FormatError({"command line", 0, 0, "--config"}, "a ROS recording takes topics, not --config");
  if (a.rig.empty()) throw error::FormatError({"command line", 0, 0, "--rig"}, "a ROS recording is imported for a rig: give --rig RIG");
  if (a.force) throw error::FormatError({"command line", 0, 0, "--force"}, "a ROS recording is imported into a new or empty folder only");
  const auto rig = format::load_rig(a.rig);
  std::ifstream in(a.rig, std::ios::binary);
  const std::string rig_text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto files = acquisition::load_ros_recording(a.data);
  const auto rep = acquisition::import_ros_recording(files, a.ros, rig, rig_text, a.out);
  const auto check = format::load_run(a.out);  // what readers will see: must pass the strict reader
  std::cout << fmt::format("imported {} -> {} (rig '{}', {} samples at {} Hz)\n", a.data, a.out, rig.name, check.samples.size(),
                           a.ros.output_rate_hz);
  std::cout << fmt::format("  {}: {} wrench messages, {} Hz{}\n", a.ros.wrench_topic, rep.wrenches, rep.wrench_rate_hz,
                           a.ros.wrench_rate_hz > 0 ? "" : " (measured)");
  std::cout << fmt::format("  {}: {} pose messages\n", a.ros.pose_topic, rep.poses);
  if (!a.ros.joints_topic.empty())
    std::cout << fmt::format("  {}: {} joint states ({})\n", a.ros.joints_topic, rep.joint_states, fmt::join(rep.joint_names, ", "));
  if (rep.gaps > 0) std::cout << fmt::format("  {} gaps in the wrench stream (flagged in the quality column)\n", rep.gaps);
  return 0;
}

int import_calibration_run(const ImportArgs& a) {
  if (a.rig.empty()) throw error::FormatError({a.config, 0, 0, "kind"}, "a calibration run is imported for a robot: give --rig RIG");
  const auto cfg = hil::import::load_calibration_import_config(a.config);
  const auto rig = format::load_rig(a.rig);
  if (!rig.robot) throw error::FormatError({a.rig, 0, 0, "robot"}, "the rig has no robot");
  if (fs::exists(a.out) && !a.force) throw std::runtime_error(a.out + ": exists (use --force to overwrite it)");
  const auto table = hil::import::read_delimited(a.data, cfg.delimiter, cfg.header, cfg.columns);
  const std::string text = hil::import::import_calibration_table(table, cfg, *rig.robot);
  // What readers will see: the strict reader must take it before it is written.
  const auto run = format::parse_calibration_run(text, a.out, *rig.robot);
  {
    std::ofstream out(a.out, std::ios::binary | std::ios::trunc);
    out << text;
    if (!out) throw std::runtime_error(a.out + ": cannot write");
  }
  std::cout << fmt::format("imported {} -> {} ({} postures of robot '{}', {} station(s){})\n", a.data, a.out, run.postures.size(),
                           rig.robot->name, run.stations.size(), run.has_orientation ? ", full poses" : "");
  return 0;
}

int run_import(const ImportArgs& a) {
  if (is_ros_recording(a.data)) return import_ros(a);
  if (a.config.empty())
    throw error::FormatError({"command line", 0, 0, "--config"}, "a CSV is imported with a mapping: give --config MAP.yaml");
  if (hil::import::import_config_kind(a.config) == "calibration_run") return import_calibration_run(a);
  const auto cfg = hil::import::load_import_config(a.config);
  if (fs::exists(a.out) && !(fs::is_directory(a.out) && fs::is_empty(a.out)) && !a.force)
    throw std::runtime_error(a.out + ": exists and is not an empty folder (use --force to overwrite its run files)");
  const auto table = hil::import::read_delimited(a.data, cfg.delimiter, cfg.header, cfg.columns);
  const auto run = hil::import::import_table(table, cfg, a.rig_name);
  hil::import::write_imported_run(a.out, run);
  const auto check = format::load_run(a.out);  // what readers will see: must pass the strict reader
  std::cout << fmt::format("imported {} -> {} (rig '{}', {} samples, {:.2f} Hz)\n", a.data, a.out, run.info.rig, check.samples.size(),
                           run.info.output_rate_hz);
  std::cout << hil::import::report_text(run.report);
  return 0;
}

}  // namespace

void add_import(CLI::App& app) {
  auto* cmd = app.add_subcommand("import",
                                 "Turn a marker-plus-force-plate CSV (motion capture + force plate) into a run folder, a calibration "
                                 "table into a calibration run (a config of kind calibration_run, with --rig), or a ROS 2 recording "
                                 "(.mcap, or a ros2 bag folder) of standard topics into a run folder (with --rig)");
  static ImportArgs args;
  cmd->add_option("DATA", args.data, "the CSV (or other delimited) data file; an .mcap file or a ros2 bag folder (metadata.yaml)")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("--config", args.config, "mapping config (YAML, see docs/import.md); not for a ROS recording")->check(CLI::ExistingFile);
  auto* ros = cmd->add_option_group("ROS 2 recordings", "an .mcap file or a ros2 bag folder (docs/import.md)");
  ros->add_option("--wrench", args.ros.wrench_topic, "geometry_msgs/WrenchStamped topic, in the force plate's frame")
      ->capture_default_str();
  ros->add_option("--pose", args.ros.pose_topic, "geometry_msgs/PoseStamped topic: the end effector in world")->capture_default_str();
  ros->add_option("--joints", args.ros.joints_topic, "sensor_msgs/JointState topic (default: none)");
  ros->add_option("--rate", args.ros.output_rate_hz, "output rate (Hz); must divide the wrench rate")->capture_default_str();
  ros->add_option("--wrench-rate", args.ros.wrench_rate_hz, "the wrench stream's nominal rate (Hz); default: measured from its stamps");
  cmd->add_option("--out", args.out, "run folder to write (run.yaml, samples.csv); a calibration run: the CSV file")->required();
  cmd->add_option("--rig", args.rig,
                  "calibration runs: the rig whose robot the postures are of (its joint names and limits); ROS recordings: the rig "
                  "(copied into the run)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--rig-name", args.rig_name, "rig name written in run.yaml (default: the config's `rig`)");
  cmd->add_flag("--force", args.force, "overwrite the run files of an existing folder");
  cmd->callback([] { set_action([] { return run_import(args); }); });
}

}  // namespace hil::cli
