#include "summary.hpp"

#include <fmt/format.h>

namespace hil::cli {

void print_samples_summary(std::ostream& os, const format::SampleTable& t) {
  const auto s = format::summarize(t);
  os << fmt::format("  samples: {}, duration {:.3f} s, rate {:.2f} Hz (median step {:.3f} ms)\n", s.count, s.duration_s,
                    s.rate_hz, s.median_dt_s * 1e3);
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
    os << fmt::format(", robot '{}' ({} joints, {} DH)", rig.robot->name, rig.robot->joints.size(),
                      rig.robot->convention == format::DhConvention::standard ? "standard" : "modified");
  os << '\n';
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
      os << fmt::format("  robot controller: Modbus TCP {}:{} unit {}, map {}, {} Hz\n", d.host, d.port, d.unit_id, d.register_map, d.rate_hz);
    else
      os << fmt::format("  robot controller: Modbus RTU {} {} baud unit {}, map {}, {} Hz\n", d.serial_device, d.baud, d.unit_id, d.register_map, d.rate_hz);
  }
  if (rig.model.contact)
    os << fmt::format("  contact model: K = {:.4g} N/m, mu = {:.3g}, v_t,m = {:.3g} m/s\n", rig.model.contact->stiffness_n_per_m,
                      rig.model.contact->friction_coefficient, rig.model.contact->sticking_threshold_m_per_s);
  os << fmt::format("  geometric uncertainties: {}\n", rig.model.uncertainties.size());
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
