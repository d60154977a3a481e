// `hil export RUN --mcap OUT [--compression none|zstd|lz4] [--rig RIG]`: a run folder as an MCAP
// file with ROS 2 channels (docs/mcap.md), for Foxglove, PlotJuggler and ros2 bag.
#include <fmt/format.h>

#include <iostream>

#include <hil/cli/commands.hpp>
#include <hil/error/error.hpp>
#include <hil/format/run.hpp>
#include <hil/mcap/mcap.hpp>
#include <hil/mcap/recording.hpp>

namespace hil::cli {
namespace {
struct ExportOptions {
  std::string run, rig, mcap;
  std::string compression = "zstd";
  bool tf = true;
};
}  // namespace

void add_export(CLI::App& app) {
  auto* cmd = app.add_subcommand("export", "Convert a recorded run to another format (MCAP: ROS 2 bags, Foxglove, PlotJuggler)");
  static ExportOptions o;
  cmd->add_option("RUN", o.run, "run folder")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--mcap", o.mcap, "MCAP file to write")->required();
  cmd->add_option("--compression", o.compression, "chunk compression: none, zstd or lz4")
      ->check(CLI::IsMember({"none", "zstd", "lz4"}))
      ->capture_default_str();
  cmd->add_flag("!--no-tf", o.tf, "no /tf channel (the moving robot base -> ee transform with every sample)");
  cmd->add_option("--rig", o.rig, "rig file (default: the run's rig.yaml; without one, no /tf_static)")->check(CLI::ExistingFile);
  cmd->callback([] {
    set_action([] {
      const auto run = format::load_run(o.run, o.rig);
      mcap::RecordingOptions ro;
      ro.compression = mcap::parse_compression(o.compression);
      ro.tf = o.tf;
      mcap::export_run(run, o.mcap, ro);
      std::cout << fmt::format("exported {} samples of {} -> {} ({}{})\n", run.samples.size(), o.run, o.mcap, o.compression,
                               run.rig ? "" : ", no rig: no /tf_static");
      return 0;
    });
  });
}

}  // namespace hil::cli
