// `hil validate PATH`: checks a run folder, a rig file, run.yaml or samples.csv and summarises it.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "hil/format/run.hpp"
#include "summary.hpp"

namespace hil::cli {
namespace fs = std::filesystem;

int validate(const std::string& path, const std::string& rig_path) {
  if (!fs::exists(path)) throw std::runtime_error(path + ": no such file or folder");
  if (fs::is_directory(path)) {
    const auto run = format::load_run(path, rig_path);
    std::cout << fmt::format("run {}: OK\n", path);
    print_run_summary(std::cout, run);
    return 0;
  }
  const auto name = fs::path(path).filename().string();
  if (name == "run.yaml") {
    const auto info = format::load_run_info(path);
    std::cout << fmt::format("run.yaml {}: OK (rig '{}', started {}, output {} Hz, {} sources)\n", path, info.rig,
                             info.start_time_utc, info.output_rate_hz, info.sources.size());
    return 0;
  }
  const auto ext = fs::path(path).extension().string();
  if (ext == ".csv") {
    const auto table = format::read_samples(path);
    std::cout << fmt::format("samples {}: OK\n", path);
    print_samples_summary(std::cout, table);
    return 0;
  }
  if (ext == ".yaml" || ext == ".yml") {
    const auto rig = format::load_rig(path);
    std::cout << fmt::format("rig {}: OK\n", path);
    print_rig_summary(std::cout, rig);
    return 0;
  }
  throw std::runtime_error(path + ": not a run folder, rig file (.yaml), run.yaml or samples.csv");
}

void add_validate(CLI::App& app) {
  auto* cmd = app.add_subcommand("validate", "Check a run folder, a rig file, run.yaml or samples.csv and summarise it");
  static std::string path, rig;
  cmd->add_option("PATH", path, "run folder, rig file, run.yaml or samples.csv")->required();
  cmd->add_option("--rig", rig, "rig file to check the run against (default: the run's rig.yaml)");
  cmd->callback([] { set_action([] { return validate(path, rig); }); });
}

}  // namespace hil::cli
