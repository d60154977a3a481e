// `hil fake-rig`, `hil acquire`, `hil echo`, `hil replay`: filled in by the rig-service work.
#include "../commands.hpp"

namespace hil::cli {
void add_rig(CLI::App& /*app*/) {}
}  // namespace hil::cli
