#pragma once
#include <cstddef>
#include <string>

namespace hil::format {

/// Levenshtein distance, ignoring ASCII case: how far a word a user typed (a column, a key, a
/// subcommand) is from one that exists, to suggest the one they probably meant.
std::size_t edit_distance(const std::string& a, const std::string& b);

}  // namespace hil::format
