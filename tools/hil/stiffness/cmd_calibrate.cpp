// `hil calibrate RUN --rig RIG`: a calibration run (measured points of static postures) against the
// rig's robot: what the postures determine, the rigid model with the station frames and the tool
// point fitted, the candidate extensions by held-out error, the named cause (docs/calibration.md,
// "Point calibration"). The work is hil::services::point_calibration's.
#include <fmt/format.h>

#include <iostream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <hil/cli/commands.hpp>
#include <hil/error/error.hpp>
#include <hil/format/output.hpp>
#include <hil/services/point_calibration.hpp>

namespace hil::cli {

namespace {

struct CalibrateArgs {
  std::string run, rig, json, candidates, tool, report, bending_links;
  int folds = 0;
  bool orientation = false;
};

Eigen::Vector3d parse_point(const std::string& text) {
  Eigen::Vector3d p;
  char c1 = 0, c2 = 0;
  std::istringstream in(text);
  if (!(in >> p.x() >> c1 >> p.y() >> c2 >> p.z()) || c1 != ',' || c2 != ',' || !in.eof() || !p.allFinite())
    throw std::invalid_argument("expected X,Y,Z in metres, found '" + text + "'");
  return p;
}

std::vector<calibration::PointCandidate> parse_candidates(const std::string& text) {
  std::vector<calibration::PointCandidate> out;
  std::istringstream in(text);
  std::string name;
  while (std::getline(in, name, ',')) out.push_back(calibration::point_candidate_from_string(name));
  return out;
}

/// A CLI11 check from a parser that throws: bad values are usage errors (exit 2) found at parsing.
template <class Parse>
CLI::Validator checked_by(Parse parse, const std::string& what) {
  return CLI::Validator(
      [parse](std::string& s) {
        try {
          parse(s);
        } catch (const std::invalid_argument& e) {
          return std::string(e.what());
        }
        return std::string();
      },
      what);
}

int calibrate(const CalibrateArgs& a) {
  services::point_calibration::Options o;
  if (!a.candidates.empty()) o.candidates = parse_candidates(a.candidates);
  o.folds = a.folds;
  o.orientation = a.orientation;
  if (!a.tool.empty()) o.tool_point_start_ee_m = parse_point(a.tool);
  std::istringstream links(a.bending_links);
  for (std::string l; std::getline(links, l, ',');)
    if (!l.empty()) o.bending_links.push_back(l);
  const auto report = services::point_calibration::run(a.run, a.rig, o);
  auto& text = format::human(format::is_stdout(a.json));
  services::point_calibration::print(text, report);
  if (!a.json.empty()) format::write_json(a.json, services::point_calibration::to_json(report));
  if (!a.report.empty()) {
    services::point_calibration::write_report(report, a.report);
    text << fmt::format("report: {}/index.html\n", a.report);
  }
  return 0;
}

}  // namespace

void add_calibrate(CLI::App& app) {
  auto* cmd = app.add_subcommand("calibrate",
                                 "What a rigid robot model misses on a calibration run (measured points of static postures): station "
                                 "frames and tool point fitted, candidates by held-out error, the named cause");
  static CalibrateArgs args;
  cmd->add_option("RUN", args.run, "calibration run (CSV, docs/formats.md; hil import writes one from a lab's table)")->required();
  cmd->add_option("--rig", args.rig, "rig file with the robot (a URDF for the gravity candidates)")->required();
  cmd->add_option("--candidates", args.candidates,
                  "comma-separated: joint_offsets, joint_compliance, backlash, geometric, flag_offsets, link_bending, measured_tilt, "
                  "base_compliance "
                  "(default: all the run allows)")
      ->check(checked_by(parse_candidates, "NAME[,NAME...]"));
  cmd->add_option("--folds", args.folds, "one station: postures left out in this many folds (default 0: one at a time)")
      ->check(CLI::Range(0, 100000));
  cmd->add_option("--tool-point", args.tool, "where the measured point is believed to be in the tool frame, X,Y,Z m (default 0,0,0)")
      ->check(checked_by(parse_point, "X,Y,Z"));
  cmd->add_option("--bending-links", args.bending_links,
                  "URDF links that may bend for link_bending, comma-separated (default: every link spanning 0.2 m or more)");
  cmd->add_flag("--orientation", args.orientation,
                "fit the run's measured orientations too (rx ry rz), weighted by sigma_m/sigma_rad where stated, else 1 mm per mrad");
  cmd->add_option("--json", args.json, "also write the result as JSON (hil.point_calibration) to OUT, or - for stdout (text to stderr)");
  cmd->add_option("--report", args.report, "also write an HTML report (index.html, figures/) to this folder");
  cmd->callback([] { set_action([] { return calibrate(args); }); });
}

}  // namespace hil::cli
