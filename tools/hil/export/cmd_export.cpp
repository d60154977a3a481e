// `hil export RUN --mcap OUT [--compression none|zstd|lz4] [--rig RIG] [--no-tf]`: a run folder as an
// MCAP file with ROS 2 channels (docs/mcap.md), for Foxglove, PlotJuggler and ros2 bag.
// `hil export --recover BROKEN.mcap --mcap OUT`: what can be read of a recording that was not closed.
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
  std::string run, rig, mcap, recover;
  std::string compression = "zstd";
  bool tf = true;
};

/// `hil export --recover BROKEN.mcap --mcap OUT`: the readable part of a recording, as a complete file.
int recover(const ExportOptions& o) {
  mcap::Recovery r;
  const auto file = mcap::recover_file(o.recover, r);
  const auto n = mcap::rewrite(file, o.mcap, mcap::parse_compression(o.compression));
  const auto* samples = file.channel(mcap::topic::kPoseWrench);
  const auto n_samples = samples ? file.messages_on(mcap::topic::kPoseWrench).size() : 0;
  if (r.complete) {
    std::cout << fmt::format("{}: complete, nothing to recover; {} messages ({} samples) copied -> {}\n", o.recover, n, n_samples, o.mcap);
  } else {
    std::cout << fmt::format("recovered {} messages ({} samples) in {} chunks, {} of {} bytes, from {} -> {}\n", n, n_samples, r.chunks,
                             r.bytes_read, r.bytes_total, o.recover, o.mcap);
    std::cout << fmt::format("  reading stopped at {}\n", r.stopped);
  }
  return 0;
}
}  // namespace

void add_export(CLI::App& app) {
  auto* cmd = app.add_subcommand("export", "Convert a recorded run to another format (MCAP: ROS 2 bags, Foxglove, PlotJuggler), or recover "
                                           "a recording that was not closed");
  static ExportOptions o;
  auto* run_opt = cmd->add_option("RUN", o.run, "run folder")->check(CLI::ExistingDirectory);
  auto* rec = cmd->add_option("--recover", o.recover,
                              "an MCAP recording without its footer (killed, power lost) or damaged at its end: write what can be read "
                              "of it, chunk by chunk, as a complete file to --mcap")
                  ->check(CLI::ExistingFile);
  run_opt->excludes(rec);
  cmd->add_option("--mcap", o.mcap, "MCAP file to write")->required();
  cmd->add_option("--compression", o.compression, "chunk compression: none, zstd or lz4")
      ->check(CLI::IsMember({"none", "zstd", "lz4"}))
      ->capture_default_str();
  cmd->add_flag("!--no-tf", o.tf, "no /tf channel (the moving robot base -> ee transform with every sample)");
  cmd->add_option("--rig", o.rig, "rig file (default: the run's rig.yaml; without one, no /tf_static)")->check(CLI::ExistingFile);
  cmd->callback([] {
    set_action([] {
      if (!o.recover.empty()) {
        if (!o.rig.empty()) throw error::FormatError({"command line", 0, 0, "--rig"}, "--recover copies a recording: it takes no --rig");
        return recover(o);
      }
      if (o.run.empty()) throw error::FormatError({"command line", 0, 0, "RUN"}, "give a run folder, or --recover FILE.mcap");
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
