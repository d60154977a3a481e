#pragma once
// The rig-service subcommands, each in its own file; cmd_rig.cpp registers them.
#include <CLI/CLI.hpp>

namespace hil::cli {
void add_fake_rig(CLI::App& app);  // cmd_fake_rig.cpp
}  // namespace hil::cli
