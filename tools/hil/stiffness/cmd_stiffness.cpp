// `hil stiffness identify|predict|simulate|table1|replay|worker`: elastostatic calibration of
// serial robots (issue 4). Command-line plumbing only: the files are hil::models' (formats/models),
// the work hil::services::stiffness' (services/stiffness, services/workers), the numerics
// hil::calibration's.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <csignal>
#include <iostream>
#include <sstream>

#include <hil/cli/commands.hpp>
#include <hil/cli/participant.hpp>
#include <hil/format/output.hpp>
#include <hil/calibration/experiment.hpp>
#include <hil/dds/topics.hpp>
#include <hil/error/error.hpp>
#include <hil/models/stiffness_model.hpp>
#include <hil/services/stiffness.hpp>
#include <hil/services/stiffness_worker.hpp>

namespace hil::cli {
namespace hc = hil::calibration;
using error::FormatError;
using namespace services::stiffness;
using models::load_robot;
using models::read_stiffness_table;
using format::human;
using format::is_stdout;
using format::tag_format;
using format::write_json;
using format::Output;

namespace {

struct ReductionArgs {
  double noise_pos_m = 0.0;
  double noise_rot_rad = 0.0;
  double neglect_below = 2.0;
  double pnr_low = 2.0;
  double pnr_high = 5.0;
  double rank_tol = 1e-9;
  bool complete_ranks = false;
  bool no_sparsing = false;
  std::vector<std::string> priorities;  // NAME=P
  std::vector<std::string> fixes;       // NAME=VALUE
  std::vector<std::string> templates;   // Lk=beam|full|36 chars of 0/1
};

std::pair<std::string, double> name_value(const std::string& s, const char* option) {
  const auto eq = s.find('=');
  if (eq == std::string::npos || eq == 0) throw FormatError({"command line", 0, 0, option}, "expected NAME=VALUE, found '" + s + "'");
  try {
    std::size_t used = 0;
    const double v = std::stod(s.substr(eq + 1), &used);
    if (used != s.size() - eq - 1) throw std::invalid_argument("trailing");
    return {s.substr(0, eq), v};
  } catch (const std::exception&) {
    throw FormatError({"command line", 0, 0, option}, "not a number after '=' in '" + s + "'");
  }
}

hc::PipelineOptions pipeline_options(const ReductionArgs& a, const hc::VjmModel& model) {
  hc::PipelineOptions o;
  o.sparsify = !a.no_sparsing;
  o.neglect_below = a.neglect_below;
  o.pnr = {a.pnr_low, a.pnr_high};
  o.algebraic.rank.tolerance = a.rank_tol;
  o.complete_ranks = a.complete_ranks;
  const auto all = hc::m1_symmetrise(hc::complete_parameters(model));
  auto known = [&](const std::string& name, const char* opt) {
    if (hc::find_parameter(all, name) < 0 && hc::find_parameter(hc::complete_parameters(model), name) < 0)
      throw FormatError({"command line", 0, 0, opt}, "unknown parameter '" + name + "' (names like L2.k44, L3.k26, J1.k)");
  };
  for (const auto& p : a.priorities) {
    const auto [n, v] = name_value(p, "--priority");
    known(n, "--priority");
    o.priorities[n] = v;
  }
  for (const auto& f : a.fixes) {
    const auto [n, v] = name_value(f, "--fix");
    known(n, "--fix");
    o.fixed_values[n] = v;
  }
  for (const auto& t : a.templates) {
    const auto eq = t.find('=');
    const std::string link = eq == std::string::npos ? "" : t.substr(0, eq);
    const int s = model.find(link);
    if (s < 0 || model.springs()[static_cast<std::size_t>(s)].kind != hc::SpringKind::link)
      throw FormatError({"command line", 0, 0, "--template"}, "expected Lk=beam|full|<36 digits 0/1>, found '" + t + "'");
    const std::string v = t.substr(eq + 1);
    hc::Template tp;
    if (v == "beam") tp = hc::beam_template();
    else if (v == "full") tp = hc::full_template();
    else if (v.size() == 36 && v.find_first_not_of("01") == std::string::npos) {
      for (int i = 0; i < 36; ++i) tp(i / 6, i % 6) = v[static_cast<std::size_t>(i)] == '1';
    } else {
      throw FormatError({"command line", 0, 0, "--template"}, "expected beam, full or 36 digits 0/1 (row-major), found '" + v + "'");
    }
    o.templates[model.springs()[static_cast<std::size_t>(s)].index] = tp;
  }
  return o;
}

void add_reduction_options(CLI::App* cmd, ReductionArgs& a) {
  cmd->add_option("--noise-pos-m", a.noise_pos_m, "position noise σ per axis, m (default: estimated from the residuals)");
  cmd->add_option("--noise-rot-rad", a.noise_rot_rad, "rotation noise σ per axis, rad (default: estimated)");
  cmd->add_option("--neglect-below", a.neglect_below, "M6: neglect parameters whose parameter-to-noise ratio stays below this (0: off)")
      ->capture_default_str();
  cmd->add_option("--pnr-low", a.pnr_low, "G1- below, G1~ from")->capture_default_str();
  cmd->add_option("--pnr-high", a.pnr_high, "G1+ from")->capture_default_str();
  cmd->add_option("--rank-tol", a.rank_tol, "rank tolerance on the column-scaled singular values")->capture_default_str();
  cmd->add_flag("--complete-ranks", a.complete_ranks, "also compute the ranks of the complete (258) and symmetrised models");
  cmd->add_flag("--no-sparsing", a.no_sparsing, "skip M2 (no link template)");
  cmd->add_option("--priority", a.priorities, "M5b priority NAME=P (higher kept first; default joints 3, diagonal 2, couplings 1)");
  cmd->add_option("--fix", a.fixes, "M5c value NAME=VALUE for a parameter that gets fixed (default 0)");
  cmd->add_option("--template", a.templates, "M2 template for a link: Lk=beam|full|<36 digits 0/1, row-major>");
}

// ---- identify
int identify(const std::string& data_path, const std::string& rig, const std::string& json_out, const ReductionArgs& a) {
  const hc::VjmModel model(load_robot(rig));
  const auto table = read_stiffness_table(data_path, model.dof(), true);
  const auto opt = pipeline_options(a, model);
  const auto r = hc::calibrate(model, table.rows, {a.noise_pos_m, a.noise_rot_rad}, opt);
  print_report(human(is_stdout(json_out)), model, r);
  if (!json_out.empty()) {
    write_json(json_out, models::result_to_json(model, r));
    if (!is_stdout(json_out)) spdlog::info("model written to {}", json_out);
  }
  return 0;
}

// ---- predict
int predict(const std::string& model_path, const std::string& data_path, const std::string& rig, bool compensate,
            const std::string& out_path) {
  const hc::SerialRobot robot = rig.empty() ? hc::SerialRobot{} : load_robot(rig);
  const auto mf = models::read_model_file(model_path, rig.empty() ? nullptr : &robot);
  const auto table = read_stiffness_table(data_path, mf.model.dof(), false);
  Output out(out_path.empty() ? "-" : out_path);
  write_predictions(out.stream(), mf, table, compensate);
  out.close();
  return 0;
}

// ---- simulate
struct SimArgs {
  std::string rig, truth, out;
  int configs = 50;
  int loads = 1;
  double force_n = 1000.0;
  double moment_nm = 0.0;
  std::string measure = "pose6";
  std::vector<std::string> markers;
  double noise_pos_m = 10e-6;
  double noise_rot_rad = 10e-6;
  std::uint64_t seed = 1;
};

int simulate(const SimArgs& a) {
  const hc::VjmModel model(load_robot(a.rig));
  const auto truth = models::read_truth_file(a.truth, model);
  hc::ExperimentPlan plan;
  plan.configurations = a.configs;
  plan.loads_per_config = a.loads;
  plan.force_n = a.force_n;
  plan.moment_nm = a.moment_nm;
  plan.seed = a.seed;
  plan.kind = a.measure == "pose6"    ? hc::MeasurementKind::pose6
              : a.measure == "point3" ? hc::MeasurementKind::point3
                                      : hc::MeasurementKind::markers;
  for (const auto& m : a.markers) {
    double x = 0, y = 0, z = 0;
    char c1 = 0, c2 = 0;
    std::istringstream is(m);
    if (!(is >> x >> c1 >> y >> c2 >> z) || c1 != ',' || c2 != ',')
      throw FormatError({"command line", 0, 0, "--marker"}, "expected X,Y,Z in metres (tool frame), found '" + m + "'");
    plan.p_ee_marker_m.emplace_back(x, y, z);
  }
  if (plan.kind == hc::MeasurementKind::markers && plan.p_ee_marker_m.empty())
    throw FormatError({"command line", 0, 0, "--marker"}, "--measure markers needs at least one --marker X,Y,Z");
  Output out(a.out.empty() ? "-" : a.out);
  write_simulated_table(out.stream(), model, truth, plan, {a.noise_pos_m, a.noise_rot_rad},
                        fmt::format("rig {}, truth {}", a.rig, a.truth));
  out.close();
  return 0;
}

// ---- table1
int table1(const std::string& rig, int configs, const std::string& measure, std::uint64_t seed, bool complete_ranks) {
  const hc::VjmModel model(rig.empty() ? hc::kr270_like() : load_robot(rig));
  print_table1(std::cout, model, configs, measure, seed, complete_ranks);
  return 0;
}

// ---- replay / worker
std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

int replay(const std::string& data_path, int dof_from_rig, double rate_hz, double wait_s) {
  const auto table = read_stiffness_table(data_path, dof_from_rig, true);
  dds::Participant p(participant_options("hil-stiffness-replay"));
  const std::size_t n = replay_measurements(p, table, data_path, rate_hz, wait_s);
  std::cout << fmt::format("replay: {} measurements published on {}\n", n, dds::topics::kStiffnessMeasurement);
  return 0;
}

int worker(const std::string& rig, const std::string& model_path, const ReductionArgs& a, std::size_t count, double timeout_s,
           double estimate_period_ms) {
  if (!(estimate_period_ms >= 0.0) || estimate_period_ms > 3.6e6)
    throw FormatError({"command line", 0, 0, "--estimate-period-ms"}, "must be between 0 and 3,600,000 ms");
  const hc::VjmModel model(load_robot(rig));
  if (!(a.noise_pos_m > 0.0) || !(a.noise_rot_rad > 0.0))
    throw FormatError({"command line", 0, 0, "--noise-pos-m"}, "the worker needs the noise: --noise-pos-m and --noise-rot-rad (> 0)");
  auto id = make_online_identifier(model, model_path, {a.noise_pos_m, a.noise_rot_rad}, pipeline_options(a, model));
  dds::Participant p(participant_options("hil-stiffness-worker"));
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const WorkerRun run = run_stiffness_worker(p, std::move(id), count, timeout_s, g_stop,
                                             std::chrono::microseconds(static_cast<long>(estimate_period_ms * 1e3)));
  std::cout << fmt::format("worker: {} measurements processed, {} rejected; last rank {}\n", run.processed, run.rejected, run.last_rank);
  return count > 0 && run.processed < count ? 1 : 0;
}

}  // namespace

void add_stiffness(CLI::App& app) {
  auto* st = app.add_subcommand("stiffness", "Elastostatic calibration of serial robots (VJM model, reduction M1-M6)");
  st->require_subcommand(1);

  {
    auto* cmd = st->add_subcommand("identify", "Reduce the complete VJM model and identify it from a stiffness-experiment table");
    static std::string data, rig, json;
    static ReductionArgs a;
    cmd->add_option("DATA", data, "stiffness-experiment table (CSV, docs/calibration.md)")->required();
    cmd->add_option("--rig", rig, "rig file with the robot (DH table or URDF)")->required();
    cmd->add_option(
        "--json", json,
        "write the report and the identified model as JSON (hil.stiffness_model; - for stdout, the text report then goes to stderr)");
    add_reduction_options(cmd, a);
    cmd->callback([] { set_action([] { return identify(data, rig, json, a); }); });
  }
  {
    auto* cmd = st->add_subcommand("predict", "Predict deflections for configurations and loads; --compensate prints corrected targets");
    static std::string model, data, rig, out;
    static bool compensate = false;
    cmd->add_option("MODEL", model, "model file (identify --json output, or a truth file with --rig)")->required();
    cmd->add_option("--data", data, "table of configurations and loads (measured columns optional)")->required();
    cmd->add_option("--rig", rig, "rig file (default: the robot stored in the model)");
    cmd->add_flag("--compensate", compensate, "also print the target pose, the compensated pose and joints");
    cmd->add_option("--out", out, "output CSV (default or -: stdout)");
    cmd->callback([] { set_action([] { return predict(model, data, rig, compensate, out); }); });
  }
  {
    auto* cmd = st->add_subcommand("simulate", "Generate a stiffness-experiment table from a known compliance set, with noise");
    static SimArgs a;
    cmd->add_option("--rig", a.rig, "rig file with the robot (DH table or URDF)")->required();
    cmd->add_option("--truth", a.truth, "truth file (JSON \"springs\", docs/calibration.md)")->required();
    cmd->add_option("--configs", a.configs, "random configurations within the joint limits")
        ->capture_default_str()
        ->check(CLI::Range(1, 1000000));
    cmd->add_option("--loads-per-config", a.loads, "random loads per configuration")->capture_default_str()->check(CLI::Range(1, 1000));
    cmd->add_option("--force-n", a.force_n, "force magnitude of each load, N")->capture_default_str();
    cmd->add_option("--moment-nm", a.moment_nm, "moment magnitude of each load, N·m")->capture_default_str();
    cmd->add_option("--measure", a.measure, "pose6 (dx..rz), point3 (dx dy dz) or markers")
        ->capture_default_str()
        ->check(CLI::IsMember({"pose6", "point3", "markers"}));
    cmd->add_option("--marker", a.markers, "marker position X,Y,Z in the tool frame, m (repeat)");
    cmd->add_option("--noise-pos-m", a.noise_pos_m, "position noise σ, m")->capture_default_str();
    cmd->add_option("--noise-rot-rad", a.noise_rot_rad, "rotation noise σ, rad")->capture_default_str();
    cmd->add_option("--seed", a.seed, "random seed")->capture_default_str();
    cmd->add_option("--out", a.out, "output CSV (default or -: stdout)");
    cmd->callback([] { set_action([] { return simulate(a); }); });
  }
  {
    auto* cmd = st->add_subcommand("table1", "Reproduce the counting of the paper's Table I and print it beside the paper's");
    static std::string rig, measure = "pose6";
    static int configs = 60;
    static std::uint64_t seed = 1;
    static bool complete = true;
    cmd->add_option("--rig", rig, "rig file (default: the built-in KR-270-like robot)");
    cmd->add_option("--configs", configs, "random configurations (2 loads each)")->capture_default_str();
    cmd->add_option("--measure", measure, "pose6, point3, point3-forces or markers")
        ->capture_default_str()
        ->check(CLI::IsMember({"pose6", "point3", "point3-forces", "markers"}));
    cmd->add_option("--seed", seed, "random seed")->capture_default_str();
    cmd->callback([] { set_action([] { return table1(rig, configs, measure, seed, complete); }); });
  }
  {
    auto* cmd = st->add_subcommand("replay", "Publish a stiffness-experiment table on the measurement topic");
    static std::string data, rig;
    static double rate = 0.0, wait = 5.0;
    cmd->add_option("DATA", data, "stiffness-experiment table (tool displacement columns)")->required();
    cmd->add_option("--rig", rig, "rig file (for the joint count)")->required();
    cmd->add_option("--rate-hz", rate, "measurements per second (0: as fast as possible)")->capture_default_str();
    cmd->add_option("--wait-readers-s", wait, "wait this long for a worker to match")->capture_default_str();
    cmd->callback([] { set_action([] { return replay(data, load_robot(rig).dof(), rate, wait); }); });
  }
  {
    auto* cmd = st->add_subcommand("worker", "Online identification: measurements in, an estimate out after each one");
    static std::string rig, model;
    static ReductionArgs a;
    static std::size_t count = 0;
    static double timeout = 0.0, period_ms = 0.0;
    cmd->add_option("--rig", rig, "rig file with the robot (DH table or URDF)")->required();
    cmd->add_option("--model", model, "keep the reduced model of an identify --json output (default: reduce online)");
    add_reduction_options(cmd, a);
    cmd->add_option("--count", count, "stop after this many measurements (0: run until interrupted)")->capture_default_str();
    cmd->add_option("--timeout-s", timeout, "stop after this long (0: never)")->capture_default_str();
    cmd->add_option("--estimate-period-ms", period_ms,
                    "estimate at most once a period (and one period after the last measurement); 0: after every measurement. "
                    "50 keeps up with a 1 kHz bus")
        ->capture_default_str();
    cmd->callback([] { set_action([] { return worker(rig, model, a, count, timeout, period_ms); }); });
  }
}

}  // namespace hil::cli
