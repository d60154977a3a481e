// `hil fake-rig`, `hil acquire`, `hil echo`, `hil replay`: the rig service. Each subcommand lives
// in its own file; this registrar only wires them.
#include <hil/cli/commands.hpp>
#include "rig_commands.hpp"

namespace hil::cli {
void add_rig(CLI::App& app) { add_fake_rig(app); }
}  // namespace hil::cli
