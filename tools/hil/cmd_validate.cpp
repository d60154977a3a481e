// `hil validate PATH [--json [OUT|-]]`: checks a run folder, a rig file, run.yaml, samples.csv or a
// calibration run (against --rig's robot) and summarises it, as text and optionally as JSON (hil.validation).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include <hil/cli/commands.hpp>
#include <hil/error/error.hpp>
#include <hil/format/calibration_run.hpp>
#include <hil/format/csv.hpp>
#include <hil/format/run.hpp>
#include <hil/format/output.hpp>
#include <hil/mcap/mcap.hpp>
#include "summary.hpp"

namespace hil::cli {

using format::human;
using format::is_stdout;
using format::tag_format;
using format::write_json;
namespace fs = std::filesystem;

namespace {

/// The column names of a CSV's header line (the first that is not blank or a comment).
std::vector<std::string> csv_header(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::vector<std::string> names;
    std::string cell;
    std::istringstream cells(line);
    while (std::getline(cells, cell, ',')) names.push_back(cell.substr(0, cell.find_last_not_of(" \t\r") + 1));
    return names;
  }
  return {};
}

/// What PATH is: run, run_info (run.yaml), samples or calibration_run (.csv, by its header) or rig
/// (.yaml). \throws FormatError.
std::string kind_of(const std::string& path) {
  if (!fs::exists(path)) throw error::FormatError({path, 0, 0, ""}, "no such file or folder");
  if (fs::is_directory(path)) return "run";
  if (fs::path(path).filename() == "run.yaml") return "run_info";
  const auto ext = fs::path(path).extension().string();
  if (ext == ".csv") return format::looks_like_calibration_run(csv_header(path)) ? "calibration_run" : "samples";
  if (ext == ".yaml" || ext == ".yml") return "rig";
  if (ext == ".mcap") return "mcap";
  throw error::FormatError({path, 0, 0, ""},
                           "not a run folder, rig file (.yaml), run.yaml, samples.csv, calibration run (.csv) or MCAP recording (.mcap)");
}

/// An MCAP recording, checked whole (every CRC, index and count); a file that fails is also read
/// as `hil export --recover` would, so that the error says what can be saved.
nlohmann::json check_mcap(const std::string& path, std::ostream& text) {
  mcap::File f;
  try {
    f = mcap::read_file(path);
  } catch (const error::FormatError& e) {
    mcap::Recovery r;
    try {
      mcap::recover_file(path, r);
    } catch (const std::exception&) {
      throw e;
    }
    throw error::FormatError(e.where(),
                             fmt::format("{} (hil export --recover {} --mcap OUT saves {} messages in {} chunks, {} of {} bytes)",
                                         e.message(), path, r.messages, r.chunks, r.bytes_read, r.bytes_total));
  }
  std::map<std::uint16_t, std::size_t> per_channel;
  for (const auto& m : f.messages) ++per_channel[m.channel_id];
  std::uint64_t first = 0, last = 0;
  for (const auto& m : f.messages) {
    first = first == 0 ? m.log_time_ns : std::min(first, m.log_time_ns);
    last = std::max(last, m.log_time_ns);
  }
  std::set<std::string> compressions;
  for (const auto& c : f.chunks) compressions.insert(c.compression.empty() ? "none" : c.compression);
  nlohmann::json channels = nlohmann::json::array();
  for (const auto& c : f.channels) {
    const auto* s = f.schema(c.schema_id);
    channels
        .push_back({{"topic", c.topic}, {"schema", s ? s->name : ""}, {"encoding", c.message_encoding}, {"messages", per_channel[c.id]}});
  }
  const double duration_s = f.messages.empty() ? 0.0 : static_cast<double>(last - first) * 1e-9;
  text << fmt::format("mcap {}: OK (profile '{}', written by '{}')\n", path, f.header.profile, f.header.library);
  text << fmt::format("  messages: {} in {} chunks ({}), {:.3f} s\n", f.messages.size(), f.chunks.size(),
                      compressions.empty() ? std::string("none") : fmt::format("{}", fmt::join(compressions, ", ")), duration_s);
  for (const auto& c : channels)
    text << fmt::format("    {} ({}): {}\n", c["topic"].get<std::string>(), c["schema"].get<std::string>(),
                        c["messages"].get<std::size_t>());
  return {{"profile", f.header.profile}, {"library", f.header.library}, {"messages", f.messages.size()},
          {"chunks", f.chunks.size()},   {"start_ns", first},           {"end_ns", last},
          {"duration_s", duration_s},    {"channels", channels}};
}

/// Checks PATH of that kind, prints the human summary to `text` and returns it as JSON.
nlohmann::json check(const std::string& kind, const std::string& path, const std::string& rig_path, std::ostream& text) {
  if (kind == "mcap") return check_mcap(path, text);
  if (kind == "run") {
    const auto run = format::load_run(path, rig_path);
    text << fmt::format("run {}: OK\n", path);
    print_run_summary(text, run);
    return run_summary_json(run);
  }
  if (kind == "run_info") {
    const auto info = format::load_run_info(path);
    text << fmt::format("run.yaml {}: OK (rig '{}', started {}, output {} Hz, {} sources)\n", path, info.rig, info.start_time_utc,
                        info.output_rate_hz, info.sources.size());
    return run_info_json(info);
  }
  if (kind == "samples") {
    const auto table = format::read_samples(path);
    text << fmt::format("samples {}: OK\n", path);
    print_samples_summary(text, table);
    return samples_summary_json(table);
  }
  if (kind == "calibration_run") {
    if (rig_path.empty()) throw error::FormatError({path, 0, 0, ""}, "a calibration run is checked against its robot: give --rig RIG");
    const auto rig = format::load_rig(rig_path);
    if (!rig.robot) throw error::FormatError({rig_path, 0, 0, "robot"}, "the rig has no robot to check the calibration run against");
    const auto run = format::read_calibration_run(path, *rig.robot);
    std::map<std::string, int> per_station;
    for (const auto& p : run.postures) ++per_station[p.station];
    nlohmann::json j = {{"robot", rig.robot->name},         {"postures", run.postures.size()},    {"stations", nlohmann::json::array()},
                        {"joints", run.joint_names},        {"orientation", run.has_orientation}, {"sigma", run.has_sigma},
                        {"flags", nlohmann::json::array()}, {"tilts", nlohmann::json::array()},   {"payload", run.has_payload},
                        {"wrench", run.has_wrench}};
    text << fmt::format("calibration run {}: OK ({} postures of robot '{}', {} station(s){}{})\n", path, run.postures.size(),
                        rig.robot->name, run.stations.size(), run.has_orientation ? ", full poses" : ", points",
                        run.has_sigma ? ", with sigma" : "");
    for (const auto& s : run.stations) {
      j["stations"].push_back({{"id", s}, {"postures", per_station[s]}});
      text << fmt::format("  station {}: {} postures\n", s, per_station[s]);
    }
    for (std::size_t f = 0; f < run.flag_names.size(); ++f) {
      int set = 0;
      for (const auto& p : run.postures) set += p.flags[f] ? 1 : 0;
      j["flags"].push_back({{"name", run.flag_names[f]}, {"set", set}});
      text << fmt::format("  flag {}: set on {} postures\n", run.flag_names[f], set);
    }
    for (const auto& t : run.tilts) j["tilts"].push_back(t.column);
    return j;
  }
  const auto rig = format::load_rig(path);
  text << fmt::format("rig {}: OK\n", path);
  print_rig_summary(text, rig);
  return rig_summary_json(rig);
}

nlohmann::json error_json(const std::string& path, const std::exception& e) {
  auto null_if = [](auto v, bool unknown) { return unknown ? nlohmann::json() : nlohmann::json(v); };
  if (const auto* f = dynamic_cast<const error::FormatError*>(&e)) {
    const auto& w = f->where();
    return {{"file", w.file.empty() ? path : w.file},
            {"line", null_if(w.line, w.line == 0)},
            {"column", null_if(w.column, w.column == 0)},
            {"field", null_if(w.field, w.field.empty())},
            {"message", f->message()},
            {"text", e.what()}};
  }
  return {{"file", path}, {"line", nullptr}, {"column", nullptr}, {"field", nullptr}, {"message", e.what()}, {"text", e.what()}};
}

/// `json_out` empty: no JSON. A failed check still writes the JSON (ok: false, the error), then
/// rethrows for main() to print the error and exit 2.
int validate(const std::string& path, const std::string& rig_path, const std::string& json_out) {
  auto& text = human(is_stdout(json_out));
  nlohmann::json j;
  tag_format(j, "validation");
  j["path"] = path;
  j["rig"] = rig_path.empty() ? nlohmann::json() : nlohmann::json(rig_path);
  j["kind"] = nullptr;
  try {
    const auto kind = kind_of(path);
    j["kind"] = kind;
    j["summary"] = check(kind, path, rig_path, text);
    j["ok"] = true;
    j["errors"] = nlohmann::json::array();
  } catch (const std::exception& e) {
    if (json_out.empty()) throw;
    j["ok"] = false;
    j["summary"] = nullptr;
    j["errors"] = nlohmann::json::array({error_json(path, e)});
    write_json(json_out, j);
    throw;
  }
  if (!json_out.empty()) write_json(json_out, j);
  return 0;
}

}  // namespace

void add_validate(CLI::App& app) {
  auto* cmd = app.add_subcommand("validate",
                                 "Check a run folder, a rig file, run.yaml, samples.csv, a calibration run or an MCAP recording "
                                 "and summarise it");
  static std::string path, rig, json;
  static CLI::Option* json_opt = nullptr;
  cmd->add_option("PATH", path,
                  "run folder, rig file, run.yaml, samples.csv, calibration run (.csv with posture, px, py, pz) or MCAP recording (.mcap)")
      ->required();
  cmd->add_option("--rig", rig, "rig file to check the run against (default: the run's rig.yaml); a calibration run's robot");
  json_opt = cmd->add_option("--json", json,
                             "also write the summary (or the error) as JSON (hil.validation) to OUT; without OUT or with -, to "
                             "stdout and the text to stderr")
                 ->expected(0, 1)
                 ->type_name("[OUT|-]");
  cmd->callback([] {
    const std::string out = json_opt->count() > 0 && json.empty() ? "-" : json;
    set_action([out] { return validate(path, rig, out); });
  });
}

}  // namespace hil::cli
