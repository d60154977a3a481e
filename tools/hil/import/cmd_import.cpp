// `hil import DATA --config MAP.yaml --out RUN`: marker-plus-force-plate CSV -> a run folder.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <iostream>

#include <hil/cli/commands.hpp>
#include <hil/format/run.hpp>
#include <hil/import/config.hpp>
#include <hil/import/importer.hpp>

namespace hil::cli {
namespace fs = std::filesystem;

namespace {

struct ImportArgs {
  std::string data, config, out, rig_name;
  bool force = false;
};

int run_import(const ImportArgs& a) {
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
  auto* cmd = app.add_subcommand("import", "Turn a marker-plus-force-plate CSV (motion capture + force plate) into a run folder");
  static ImportArgs args;
  cmd->add_option("DATA", args.data, "the CSV (or other delimited) data file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--config", args.config, "mapping config (YAML, see docs/import.md)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", args.out, "run folder to write (run.yaml, samples.csv)")->required();
  cmd->add_option("--rig-name", args.rig_name, "rig name written in run.yaml (default: the config's `rig`)");
  cmd->add_flag("--force", args.force, "overwrite the run files of an existing folder");
  cmd->callback([] { set_action([] { return run_import(args); }); });
}

}  // namespace hil::cli
