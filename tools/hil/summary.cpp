#include "summary.hpp"

#include <fmt/format.h>

#include <hil/format/ros_frames.hpp>

namespace hil::cli {

void print_samples_summary(std::ostream& os, const format::SampleTable& t) {
  const auto s = format::summarize(t);
  os << fmt::format("  samples: {}, duration {:.3f} s, rate {:.2f} Hz (median step {:.3f} ms)\n", s.count, s.duration_s, s.rate_hz,
                    s.median_dt_s * 1e3);
  if (s.gaps.empty()) {
    os << "  gaps: none\n";
  } else {
    os << fmt::format("  gaps: {} (steps over 1.5x the median)\n", s.gaps.size());
    for (std::size_t i = 0; i < s.gaps.size() && i < 10; ++i)
      os << fmt::format("    before t = {:.4f} s (line {}): {:.3f} ms\n", s.gaps[i].t_s, s.gaps[i].line, s.gaps[i].dt_s * 1e3);
    if (s.gaps.size() > 10) os << fmt::format("    ... {} more\n", s.gaps.size() - 10);
  }
  os << fmt::format("  joints: {}{}\n", t.joint_count(),
                    t.extra_columns.empty() ? "" : fmt::format(", extra columns kept and ignored: {}", fmt::join(t.extra_columns, " ")));
  os << "  ranges:\n";
  for (const auto& r : s.ranges) os << fmt::format("    {:>3} [{: .6g}, {: .6g}]\n", r.column, r.min, r.max);
}

void print_rig_summary(std::ostream& os, const format::RigSpec& rig) {
  os << fmt::format("  rig '{}': {} frames", rig.name, rig.frames.size());
  if (rig.robot)
    os << (rig.robot->convention == format::DhConvention::urdf
               ? fmt::format(", robot '{}' ({} joints, URDF {} -> {})", rig.robot->name, rig.robot->joints.size(), rig.robot->base_link,
                             rig.robot->tip_link)
               : fmt::format(", robot '{}' ({} joints, {} DH)", rig.robot->name, rig.robot->joints.size(),
                             format::convention_name(rig.robot->convention)));
  os << '\n';
  const auto moving = format::moving_frame(&rig);
  os << fmt::format("  tf: {} -> {} on /tf with every sample{}\n", moving.parent, moving.child,
                    rig.robot ? fmt::format(" ({} -> {} on /tf_static)", rig.tf.world, rig.tf.base) : "");
  if (rig.robot)
    for (const auto& j : rig.robot->joints)
      if (!j.mimic_of.empty())
        os << fmt::format("    mimic joint {} = {:g} × {} {:+g}\n", j.name, j.mimic_multiplier, j.mimic_of, j.mimic_offset);
  os << fmt::format("  objects: {}, features: {}, polyhedra: {}\n", rig.objects.size(), format::total_features(rig),
                    format::total_polyhedra(rig));
  for (const auto& o : rig.objects)
    os << fmt::format("    {} (frame {}): {} features, {} polyhedra\n", o.name, o.frame, o.features.size(), o.polyhedron_count());
  if (rig.devices.force_plate) {
    const auto& d = *rig.devices.force_plate;
    os << fmt::format("  force plate: {} on {}, base id 0x{:x}, {} Hz\n", d.protocol, d.interface, d.base_id, d.rate_hz);
  }
  if (rig.devices.robot) {
    const auto& d = *rig.devices.robot;
    if (d.transport == "tcp")
      os << fmt::format("  robot controller: Modbus TCP {}:{} unit {}, map {}, {} Hz\n", d.host, d.port, d.unit_id, d.register_map,
                        d.rate_hz);
    else
      os << fmt::format("  robot controller: Modbus RTU {} {} baud unit {}, map {}, {} Hz\n", d.serial_device, d.baud, d.unit_id,
                        d.register_map, d.rate_hz);
  }
  if (rig.model.contact)
    os << fmt::format("  contact model: K = {:.4g} N/m, mu = {:.3g}, v_t,m = {:.3g} m/s\n", rig.model.contact->stiffness_n_per_m,
                      rig.model.contact->friction_coefficient, rig.model.contact->sticking_threshold_m_per_s);
  os << fmt::format("  geometric uncertainties: {}\n", rig.model.uncertainties.size());
}

nlohmann::json samples_summary_json(const format::SampleTable& t) {
  using nlohmann::json;
  const auto s = format::summarize(t);
  json j = {{"count", s.count},          {"duration_s", s.duration_s},       {"rate_hz", s.rate_hz},  {"median_step_s", s.median_dt_s},
            {"joints", t.joint_count()}, {"extra_columns", t.extra_columns}, {"gaps", json::array()}, {"ranges", json::object()}};
  for (const auto& g : s.gaps) j["gaps"].push_back({{"t_s", g.t_s}, {"dt_s", g.dt_s}, {"line", g.line}});
  for (const auto& r : s.ranges) j["ranges"][r.column] = {{"min", r.min}, {"max", r.max}};
  return j;
}

nlohmann::json rig_summary_json(const format::RigSpec& rig) {
  using nlohmann::json;
  json j = {{"name", rig.name},
            {"frames", rig.frames.size()},
            {"robot", nullptr},
            {"objects", json::array()},
            {"features", format::total_features(rig)},
            {"polyhedra", format::total_polyhedra(rig)},
            {"force_plate", nullptr},
            {"robot_controller", nullptr},
            {"contact_model", nullptr},
            {"geometric_uncertainties", rig.model.uncertainties.size()}};
  const auto moving = format::moving_frame(&rig);
  j["tf"] = {
      {"world", rig.tf.world}, {"base", rig.tf.base}, {"ee", rig.tf.ee}, {"moving_parent", moving.parent}, {"moving_child", moving.child}};
  if (rig.robot) {
    j["robot"] = {{"name", rig.robot->name},
                  {"joints", rig.robot->joints.size()},
                  {"convention", format::convention_name(rig.robot->convention)}};
    if (rig.robot->convention == format::DhConvention::urdf) {
      j["robot"]["urdf"] = rig.robot->urdf_file;
      j["robot"]["base_link"] = rig.robot->base_link;
      j["robot"]["tip_link"] = rig.robot->tip_link;
    }
  }
  for (const auto& o : rig.objects)
    j["objects"].push_back({{"name", o.name}, {"frame", o.frame}, {"features", o.features.size()}, {"polyhedra", o.polyhedron_count()}});
  if (rig.devices.force_plate) {
    const auto& d = *rig.devices.force_plate;
    j["force_plate"] = {{"protocol", d.protocol}, {"interface", d.interface}, {"base_id", d.base_id}, {"rate_hz", d.rate_hz}};
  }
  if (rig.devices.robot) {
    const auto& d = *rig.devices.robot;
    json r = {{"transport", d.transport}, {"unit_id", d.unit_id}, {"register_map", d.register_map}, {"rate_hz", d.rate_hz}};
    if (d.transport == "tcp") r["host"] = d.host, r["port"] = d.port;
    else r["serial_device"] = d.serial_device, r["baud"] = d.baud;
    j["robot_controller"] = r;
  }
  if (rig.model.contact)
    j["contact_model"] = {{"stiffness_n_per_m", rig.model.contact->stiffness_n_per_m},
                          {"friction_coefficient", rig.model.contact->friction_coefficient},
                          {"sticking_threshold_m_per_s", rig.model.contact->sticking_threshold_m_per_s}};
  return j;
}

nlohmann::json run_info_json(const format::RunInfo& info) {
  nlohmann::json j = {{"rig", info.rig},
                      {"start_time_utc", info.start_time_utc},
                      {"output_rate_hz", info.output_rate_hz},
                      {"sources", nlohmann::json::array()}};
  for (const auto& s : info.sources) j["sources"].push_back({{"name", s.name}, {"kind", s.kind}, {"rate_hz", s.rate_hz}, {"raw", s.raw}});
  return j;
}

nlohmann::json run_summary_json(const format::Run& run) {
  return {{"run_info", run_info_json(run.info)},
          {"samples", samples_summary_json(run.samples)},
          {"rig", run.rig ? rig_summary_json(*run.rig) : nlohmann::json()}};
}

void print_run_summary(std::ostream& os, const format::Run& run) {
  os << fmt::format("  recorded on rig '{}', started {}, output {} Hz\n", run.info.rig, run.info.start_time_utc, run.info.output_rate_hz);
  for (const auto& s : run.info.sources)
    os << fmt::format("  source {} ({}{}{})\n", s.name, s.kind, s.rate_hz > 0 ? fmt::format(", {} Hz", s.rate_hz) : "",
                      s.raw.empty() ? "" : ", raw " + s.raw);
  print_samples_summary(os, run.samples);
  if (run.rig) print_rig_summary(os, *run.rig);
  else os << "  rig: none in the run folder (pass --rig to check against one)\n";
}

}  // namespace hil::cli
