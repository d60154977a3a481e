// `hil diagnose RUN`: what the nominal simulation gets wrong, the named cause, the extended model
// and its held-out gain (issue 6).
#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>

#include <hil/cli/commands.hpp>
#include <hil/error/error.hpp>
#include <hil/format/output.hpp>
#include <hil/format/run.hpp>
#include <hil/services/diagnose_output.hpp>
#include <hil/services/diagnose_run.hpp>

namespace hil::cli {

namespace diagnose = services::diagnose;
using format::human;
using format::is_stdout;
using format::tag_format;
using format::write_json;

namespace {

struct DiagnoseArgs {
  std::string run, rig, json, report, truth;
  std::vector<std::string> candidates;
  int folds = 5;
  int cv_offsets = 0;
  int threads = 0;
  hil::diagnose::RateSource damping_rates = hil::diagnose::RateSource::automatic;
  double window_s = 0.0;
  std::size_t max_samples = 10000;
  bool quiet = false;
  bool stability = false;
  std::string stability_grid;
};

/// Progress lines "[diagnose<stage> step/total] what" on stderr: rewritten in place on a terminal,
/// one per line otherwise; none when quiet.
hil::diagnose::Progress progress_lines(bool quiet, bool tty, const std::string& stage, int width) {
  if (quiet) return {};
  return [tty, stage, width](int step, int total, const std::string& what) {
    if (tty) std::cerr << fmt::format("\r[diagnose{} {}/{}] {:<{}}", stage, step, total, what, width) << std::flush;
    else std::cerr << fmt::format("[diagnose{} {}/{}] {}\n", stage, step, total, what);
  };
}

int diagnose_cmd(const DiagnoseArgs& a) {
  diagnose::Options o;
  o.candidates = a.candidates;
  o.folds = a.folds;
  o.cv_offsets = a.cv_offsets;
  o.threads = a.threads;
  o.damping_rates = a.damping_rates;
  o.max_samples = a.max_samples;
  o.progress_detail = true;
  const bool tty = isatty(STDERR_FILENO) != 0;
  o.progress = progress_lines(a.quiet, tty, "", 80);
  // A file is a stiffness-experiment table; a folder a run.
  const bool table = std::filesystem::is_regular_file(a.run);
  if (table && a.window_s > 0)
    throw error::FormatError({"command line", 0, 0, "--window"}, "applies to a run folder (a stiffness table has no time)");
  const bool stability = a.stability || !a.stability_grid.empty();
  if (table && stability)
    throw error::FormatError({"command line", 0, 0, "--stability"}, "applies to a run folder (a stiffness table has no time blocks)");
  std::vector<std::pair<int, int>> grid;
  try {
    grid = a.stability_grid.empty() ? diagnose::default_stability_grid() : diagnose::parse_stability_grid(a.stability_grid);
  } catch (const std::invalid_argument& e) {
    throw error::FormatError({"command line", 0, 0, "--stability-grid"}, e.what());
  }
  std::optional<format::Run> run;
  if (!table) run = format::load_run(a.run, a.rig);
  auto r = table ? diagnose::diagnose_table(a.run, a.rig, o) : diagnose::diagnose_run(*run, o);
  if (a.window_s > 0) {
    if (!a.quiet && tty) std::cerr << "\r" << std::string(100, ' ') << "\r";
    auto wo = o;
    wo.progress = progress_lines(a.quiet, tty, " window", 50);
    r.windows = diagnose::diagnose_windows(*run, a.window_s, wo);
  }
  if (stability) {
    if (!a.quiet && tty) std::cerr << "\r" << std::string(100, ' ') << "\r";
    auto so = o;
    so.progress = progress_lines(a.quiet, tty, " stability", 50);
    r.stability = diagnose::verdict_stability(*run, so, grid);
  }
  if (!a.quiet && tty) std::cerr << "\r" << std::string(100, ' ') << "\r";
  auto& text = human(is_stdout(a.json));
  diagnose::print_summary(text, r);
  if (!a.json.empty()) write_json(a.json, diagnose::to_json(r));
  if (!a.report.empty()) {
    diagnose::write_report(a.report, r, a.truth.empty() ? diagnose::TruthValues{} : diagnose::read_truth(a.truth, r));
    text << "report: " << (std::filesystem::path(a.report) / "index.html").string() << "\n";
  }
  return 0;
}

/// The candidates per model family and what asks for repeated CV, from the effect registry.
std::string candidates_help() {
  namespace dg = hil::diagnose;
  return fmt::format("only these candidate causes (default: all that apply). Contact runs: {}; deflection runs: {}; "
                     "stiffness tables: {}",
                     fmt::join(dg::effect_names(dg::FamilyKind::contact), ", "),
                     fmt::join(dg::effect_names(dg::FamilyKind::deflection), ", "), fmt::join(dg::stiffness_extensions(), ", "));
}

std::string cv_offsets_help() {
  std::vector<std::string> asks;
  for (const hil::diagnose::Effect* e : hil::diagnose::registered_effects())
    if (e->cv_offsets() > 1) asks.push_back(fmt::format("{} when {} is a candidate", e->cv_offsets(), e->name()));
  return fmt::format("repeat the cross-validation over this many offsets of its block grid and pool the held-out errors "
                     "(0: {}{}1)",
                     fmt::join(asks, ", "), asks.empty() ? "" : ", else ");
}

}  // namespace

void add_diagnose(CLI::App& app) {
  static DiagnoseArgs da;
  auto* d = app.add_subcommand("diagnose",
                               "What the nominal model gets wrong on a run, the named cause, the extended model and its held-out gain");
  d->add_option("RUN", da.run, "run folder, or a stiffness-experiment table (CSV, with --rig of its robot)")->required();
  d->add_option("--rig", da.rig, "rig file (default: the run's rig.yaml)");
  d->add_option("--json", da.json, "write the diagnosis as JSON (hil.diagnosis; - for stdout, the summary then goes to stderr)");
  auto* report = d->add_option("--report", da.report, "write an HTML report into this folder");
  d->add_option("--truth", da.truth,
                "a hidden-effects file (hil contact simulate --truth-out): its values are drawn beside the report's intervals; "
                "the diagnosis itself never reads it")
      ->needs(report);
  d->add_option("--window", da.window_s,
                "also diagnose each window of this many seconds on its own: when a cause appears or drifts (a timeline in "
                "the summary, JSON and report)")
      ->check(CLI::PositiveNumber);
  d->add_option("--candidates", da.candidates, candidates_help())->delimiter(',');
  d->add_option("--folds", da.folds, "blocks of the cross-validation over time")->capture_default_str()->check(CLI::Range(2, 1000));
  d->add_option("--cv-offsets", da.cv_offsets, cv_offsets_help())->capture_default_str()->check(CLI::Range(0, 64));
  d->add_option("--threads", da.threads,
                "threads the cross-validation folds run on, with two models scored side by side (0: one per core; "
                "1: one thread, models one after another, e.g. to leave a core to an acquisition); the result is the "
                "same on any number")
      ->capture_default_str()
      ->check(CLI::Range(0, 256));
  const std::map<std::string, hil::diagnose::RateSource> rates{{"auto", hil::diagnose::RateSource::automatic},
                                                               {"twist", hil::diagnose::RateSource::twist},
                                                               {"poses", hil::diagnose::RateSource::poses}};
  d->add_option("--damping-rates", da.damping_rates,
                "where contact_damping's penetration rates come from: auto (per axis, the pose slope where it beats the "
                "reported twist), twist, poses")
      ->transform(CLI::CheckedTransformer(rates, CLI::ignore_case))
      ->default_str("auto");
  d->add_option("--max-samples", da.max_samples,
                "diagnose a longer run on one sample in k, k the smallest that leaves at most this many (0: every sample; the "
                "cost grows with the samples diagnosed, about 8 ms each on two cores)")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{0}, std::size_t{1'000'000'000}));
  d->add_flag("--stability", da.stability,
              "also diagnose the run under 5, 8 and 10 folds, each on 1, 2 and 8 grid offsets, and print the verdicts side by "
              "side: a cause that changes with the cross-validation's settings is reported as unstable (9 diagnoses)");
  d->add_option("--stability-grid", da.stability_grid,
                "the settings --stability tries, as FOLDS:OFFSETS,... (implies --stability), e.g. 5:1,5:2,5:8");
  d->add_flag("--quiet", da.quiet, "no progress lines");
  d->callback([] { set_action([] { return diagnose_cmd(da); }); });
}

}  // namespace hil::cli
