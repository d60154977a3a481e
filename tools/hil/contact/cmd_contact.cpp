// `hil contact simulate|identify|worker`: contact-parameter identification (issue 5).
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <thread>

#include <hil/cli/commands.hpp>
#include <hil/format/output.hpp>
#include <hil/error/error.hpp>
#include <hil/format/run.hpp>
#include <hil/diagnose/contact_family.hpp>
#include <hil/services/contact_identify.hpp>
#include <hil/models/contact.hpp>
#include <hil/services/contact_simulate.hpp>
#include "contact_commands.hpp"
#include <hil/services/contact_worker.hpp>

namespace hil::cli {

namespace contact = services::contact;
using services::contact::SimulateArgs;
using services::contact::simulate_run;
using format::human;
using format::is_stdout;
using format::tag_format;
using format::write_json;

namespace cid = hil::contact_id;
namespace fs = std::filesystem;

namespace {

struct IdentifyArgs {
  std::string run, rig, json, report;
  bool geometric = false;
  bool include_weak = false;
  std::string lambda = "auto", solver = "lm", jacobian = "golub-pereyra";
  int window = 25;
  int lcurve_points = 30;
};

int identify(const IdentifyArgs& a) {
  const auto run = format::load_run(a.run, a.rig);
  const auto problem = contact::problem_from_run(run);
  contact::IdentifyOptions o;
  o.geometric = a.geometric;
  o.lambda = a.lambda;
  o.solver = a.solver;
  o.jacobian = a.jacobian;
  o.window = a.window;
  o.lcurve_points = a.lcurve_points;
  o.include_weak = a.include_weak;
  const auto r = contact::identify(problem, o);
  auto& text = human(is_stdout(a.json));
  contact::print(text, problem, r);
  if (!a.json.empty()) write_json(a.json, contact::to_json(problem, r));
  if (!a.report.empty()) {
    contact::write_report(a.report, fs::path(a.run).filename().string(), problem, r);
    text << "report: " << (fs::path(a.report) / "index.html").string() << "\n";
  }
  return 0;
}

}  // namespace

void add_contact(CLI::App& app) {
  auto* contact = app.add_subcommand("contact", "Contact-parameter identification (stiffness, friction, geometry)");
  contact->require_subcommand(1);

  static SimulateArgs sa;
  auto* sim = contact->add_subcommand("simulate", "Simulate a run of the rig's contact scene along a trajectory");
  sim->add_option("--rig", sa.rig, "rig file (objects, frames, contact model)")->required();
  sim->add_option("--trajectory", sa.trajectory, "CSV: t,px,py,pz,qw,qx,qy,qz[,vx,vy,vz,wx,wy,wz] (ee in world)")->required();
  sim->add_option("--out", sa.out, "run folder to write")->required();
  sim->add_option("--truth", sa.truth, "YAML with the true K, mu, sensor model and geometric uncertainties");
  sim->add_option("--decimate", sa.decimate, "keep every Nth sample (e.g. 20: 1 kHz -> 50 Hz)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  sim->add_option("--force-resolution", sa.force_resolution, "N");
  sim->add_option("--moment-resolution", sa.moment_resolution, "N m");
  sim->add_option("--position-resolution", sa.position_resolution, "m");
  sim->add_option("--velocity-resolution", sa.velocity_resolution, "m/s");
  sim->add_option("--force-noise", sa.force_noise, "N (Gaussian std)");
  sim->add_option("--moment-noise", sa.moment_noise, "N m (Gaussian std)");
  sim->add_option("--seed", sa.seed, "noise seed");
  static const std::vector<std::string> injectable = hil::diagnose::injectable_contact_effects();
  sim->add_option("--inject", sa.inject,
                  fmt::format("hide an effect in the data (a diagnosis candidate: {}); repeatable", fmt::join(injectable, ", ")))
      ->delimiter(',')
      ->check(CLI::IsMember(injectable));
  sim->add_option("--effect-seed", sa.effect_seed, "seed of the injected effects' random magnitudes")->capture_default_str();
  sim->add_option("--truth-out", sa.truth_out, "write the injected effects (the hidden truth) as JSON (hil.hidden_effects; - for stdout)");
  sim->callback([] { set_action([] { return simulate_run(sa); }); });

  static std::string schema_out = "-";
  auto* schema =
      contact->add_subcommand("truth-schema",
                              "Write the JSON schema of --truth-out files (hil.hidden_effects), made from the diagnosis' effect registry");
  schema->add_option("--out", schema_out, "where to write it (- for stdout; docs/schemas/hil.hidden_effects.schema.json is this)")
      ->capture_default_str();
  schema->callback([] {
    set_action([] {
      write_json(schema_out, contact::hidden_effects_schema());
      return 0;
    });
  });

  static IdentifyArgs ia;
  auto* id = contact->add_subcommand("identify", "Identify K and mu (and optionally the geometric uncertainties) from a run");
  id->add_option("RUN", ia.run, "run folder")->required();
  id->add_option("--rig", ia.rig, "rig file (default: the run's rig.yaml)");
  id->add_flag("--geometric", ia.geometric, "also identify the rig's geometric uncertainties (variable projection)");
  id->add_flag("--include-weak", ia.include_weak, "also fit the weakly observable uncertainties");
  id->add_option("--lambda", ia.lambda, "Tikhonov weight, or 'auto' for the L-curve corner")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& v) {
            if (v == "auto") return std::string();
            char* end = nullptr;
            const double x = std::strtod(v.c_str(), &end);
            return end != v.c_str() && *end == '\0' && std::isfinite(x) && x >= 0 ? std::string()
                                                                                  : "expected a number >= 0 or 'auto', found '" + v + "'";
          },
          "NUMBER|auto"));
  id->add_option("--solver", ia.solver, "lm (Levenberg-Marquardt) or nm (Nelder-Mead)")
      ->capture_default_str()
      ->check(CLI::IsMember({"lm", "nm"}));
  id->add_option("--jacobian", ia.jacobian, "golub-pereyra or kaufman (lm only)")
      ->capture_default_str()
      ->check(CLI::IsMember({"golub-pereyra", "kaufman"}));
  id->add_option("--window", ia.window, "sliding window (samples) of the instantaneous estimates")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  id->add_option("--lcurve-points", ia.lcurve_points, "values of lambda on the L-curve")
      ->capture_default_str()
      ->check(CLI::Range(3, 10000));
  id->add_option("--json", ia.json, "write the results as JSON (hil.contact_identification; - for stdout, the text then goes to stderr)");
  id->add_option("--report", ia.report, "write an HTML report into this folder");
  id->callback([] { set_action([] { return identify(ia); }); });

  add_contact_worker(*contact);
}

}  // namespace hil::cli
