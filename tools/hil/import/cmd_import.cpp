// `hil import DATA --config MAP.yaml --out RUN`: marker-plus-force-plate CSV -> a run folder; with a
// config of `kind: calibration_run` and --rig, a lab's calibration table -> a calibration run (CSV).
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <fstream>
#include <iostream>

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
};

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
                                 "Turn a marker-plus-force-plate CSV (motion capture + force plate) into a run folder, or a calibration "
                                 "table into a calibration run (a config of kind calibration_run, with --rig)");
  static ImportArgs args;
  cmd->add_option("DATA", args.data, "the CSV (or other delimited) data file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--config", args.config, "mapping config (YAML, see docs/import.md)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", args.out, "run folder to write (run.yaml, samples.csv); a calibration run: the CSV file")->required();
  cmd->add_option("--rig", args.rig, "calibration runs: the rig whose robot the postures are of (its joint names and limits)");
  cmd->add_option("--rig-name", args.rig_name, "rig name written in run.yaml (default: the config's `rig`)");
  cmd->add_flag("--force", args.force, "overwrite the run files of an existing folder");
  cmd->callback([] { set_action([] { return run_import(args); }); });
}

}  // namespace hil::cli
