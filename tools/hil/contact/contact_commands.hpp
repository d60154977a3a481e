#pragma once
// The `hil contact` subcommands defined outside cmd_contact.cpp.
#include <CLI/CLI.hpp>

namespace hil::cli {

/// `hil contact worker` (cmd_contact_worker.cpp).
void add_contact_worker(CLI::App& contact);

}  // namespace hil::cli
