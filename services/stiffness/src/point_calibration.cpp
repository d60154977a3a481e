#include <hil/services/point_calibration.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include <hil/error/error.hpp>
#include <hil/format/output.hpp>
#include <hil/format/rig.hpp>
#include <hil/models/stiffness.hpp>
#include <hil/report/html.hpp>

namespace hil::services::point_calibration {

namespace hc = hil::calibration;

Report run(const std::string& run_path, const std::string& rig_path, const Options& options) {
  Report r;
  r.run_path = run_path;
  r.rig_path = rig_path;
  const auto rig = format::load_rig(rig_path);
  if (!rig.robot) throw error::FormatError({rig_path, 0, 0, "robot"}, "the rig has no robot to calibrate");
  r.robot_name = rig.robot->name;
  r.robot_links = rig.robot->body_links;
  r.run = format::read_calibration_run(run_path, *rig.robot);
  const hc::SerialRobot robot = models::to_serial_robot(*rig.robot);
  for (const auto& j : robot.joints) r.joint_units.push_back(j.kind == hc::JointKind::prismatic ? "m" : "rad");
  for (const auto& p : r.run.postures) {
    hc::PointObservation o;
    o.q = p.q;
    o.station = static_cast<int>(std::find(r.run.stations.begin(), r.run.stations.end(), p.station) - r.run.stations.begin());
    o.p_station_m = p.p_measured_m;
    o.payload_kg = p.payload_kg;
    o.payload_com_ee_m = p.payload_com_m;
    o.sigma_m = p.sigma_m;
    o.flags = p.flags;
    o.tilts_rad = p.tilts_rad;
    o.r_station_rad = p.r_measured_rad;
    o.sigma_rad = p.sigma_rad;
    r.observations.push_back(o);
  }
  const int stations = static_cast<int>(r.run.stations.size());
  hc::PointFitOptions fo;
  fo.tool_point_start_ee_m = options.tool_point_start_ee_m;
  fo.station_names = r.run.stations;
  fo.flag_names = r.run.flag_names;
  if (options.orientation && !r.run.has_orientation)
    throw std::invalid_argument("--orientation: the run has no measured orientations (rx, ry, rz columns)");
  fo.fit_orientation = r.orientation = options.orientation;
  // Links by name to the chain's bodies (the run's reader has checked that tilt columns name one).
  const auto body_of = [&](const std::string& link, const std::string& what) {
    const auto& links = robot.body_links;
    const auto at = std::find(links.begin(), links.end(), link);
    if (at == links.end()) {
      std::string all;
      for (const auto& l : links) all += (all.empty() ? "" : ", ") + l;
      throw std::invalid_argument(what + " '" + link + "' is not a link of the robot's chain" +
                                  (all.empty() ? std::string(" (the robot has no link names: give it as a URDF)") : " (" + all + ")"));
    }
    return static_cast<int>(at - links.begin());
  };
  for (const auto& t : r.run.tilts) fo.tilts.push_back({body_of(t.link, "tilt column " + t.column + ": link"), t.axis, t.column});
  for (const auto& l : options.bending_links) {
    const int b = body_of(l, "bending link");
    if (b == 0) throw std::invalid_argument("bending link '" + l + "' is the chain's base: it moves with no joint");
    fo.bending_bodies.push_back(b);
  }
  std::vector<hc::PointCandidate> usable;
  for (const auto c : options.candidates) {
    if (c == hc::PointCandidate::rigid) continue;
    if (std::string why; !hc::usable(c, robot, r.observations, fo, &why)) {
      r.skipped.push_back(why);
      continue;
    }
    usable.push_back(c);
  }
  // The nuisance frames first (the rigid model): what the candidates could determine depends on
  // where the tool point is (a point on a joint's axis does not see that joint's offset).
  r.rigid = hc::fit_points(robot, r.observations, stations, {}, fo);
  fo.tool_point_start_ee_m = r.rigid.tool_point_ee_m;
  // What the postures determine, before any candidate's parameters are estimated.
  r.determined.push_back(hc::identifiability(robot, r.observations, stations, {}, fo));
  for (const auto c : usable) r.determined.push_back(hc::identifiability(robot, r.observations, stations, {c}, fo));
  r.comparison = hc::compare_point_candidates(robot, r.observations, stations, usable, options.folds, fo);
  if (r.comparison.cause >= 0) {
    const int shown = r.comparison.second_cause >= 0 ? r.comparison.second_cause : r.comparison.cause;
    // The named model as it was compared: link_bending on the links kept, not on those dropped.
    if (!r.comparison.bending_bodies.empty()) fo.bending_bodies = r.comparison.bending_bodies;
    r.cause = hc::fit_points(robot, r.observations, stations, r.comparison.rows[static_cast<std::size_t>(shown)].model, fo);
  }
  return r;
}

namespace {

std::string value_text(const hc::PointParameter& p) {
  if (!p.identifiable) return fmt::format("{:.6g} {} (not determined)", p.value, p.unit);
  return fmt::format("{:.6g} ± {:.2g} {} (95 %)", p.value, 1.96 * p.std, p.unit);
}

/// Rows of single candidates (the rest add a second candidate to the cause).
std::size_t usable_count(const Report& r) {
  std::size_t n = 0;
  for (const auto& row : r.comparison.rows) n += row.model.size() == 1 ? 1 : 0;
  return n;
}

}  // namespace

void print(std::ostream& os, const Report& r) {
  os << fmt::format("calibration run {}: {} postures of robot '{}', {} station(s){}\n", r.run_path, r.run.postures.size(), r.robot_name,
                    r.run.stations.size(),
                    r.orientation           ? " (points and orientations fitted)"
                    : r.run.has_orientation ? " (orientations given, not fitted: --orientation fits them too)"
                                            : "");
  os << "what the postures determine (each model with the nuisance frames: every station's pose, the tool point; at the rigid fit):\n";
  for (const auto& d : r.determined) {
    os << fmt::format("  {:<18} rank {:>3} of {:>3}", hc::to_string(d.model), d.rank, d.parameters_total);
    os << (d.undetermined.empty() ? "  all determined\n" : fmt::format("  undetermined ({}):\n", d.undetermined.size()));
    for (const auto& u : d.undetermined) os << "      " << u.text << "\n";
  }
  for (const auto& s : r.skipped) os << "  skipped: " << s << "\n";
  os << fmt::format(
      "rigid model, station frames and tool point fitted: {:.3f} mm RMS, {:.3f} mm max; tool point [{:.4f}, {:.4f}, {:.4f}] m\n",
      r.rigid.rms_m * 1e3, r.rigid.max_m * 1e3, r.rigid.tool_point_ee_m.x(), r.rigid.tool_point_ee_m.y(), r.rigid.tool_point_ee_m.z());
  if (r.orientation)
    os << fmt::format("  orientations: {:.3f} mrad RMS, {:.3f} mrad max; measured frame on the tool [{:.4f}, {:.4f}, {:.4f}] rad\n",
                      r.rigid.rms_rad * 1e3, r.rigid.max_rad * 1e3, r.rigid.tool_rotation_ee_rad.x(), r.rigid.tool_rotation_ee_rad.y(),
                      r.rigid.tool_rotation_ee_rad.z());
  os << fmt::format("candidates, held-out error ({}):\n", r.comparison.rigid.scheme);
  os << fmt::format("  {:<34} {:>6} {:>5} {:>12} {:>8} {:>7}\n", "model", "params", "rank", "held-out mm", "gain %", "z");
  os << fmt::format("  {:<34} {:>6} {:>5} {:>12.3f} {:>8} {:>7}\n", "rigid", r.determined.front().parameters_total,
                    r.determined.front().rank, r.comparison.rigid.rms_m * 1e3, "", "");
  for (std::size_t i = 0; i < r.comparison.rows.size(); ++i) {
    const auto& row = r.comparison.rows[i];
    const bool cause = static_cast<int>(i) == r.comparison.cause || static_cast<int>(i) == r.comparison.second_cause;
    os << fmt::format("  {:<34} {:>6} {:>5} {:>12.3f} {:>8.1f} {:>7.2f}{}\n", hc::to_string(row.model) + (row.model.size() > 1 ? " *" : ""),
                      row.parameters, row.rank, row.held_out.rms_m * 1e3, row.gain * 100, row.z, cause ? "  <-" : "");
  }
  if (r.comparison.rows.size() > usable_count(r)) os << "  (* against the cause alone)\n";
  if (const auto& n = r.comparison.noise; n.stated)
    os << fmt::format("rigid model against the stated noise: χ² {:.1f} on {:.0f} degrees of freedom (99 % bound {:.1f}): {:.2f} σ, {}\n",
                      n.chi2, n.dof, n.bound_99, n.rms_over_sigma, n.within ? "within the noise" : "above the noise");
  else os << "no measurement noise stated (sigma_m column): the rigid model is not tested against it\n";
  if (!r.comparison.bending_bodies.empty()) {
    std::string links;
    for (const int b : r.comparison.bending_bodies)
      links += (links.empty() ? "" : ", ") + (static_cast<std::size_t>(b) < r.robot_links.size()
                                                  ? r.robot_links[static_cast<std::size_t>(b)]
                                                  : "body " + std::to_string(b));
    os << "links that may bend (link_bending): " << links << "\n";
  }
  for (const auto& d : r.comparison.bending_dropped) os << "  " << d << "\n";
  os << "verdict: " << r.comparison.verdict << "\n";
  if (r.cause) {
    os << fmt::format("parameters of {} ({:.3f} mm RMS{}, noise estimate {:.3f} mm per coordinate):\n", hc::to_string(r.cause->model),
                      r.cause->rms_m * 1e3, r.orientation ? fmt::format(", {:.3f} mrad RMS", r.cause->rms_rad * 1e3) : std::string(),
                      r.cause->sigma_m * 1e3);
    for (const auto& p : r.cause->parameters)
      if (p.part != "station") os << fmt::format("  {:<32} {}\n", p.name, value_text(p));
  }
}

nlohmann::json to_json(const Report& r) {
  using nlohmann::json;
  json j;
  format::tag_format(j, "point_calibration");
  j["run"] = r.run_path;
  j["rig"] = r.rig_path;
  j["robot"] = r.robot_name;
  j["postures"] = r.run.postures.size();
  j["stations"] = r.run.stations;
  j["scheme"] = r.comparison.rigid.scheme;
  auto fit_json = [](const hc::PointFit& f) {
    json pars = json::array();
    for (const auto& p : f.parameters)
      pars.push_back({{"name", p.name},
                      {"unit", p.unit},
                      {"part", p.part},
                      {"value", p.value},
                      {"std", p.identifiable ? json(p.std) : json(nullptr)},
                      {"identifiable", p.identifiable}});
    json und = json::array();
    for (const auto& u : f.undetermined) {
      json terms = json::array();
      for (const auto& [n, w] : u.terms) terms.push_back({{"parameter", n}, {"coefficient", w}});
      und.push_back({{"text", u.text}, {"terms", terms}});
    }
    return json{{"model", hc::to_string(f.model)},
                {"rank", f.rank},
                {"parameters_total", f.parameters_total},
                {"condition", f.condition},
                {"rms_m", f.rms_m},
                {"max_m", f.max_m},
                {"sigma_m", std::isfinite(f.sigma_m) ? json(f.sigma_m) : json(nullptr)},
                {"tool_point_ee_m", {f.tool_point_ee_m.x(), f.tool_point_ee_m.y(), f.tool_point_ee_m.z()}},
                {"orientations", f.orientations},
                {"rms_rad", f.rms_rad},
                {"max_rad", f.max_rad},
                {"tool_rotation_ee_rad", {f.tool_rotation_ee_rad.x(), f.tool_rotation_ee_rad.y(), f.tool_rotation_ee_rad.z()}},
                {"parameters", pars},
                {"undetermined", und}};
  };
  j["determined"] = json::array();
  for (const auto& d : r.determined)
    j["determined"].push_back({{"model", hc::to_string(d.model)},
                               {"rank", d.rank},
                               {"parameters_total", d.parameters_total},
                               {"undetermined", fit_json(d)["undetermined"]}});
  j["rigid"] = fit_json(r.rigid);
  j["held_out"] = json::array();
  auto errors = [](const Eigen::VectorXd& e) { return std::vector<double>(e.data(), e.data() + e.size()); };
  j["held_out"].push_back({{"model", "rigid"},
                           {"rms_m", r.comparison.rigid.rms_m},
                           {"gain", 0.0},
                           {"z", 0.0},
                           {"against", "rigid"},
                           {"error_m", errors(r.comparison.rigid.error_m)}});
  for (std::size_t i = 0; i < r.comparison.rows.size(); ++i) {
    const auto& row = r.comparison.rows[i];
    const bool combined = row.model.size() > 1;
    j["held_out"].push_back({{"model", hc::to_string(row.model)},
                             {"rms_m", row.held_out.rms_m},
                             {"gain", row.gain},
                             {"z", std::isfinite(row.z) ? json(row.z) : json(nullptr)},
                             {"against", combined ? hc::to_string(hc::PointModel{row.model.front()}) : "rigid"},
                             {"error_m", errors(row.held_out.error_m)}});
  }
  auto name_of = [&](int i) { return i < 0 ? json(nullptr) : json(hc::to_string(r.comparison.rows[static_cast<std::size_t>(i)].model)); };
  j["cause"] = name_of(r.comparison.cause);
  j["second_cause"] = r.comparison.second_cause < 0
                          ? json(nullptr)
                          : json(hc::to_string(r.comparison.rows[static_cast<std::size_t>(r.comparison.second_cause)].model.back()));
  const auto& n = r.comparison.noise;
  json noise = nullptr;
  if (n.stated) {
    noise = {{"chi2", n.chi2}, {"dof", n.dof}, {"bound_99", n.bound_99}, {"within", n.within}, {"rms_over_sigma", n.rms_over_sigma}};
    noise["after_cause"] = r.comparison.cause < 0 ? json(nullptr)
                                                  : json{{"chi2", n.after_chi2},
                                                         {"dof", n.after_dof},
                                                         {"bound_99", n.after_bound_99},
                                                         {"within", n.after_within},
                                                         {"rms_over_sigma", n.after_rms_over_sigma}};
  }
  j["noise"] = noise;
  j["kind"] = r.comparison.kind;
  j["reduced"] = r.comparison.reduced.empty() ? json(nullptr) : json(r.comparison.reduced);
  j["orientation"] = r.orientation;
  j["alternatives"] = json::array();
  for (const int a : r.comparison.alternatives) j["alternatives"].push_back(name_of(a));
  j["not_physical"] = r.comparison.not_physical;
  j["bending_links"] = json::array();
  for (const int b : r.comparison.bending_bodies)
    j["bending_links"].push_back(static_cast<std::size_t>(b) < r.robot_links.size() ? r.robot_links[static_cast<std::size_t>(b)]
                                                                                    : "body " + std::to_string(b));
  j["bending_dropped"] = r.comparison.bending_dropped;
  j["flags"] = r.run.flag_names;
  j["tilts"] = json::array();
  for (const auto& t : r.run.tilts) j["tilts"].push_back(t.column);
  j["verdict"] = r.comparison.verdict;
  j["cause_fit"] = r.cause ? fit_json(*r.cause) : json(nullptr);
  j["skipped"] = r.skipped;
  return j;
}

void write_report(const Report& r, const std::string& dir) {
  namespace rp = hil::report;
  rp::Page page("Calibration of " + r.robot_name + ": " + r.run_path);
  const auto& cmp = r.comparison;
  const bool named = cmp.cause >= 0;
  const auto* cause_row = named ? &cmp.rows[static_cast<std::size_t>(cmp.cause)] : nullptr;
  rp::Verdict v;
  v.kind = cmp.kind;
  v.headline = named ? "What the rigid model misses: " + hc::to_string(cause_row->model) +
                           (cmp.second_cause >= 0
                                ? " and " + std::string(hc::to_string(cmp.rows[static_cast<std::size_t>(cmp.second_cause)].model.back()))
                                : "")
               : cmp.kind == "unexplained" ? "Unexplained: the rigid model misses more than the noise, and no candidate explains it"
               : cmp.noise.stated          ? "Nothing to calibrate: the rigid model is within the stated measurement noise"
                                           : "No candidate predicts the held-out postures better than the rigid model";
  v.facts.push_back({"postures", fmt::format("{} from {} station(s)", r.run.postures.size(), r.run.stations.size())});
  v.facts.push_back({"rigid model, frames fitted", fmt::format("{:.2f} mm RMS, {:.2f} mm max", r.rigid.rms_m * 1e3, r.rigid.max_m * 1e3)});
  v.facts.push_back({"held-out error (" + cmp.rigid.scheme + ")",
                     named ? fmt::format("{:.2f} → {:.2f} mm RMS (gain {:.1f} %, z {:.2f})", cmp.rigid.rms_m * 1e3,
                                         cause_row->held_out.rms_m * 1e3, cause_row->gain * 100, cause_row->z)
                           : fmt::format("{:.2f} mm RMS", cmp.rigid.rms_m * 1e3)});
  if (cmp.noise.stated)
    v.facts.push_back({"against the stated noise",
                       fmt::format("χ² {:.1f} on {:.0f} dof (99 % bound {:.1f}): residual {:.2f} σ", cmp.noise.chi2, cmp.noise.dof,
                                   cmp.noise.bound_99, cmp.noise.rms_over_sigma)});
  if (!cmp.alternatives.empty()) {
    std::string alt;
    for (const int a : cmp.alternatives) alt += (alt.empty() ? "" : ", ") + hc::to_string(cmp.rows[static_cast<std::size_t>(a)].model);
    v.facts.push_back({"not told apart from", alt + " (explains these postures as well by the rules)"});
  }
  if (r.cause)
    v.facts.push_back({"determined", fmt::format("{} of {} parameters of {} (with the nuisance frames)", r.cause->rank,
                                                 r.cause->parameters_total, hc::to_string(r.cause->model))});
  v.next =
      named ? "Calibrate the determined parameters of " + hc::to_string(r.cause->model) +
                  "; add postures that separate the undetermined combinations listed below before trusting the rest."
      : cmp.kind == "unexplained"
          ? "Look for an effect outside the candidates (link bending, base compliance, a measurement-device error), or check the stated "
            "noise."
      : cmp.noise.stated ? "Nothing to do: the nominal model with the fitted frames is as good as the measurement."
                         : "State the measuring device's noise (sigma_m column) to tell 'within the noise' from 'unexplained'.";
  page.verdict(v);

  page.heading("What the postures determine");
  page.paragraph("Each model with the nuisance frames (every station's pose, the tool point), at the rigid fit, before its own parameters "
                 "are estimated: rank of the Jacobian and the combinations of named parameters the postures do not separate.");
  std::vector<std::vector<std::string>> rows;
  for (const auto& d : r.determined) {
    std::string und;
    for (const auto& u : d.undetermined) und += (und.empty() ? "" : "; ") + u.text;
    rows.push_back({hc::to_string(d.model), std::to_string(d.parameters_total), std::to_string(d.rank), und.empty() ? "—" : und});
  }
  page.table({"model", "parameters", "rank", "undetermined combinations"}, rows);

  page.heading("Candidates");
  rows.clear();
  std::vector<std::size_t> bold;
  rows.push_back({"rigid", fmt::format("{:.3f}", cmp.rigid.rms_m * 1e3), "", "", "rigid"});
  rp::Bars bars;
  bars.series = {"held-out RMS (mm)"};
  bars.value.emplace_back();
  bars.groups.push_back("rigid");
  bars.value[0].push_back(cmp.rigid.rms_m * 1e3);
  for (std::size_t i = 0; i < cmp.rows.size(); ++i) {
    const auto& row = cmp.rows[i];
    const bool combined = row.model.size() > 1;
    rows.push_back({hc::to_string(row.model), fmt::format("{:.3f}", row.held_out.rms_m * 1e3), fmt::format("{:.1f}", row.gain * 100),
                    std::isfinite(row.z) ? fmt::format("{:.2f}", row.z) : "∞",
                    combined ? hc::to_string(hc::PointModel{row.model.front()}) : "rigid"});
    if (static_cast<int>(i) == cmp.cause || static_cast<int>(i) == cmp.second_cause) bold.push_back(rows.size() - 1);
    bars.groups.push_back(hc::to_string(row.model));
    bars.value[0].push_back(row.held_out.rms_m * 1e3);
  }
  page.table({"model", "held-out RMS (mm)", "gain (%)", "z", "against"}, rows, bold);
  rp::PlotOptions bo;
  bo.title = "held-out error per model (" + cmp.rigid.scheme + ")";
  bo.xlabel = "held-out RMS (mm)";
  page.bars(bars, bo);
  page.paragraph(cmp.verdict);

  page.heading("Residuals per posture");
  rp::Bars per;
  per.series = {"rigid"};
  if (r.cause) per.series.push_back(hc::to_string(r.cause->model));
  per.value.resize(per.series.size());
  std::vector<rp::Series> xy(per.series.size()), xz(per.series.size());
  for (std::size_t k = 0; k < r.run.postures.size(); ++k) {
    per.groups.push_back(r.run.postures[k].id);
    const hc::PointFit* fits[] = {&r.rigid, r.cause ? &*r.cause : nullptr};
    for (std::size_t s = 0; s < per.series.size(); ++s) {
      const Eigen::Vector3d e = fits[s]->residual_m.segment<3>(3 * static_cast<Eigen::Index>(k)) * 1e3;
      per.value[s].push_back(e.norm());
      xy[s].x.push_back(e.x()), xy[s].y.push_back(e.y());
      xz[s].x.push_back(e.x()), xz[s].y.push_back(e.z());
    }
  }
  for (std::size_t s = 0; s < per.series.size(); ++s) {
    xy[s].name = xz[s].name = per.series[s];
    xy[s].points = xz[s].points = true;
    xy[s].point_radius = xz[s].point_radius = 3.0;
  }
  rp::PlotOptions po;
  po.title = "|predicted − measured| per posture, fitted";
  po.xlabel = "distance (mm)";
  po.wide = true;
  page.bars(per, po);
  rp::PlotOptions t1;
  t1.title = "residual vectors, x-y (station frame)";
  t1.xlabel = "x (mm)";
  t1.ylabel = "y (mm)";
  page.plot(xy, t1);
  rp::PlotOptions t2 = t1;
  t2.title = "residual vectors, x-z (station frame)";
  t2.ylabel = "z (mm)";
  page.plot(xz, t2);

  // Per joint: the residual against the joint's value. An offset or a frame error of that joint
  // shows as a pattern in its angle; compliance and bending as one in the gravity-loaded joints.
  page.heading("Residuals against each joint");
  page.paragraph("The 3-D residual of each posture against each joint's value, before (rigid) and after (" +
                 (r.cause ? hc::to_string(r.cause->model) : std::string("no cause named")) +
                 "): what is left of a pattern in a joint's angle is what the named model does not explain.");
  for (std::size_t j = 0; j < r.run.joint_names.size(); ++j) {
    std::vector<rp::Series> joint(per.series.size());
    for (std::size_t s = 0; s < per.series.size(); ++s) {
      joint[s].name = per.series[s];
      joint[s].points = true;
      joint[s].point_radius = 3.0;
      for (std::size_t k = 0; k < r.run.postures.size(); ++k) {
        joint[s].x.push_back(r.run.postures[k].q[static_cast<Eigen::Index>(j)]);
        joint[s].y.push_back(per.value[s][k]);
      }
    }
    rp::PlotOptions jo;
    jo.title = "residual against " + r.run.joint_names[j];
    jo.xlabel = r.run.joint_names[j] + " (" + (j < r.joint_units.size() ? r.joint_units[j] : "rad or m") + ")";
    jo.ylabel = "|residual| (mm)";
    page.plot(joint, jo);
  }

  if (r.cause) {
    page.heading("Parameters of " + hc::to_string(r.cause->model));
    rows.clear();
    std::vector<rp::Interval> forest;
    for (const auto& p : r.cause->parameters) {
      if (p.part == "station") continue;
      rows.push_back({p.name, fmt::format("{:.6g}", p.value), p.identifiable ? fmt::format("± {:.3g}", 1.96 * p.std) : "not determined",
                      p.unit});
      if (p.identifiable && p.part != "tool") {
        rp::Interval in;
        in.name = p.name;
        in.unit = p.unit;
        in.value = p.value;
        in.lower = p.value - 1.96 * p.std;
        in.upper = p.value + 1.96 * p.std;
        in.reference = 0.0;
        forest.push_back(in);
      }
    }
    page.table({"parameter", "value", "95 % interval", "unit"}, rows);
    if (!forest.empty()) page.forest(forest, "determined parameters, 95 % intervals", "nominal (0)");
  }
  std::ostringstream text;
  print(text, r);
  page.text_download("The text summary", "calibration.txt", text.str());
  std::filesystem::create_directories(dir);
  page.write((std::filesystem::path(dir) / "index.html").string());
  page.write_figures((std::filesystem::path(dir) / "figures").string());
}

}  // namespace hil::services::point_calibration
