// `hil stiffness ...`: filled in by its issue. Registers nothing until then.
#include "../commands.hpp"

namespace hil::cli {
void add_stiffness(CLI::App& /*app*/) {}
}  // namespace hil::cli
