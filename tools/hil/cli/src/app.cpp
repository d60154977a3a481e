#include <hil/cli/commands.hpp>

namespace hil::cli {

GlobalOptions& globals() {
  static GlobalOptions g;
  return g;
}

namespace {
Action& current_action() {
  static Action a;
  return a;
}
}  // namespace

void set_action(Action a) { current_action() = std::move(a); }
const Action& action() { return current_action(); }

}  // namespace hil::cli
