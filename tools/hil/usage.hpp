#pragma once
// Command-line usage errors: one line naming the bad word, a hint, exit status 2 (docs/cli.md).
#include <CLI/CLI.hpp>
#include <ostream>
#include <string>
#include <vector>

namespace hil::cli {

/// Exit status of a usage error or of bad input (hil::error::FormatError).
inline constexpr int kExitUsage = 2;

/// Reports a CLI11 parse error of `app` on `err` as "error: ..." naming the unknown command or
/// option, the missing argument or the bad value, with "did you mean" when a name is close and a
/// hint to the command's --help; returns 2. Help and --version print to stdout and return 0.
int report_parse_error(const CLI::App& app, const CLI::ParseError& e, std::ostream& err);

/// The names in `known` close to `word` (small edit distance, or `word` a prefix), best first.
std::vector<std::string> close_names(const std::string& word, const std::vector<std::string>& known);

}  // namespace hil::cli
