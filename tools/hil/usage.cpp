#include "usage.hpp"

#include <algorithm>
#include <iostream>

#include <hil/format/edit_distance.hpp>

namespace hil::cli {

namespace {

/// The command a parse error belongs to, and its words ("hil stiffness identify"): the first
/// command the parser entered that kept words it could not place, else the deepest one entered.
const CLI::App* culprit(const CLI::App& app, std::string& path) {
  const CLI::App* a = &app;
  path = app.get_name();
  while (a->remaining(false).empty() && !a->get_subcommands().empty()) {
    a = a->get_subcommands().front();
    path += " " + a->get_name();
  }
  return a;
}

std::vector<std::string> subcommand_names(const CLI::App& a) {
  std::vector<std::string> names;
  for (const auto* s : a.get_subcommands([](const CLI::App*) { return true; })) names.push_back(s->get_name());
  return names;
}

/// "--name" and "-n" of every option of `a` and of the apps above it (their options come first
/// on the command line, but a misplaced one is still worth a suggestion).
std::vector<std::string> option_names(const CLI::App& a) {
  std::vector<std::string> names;
  for (const CLI::App* p = &a; p != nullptr; p = p->get_parent())
    for (const auto* o : p->get_options()) {
      for (const auto& l : o->get_lnames()) names.push_back("--" + l);
      for (const auto& s : o->get_snames()) names.push_back("-" + s);
    }
  return names;
}

std::string did_you_mean(const std::string& word, const std::vector<std::string>& known) {
  const auto close = close_names(word, known);
  if (close.empty()) return "";
  std::string s = " (did you mean '" + close[0] + "'";
  if (close.size() > 1) s += " or '" + close[1] + "'";
  return s + "?)";
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

/// The first word the parser could not place, options first when `option` is set.
std::string first_word(const std::vector<std::string>& rest, bool option) {
  for (const auto& w : rest)
    if ((w.size() > 1 && w[0] == '-') == option) return w;
  return "";
}

}  // namespace

std::vector<std::string> close_names(const std::string& word, const std::vector<std::string>& known) {
  std::vector<std::pair<std::size_t, std::string>> scored;
  const auto bare = [](const std::string& s) {
    return s.substr(s.find_first_not_of('-') == std::string::npos ? 0 : s.find_first_not_of('-'));
  };
  const std::string w = bare(word);
  for (const auto& k : known) {
    const std::string kb = bare(k);
    const std::size_t d = format::edit_distance(w, kb);
    const bool prefix = w.size() >= 3 && kb.rfind(w, 0) == 0;
    // Up to one edit in three letters (at least one, at most three): typos, not other words.
    const std::size_t limit = std::clamp<std::size_t>(std::max(w.size(), kb.size()) / 3, 1, 3);
    if (d <= limit || prefix) scored.emplace_back(prefix ? 0 : d, k);
  }
  std::stable_sort(scored.begin(), scored.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::string> out;
  for (const auto& [d, k] : scored)
    if (std::find(out.begin(), out.end(), k) == out.end()) out.push_back(k);
  return out;
}

int report_parse_error(const CLI::App& app, const CLI::ParseError& e, std::ostream& err) {
  if (e.get_exit_code() == 0) return app.exit(e);                                 // --help, --help-all, --version
  if (dynamic_cast<const CLI::RuntimeError*>(&e) != nullptr) return app.exit(e);  // a callback's chosen exit status
  std::string path;
  const CLI::App* at = culprit(app, path);
  const auto rest = at->remaining(false);
  const std::string opt = first_word(rest, true), word = first_word(rest, false);
  std::string msg;
  const bool wants_subcommand = at->get_require_subcommand_min() > 0 && at->get_subcommands().empty();
  if (wants_subcommand && !word.empty()) {
    msg = "unknown command '" + word + "'" + (at == &app ? "" : " for '" + path + "'") + did_you_mean(word, subcommand_names(*at));
  } else if (!opt.empty()) {
    // An option this command does not know (CLI11 reports it as an extra, or as a missing
    // subcommand when it came before one).
    msg = "unknown option '" + opt + "' for '" + path + "'" + did_you_mean(opt, option_names(*at));
  } else if (wants_subcommand) {
    msg = "'" + path + "' needs a command: " + join(subcommand_names(*at));
  } else if (dynamic_cast<const CLI::ExtrasError*>(&e) != nullptr && !word.empty()) {
    msg = "unexpected argument '" + word + "' for '" + path + "'";
  } else {
    // Missing required argument ("--rig is required", "PATH is required"), a value missing after
    // an option ("--json: 1 required TEXT missing"), a value out of range or not a number
    // ("--folds: Value 1 not in range 2 to 1000"): CLI11's message names the option.
    msg = path + ": " + e.what();
  }
  err << "error: " << msg << "\n"
      << "run '" << path << " --help' for the usage\n";
  return kExitUsage;
}

}  // namespace hil::cli
