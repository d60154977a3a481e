#include <hil/import/importer.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <unordered_map>

#include <hil/format/csv.hpp>
#include <hil/format/edit_distance.hpp>
#include <hil/error/error.hpp>
#include <hil/import/rigid_fit.hpp>
#include <hil/so3/so3.hpp>
#include <hil/import/timeparse.hpp>

namespace hil::import {

using error::FormatError;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

/// The data's cells by row and column index (data_options reads every column as text).
class Cells {
 public:
  explicit Cells(const format::CsvTable& t) {
    for (const auto& h : t.header) columns_.push_back(&t.text(h));
  }
  const std::string& operator()(std::size_t r, std::size_t c) const { return (*columns_[c])[r]; }

 private:
  std::vector<const std::vector<std::string>*> columns_;
};

/// Column lookup with a message naming the data file's header and the closest name.
struct Columns {
  const format::CsvTable& data;
  const ImportConfig& cfg;
  std::unordered_map<std::string, std::size_t> index;

  Columns(const format::CsvTable& d, const ImportConfig& c) : data(d), cfg(c) {
    for (std::size_t i = 0; i < d.header.size(); ++i) index.emplace(d.header[i], i);
  }
  std::size_t operator()(const std::string& name, const std::string& role) const {
    const auto it = index.find(name);
    if (it != index.end()) return it->second;
    std::string hint;
    std::size_t best = 3;
    for (std::size_t i = 0; i < data.header.size(); ++i) {
      const auto dist = format::edit_distance(name, data.header[i]);
      if (dist < best) best = dist, hint = fmt::format(" (column {} is '{}': misspelt?)", i + 1, data.header[i]);
    }
    throw FormatError({data.file, data.header_line, 0, name},
                      fmt::format("column named in {} as {} is not in the data{}; the data has {} columns", cfg.file, role, hint,
                                  data.header.size()));
  }
};

/// One data row after parsing: time, wrench, markers, joints, extras.
struct ParsedRow {
  double time_raw = 0;  ///< us since 1970 (datetime) or file units (seconds)
  bool wrench_ok = true, joints_ok = true;
  Eigen::Vector3d f_data, m_data;
  std::vector<Eigen::Matrix3Xd> markers_world_m;  ///< per body
  std::vector<std::vector<bool>> seen;            ///< per body, per marker
  std::vector<double> joints, extras;
};

}  // namespace

format::CsvOptions data_options(char delimiter, bool header, const std::vector<std::string>& names, const std::string& display_name) {
  format::CsvOptions o;
  o.display_name = display_name;
  o.delimiter = delimiter;
  if (!header) o.column_names = names;
  o.missing = format::MissingCells::nan;  // as import_table reads the cells
  o.skip_blank_lines = true;
  o.skip_byte_order_mark = true;  // a UTF-8 byte-order mark is not a column name
  return o;
}

format::CsvTable read_delimited(const std::string& path, char delimiter, bool header, const std::vector<std::string>& names) {
  return format::read_csv(path, data_options(delimiter, header, names));
}

namespace {

/// Where each configured quantity sits in the table (0-based column indices).
struct ColumnIndex {
  std::size_t time = 0;
  std::array<std::size_t, 3> force{}, moment{};
  std::vector<std::vector<std::array<std::size_t, 3>>> markers;  ///< per body, per marker: x, y, z
  std::vector<std::size_t> joints, extras;
};

ColumnIndex resolve_columns(const format::CsvTable& data, const ImportConfig& cfg) {
  const Columns col(data, cfg);
  ColumnIndex c;
  c.time = col(cfg.time.column, "time.column");
  for (std::size_t k = 0; k < 3; ++k) {
    c.force[k] = col(cfg.wrench.force_columns[k], "wrench.force");
    c.moment[k] = col(cfg.wrench.moment_columns[k], "wrench.moment");
  }
  for (const auto& body : cfg.bodies) {
    c.markers.emplace_back();
    for (const auto& mk : body.markers) {
      std::array<std::size_t, 3> xyz{};
      for (std::size_t k = 0; k < 3; ++k) xyz[k] = col(mk.columns[k], fmt::format("marker '{}' of body '{}'", mk.name, body.name));
      c.markers.back().push_back(xyz);
    }
  }
  for (const auto& j : cfg.joint_columns) c.joints.push_back(col(j, "a joint"));
  for (const auto& x : cfg.extras) c.extras.push_back(col(x.column, "an extra column"));
  return c;
}

/// Extra samples.csv columns: per-body fit quality, the other bodies' poses, then the config's extras.
std::vector<std::string> output_extra_names(const ImportConfig& cfg, std::size_t ee) {
  std::vector<std::string> names;
  for (std::size_t b = 0; b < cfg.bodies.size(); ++b) {
    const auto& name = cfg.bodies[b].name;
    names.push_back(name + "_fit_rms_m");
    names.push_back(name + "_markers_seen");
    if (b != ee)
      for (const char* s : {"_px", "_py", "_pz", "_qw", "_qx", "_qy", "_qz"}) names.push_back(name + s);
  }
  for (const auto& x : cfg.extras) {
    if (std::find(names.begin(), names.end(), x.name) != names.end())
      throw FormatError({cfg.file, 0, 0, "extra_columns"},
                        fmt::format("output name '{}' is also written by the importer; rename it", x.name));
    names.push_back(x.name);
  }
  return names;
}

/// Reads one row: text that is not a number is an error; empty and NaN cells are marked missing.
ParsedRow parse_row(const format::CsvTable& data, const Cells& cells, std::size_t r, const ImportConfig& cfg, const ColumnIndex& col) {
  auto number = [&](std::size_t c, double& v) {
    v = format::read_number(cells(r, c), {data.file, data.row_line[r], c + 1, data.header[c]}, format::MissingCells::nan);
    return !std::isnan(v);
  };
  ParsedRow p;
  const auto& time_text = cells(r, col.time);
  if (cfg.time.format == TimeFormat::datetime) {
    std::string why;
    const auto us = parse_datetime_us(time_text, cfg.time.pattern, &why);
    if (!us)
      throw FormatError({data.file, data.row_line[r], col.time + 1, data.header[col.time]},
                        fmt::format("bad time text '{}': {}", time_text, why));
    p.time_raw = static_cast<double>(*us);  // exact: integers below 2^53 us (year 2255)
  } else if (!number(col.time, p.time_raw)) {
    throw FormatError({data.file, data.row_line[r], col.time + 1, data.header[col.time]}, "empty or NaN time");
  }
  for (std::size_t k = 0; k < 3; ++k) {
    p.wrench_ok = number(col.force[k], p.f_data[static_cast<Eigen::Index>(k)]) && p.wrench_ok;
    p.wrench_ok = number(col.moment[k], p.m_data[static_cast<Eigen::Index>(k)]) && p.wrench_ok;
  }
  for (const auto& body_cols : col.markers) {
    const auto nm = body_cols.size();
    Eigen::Matrix3Xd w(3, static_cast<Eigen::Index>(nm));
    std::vector<bool> seen(nm, true);
    for (std::size_t i = 0; i < nm; ++i) {
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      bool ok = true;
      for (std::size_t k = 0; k < 3; ++k) ok = number(body_cols[i][k], x[static_cast<Eigen::Index>(k)]) && ok;
      if (ok && cfg.zero_marker_is_missing && x.isZero(0.0)) ok = false;
      seen[i] = ok;
      w.col(static_cast<Eigen::Index>(i)) = ok ? Eigen::Vector3d(x * cfg.marker_m_per_unit) : Eigen::Vector3d::Constant(kNaN);
    }
    p.markers_world_m.push_back(std::move(w));
    p.seen.push_back(std::move(seen));
  }
  for (const auto c : col.joints) {
    double v = 0;
    p.joints_ok = number(c, v) && p.joints_ok;
    p.joints.push_back(v * cfg.joint_si_per_unit);
  }
  for (std::size_t x = 0; x < col.extras.size(); ++x) {
    double v = 0;
    p.extras.push_back(number(col.extras[x], v) ? v * cfg.extras[x].scale : kNaN);
  }
  return p;
}

/// Counts dropped rows by reason, remembering the first line of each.
class DropLog {
 public:
  void add(const std::string& reason, std::size_t line) {
    auto& d = drops_[reason];
    if (d.count++ == 0) d.reason = reason, d.first_line = line;
  }
  std::vector<DropCount> list() const {
    std::vector<DropCount> out;
    for (const auto& [reason, d] : drops_) out.push_back(d);
    return out;
  }

 private:
  std::map<std::string, DropCount> drops_;
};

/// Rows with strictly increasing time and a complete wrench and joint set, in file order.
std::vector<std::size_t> usable_rows(const format::CsvTable& data, const Cells& cells, const std::vector<ParsedRow>& rows,
                                     const ImportConfig& cfg, std::size_t c_time, DropLog& drops) {
  std::vector<std::size_t> keep;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    if (!keep.empty() && rows[r].time_raw <= rows[keep.back()].time_raw) {
      const bool dup = rows[r].time_raw == rows[keep.back()].time_raw;
      if (cfg.time.non_increasing == NonIncreasingTime::error)
        throw FormatError({data.file, data.row_line[r], c_time + 1, data.header[c_time]},
                          fmt::format("{} (line {} has '{}'); set time.non_increasing: drop to drop such rows",
                                      dup ? "duplicated timestamp" : "time goes backwards", data.row_line[keep.back()],
                                      cells(keep.back(), c_time)));
      drops.add(dup ? "duplicated timestamp" : "time goes backwards", data.row_line[r]);
    } else if (!rows[r].wrench_ok) {
      drops.add("force or moment cell empty or NaN", data.row_line[r]);
    } else if (!rows[r].joints_ok) {
      drops.add("joint cell empty or NaN", data.row_line[r]);
    } else {
      keep.push_back(r);
    }
  }
  return keep;
}

/// The body-frame marker positions: given, or the mean of the first rows that see every marker.
Eigen::Matrix3Xd reference_markers(const BodySpec& body, std::size_t b, const std::vector<ParsedRow>& rows,
                                   const std::vector<std::size_t>& keep, const std::string& config_file, std::size_t& rows_used) {
  const auto nm = static_cast<Eigen::Index>(body.markers.size());
  Eigen::Matrix3Xd ref(3, nm);
  rows_used = 0;
  if (!body.reference_body_m.empty()) {
    for (Eigen::Index i = 0; i < nm; ++i) ref.col(i) = body.reference_body_m[static_cast<std::size_t>(i)];
  } else {
    ref.setZero();
    for (std::size_t k = 0; k < keep.size() && rows_used < body.reference_rows; ++k) {
      const auto& p = rows[keep[k]];
      if (std::find(p.seen[b].begin(), p.seen[b].end(), false) != p.seen[b].end()) continue;
      ref += p.markers_world_m[b];
      ++rows_used;
    }
    if (rows_used == 0)
      throw FormatError({config_file, 0, 0, "bodies." + body.name},
                        "no row sees all markers of this body, so the reference cannot be taken from the data; give "
                        "reference_m");
    ref /= static_cast<double>(rows_used);
    if (body.origin == BodyOrigin::marker_centroid) ref.colwise() -= Eigen::Vector3d(ref.rowwise().mean());
  }
  if (planarity_ratio(ref) < 1e-3)
    throw FormatError({config_file, 0, 0, "bodies." + body.name},
                      "the reference marker positions are (nearly) collinear: the rotation about their line is "
                      "undetermined");
  return ref;
}

/// The pose of one body in one row, or why there is none.
std::optional<RigidFit> fit_body(const BodySpec& body, const Eigen::Matrix3Xd& ref, const ParsedRow& p, std::size_t b, std::string& why) {
  FitFailure failure;
  auto fit = fit_rigid_body(ref, p.markers_world_m[b], p.seen[b], body.min_markers, &failure);
  if (fit && body.max_residual_m > 0 && fit->residual_rms_m > body.max_residual_m) {
    failure.reason = fmt::format("fit residual {:.3g} mm above max_residual_m", fit->residual_rms_m * 1e3);
    fit.reset();
  }
  why = failure.reason;
  return fit;
}

/// Fit residuals and motion range of one body over the written rows.
BodyStats body_statistics(BodyStats st, const std::vector<const RigidFit*>& fits) {
  std::vector<double> rms;
  Eigen::Vector3d pmin = Eigen::Vector3d::Constant(1e300), pmax = -pmin, rmin = pmin, rmax = -pmin;
  const RigidFit* first = nullptr;
  for (const RigidFit* fit : fits) {
    if (!fit) {
      ++st.no_pose;
      continue;
    }
    if (!first) first = fit;
    ++st.fitted;
    if (fit->markers_used < st.markers) ++st.reduced;
    rms.push_back(fit->residual_rms_m);
    st.rms_max_m = std::max(st.rms_max_m, fit->residual_rms_m);
    pmin = pmin.cwiseMin(fit->p_world_body_m);
    pmax = pmax.cwiseMax(fit->p_world_body_m);
    const Eigen::Vector3d rv = so3::log(first->R_world_body.transpose() * fit->R_world_body);
    rmin = rmin.cwiseMin(rv);
    rmax = rmax.cwiseMax(rv);
    st.max_displacement_m = std::max(st.max_displacement_m, (fit->p_world_body_m - first->p_world_body_m).norm());
    st.max_rotation_rad = std::max(st.max_rotation_rad, rv.norm());
  }
  if (!rms.empty()) {
    double sum = 0;
    for (double v : rms) sum += v;
    st.rms_mean_m = sum / static_cast<double>(rms.size());
    st.rms_median_m = median(rms);
    st.p_range_m = pmax - pmin;
    st.rot_range_rad = rmax - rmin;
  }
  return st;
}

/// Quaternion of R with the sign closest to `prev` (w >= 0 without one): continuous over a run.
Eigen::Quaterniond continuous_quaternion(const Eigen::Matrix3d& R, const std::optional<Eigen::Quaterniond>& prev) {
  Eigen::Quaterniond q(R);
  q.normalize();
  if (prev ? q.coeffs().dot(prev->coeffs()) < 0 : q.w() < 0) q.coeffs() = -q.coeffs();
  return q;
}

std::string run_notes(const ImportReport& rep, const ImportConfig& cfg, std::size_t ee, bool start_known,
                      const std::vector<std::string>& extra_names) {
  const bool datetime = cfg.time.format == TimeFormat::datetime;
  std::string notes = fmt::format("Imported by `hil import` from {} with the mapping {}.\n",
                                  std::filesystem::path(rep.data_file).filename().string(),
                                  std::filesystem::path(rep.config_file).filename().string());
  notes += fmt::format("Rows: {} read, {} written", rep.rows_read, rep.rows_written);
  for (const auto& d : rep.dropped) notes += fmt::format("; {} dropped: {} (first on line {})", d.count, d.reason, d.first_line);
  notes += ".\n";
  if (datetime && rep.clock_taken_as_utc)
    notes += "Time: the data's clock carries no time zone; it is taken as UTC, so start_time is the clock's own "
             "reading with a Z appended (set time.utc_offset_h to convert).\n";
  else if (datetime) notes += fmt::format("Time: the data's clock is UTC{:+g} h, converted to UTC.\n", *cfg.time.utc_offset_h);
  else if (!start_known) notes += "Time: the data's absolute start time is unknown; start_time is a placeholder (1970-01-01).\n";
  notes += fmt::format("Steps: median {:.2f} ms, {} gaps longer than {} x the median (longest {:.1f} ms), kept as they are.\n",
                       rep.median_dt_s * 1e3, rep.gaps.size(), cfg.time.gap_factor, rep.max_dt_s * 1e3);
  const auto& eb = cfg.bodies[ee];
  notes += fmt::format("ee: the pose of body '{}' fitted to {} markers (Kabsch/SVD); frame {}; twist from a {:.0f} ms "
                       "local-line fit.\n",
                       eb.name, eb.markers.size(),
                       !eb.reference_body_m.empty() ? "as given by reference_m"
                       : eb.origin == BodyOrigin::marker_centroid
                           ? "at the markers' mean centroid, axes along the world's, over the first rows"
                           : "equal to the world frame over the first rows",
                       cfg.twist_window_s * 1e3);
  notes += "Extra columns: ";
  for (std::size_t i = 0; i < extra_names.size(); ++i) notes += (i ? ", " : "") + extra_names[i];
  notes += ".\n";
  if (!cfg.notes.empty()) notes += cfg.notes + (cfg.notes.back() == '\n' ? "" : "\n");
  return notes;
}

}  // namespace

ImportedRun import_table(const format::CsvTable& data, const ImportConfig& cfg, const std::string& rig_name) {
  if (data.rows() == 0) throw FormatError({data.file, 0, 0, ""}, "no data rows");
  const std::size_t nb = cfg.bodies.size();
  std::size_t ee = 0;
  for (std::size_t b = 0; b < nb; ++b)
    if (cfg.bodies[b].name == cfg.ee_body) ee = b;
  const ColumnIndex col = resolve_columns(data, cfg);
  const auto extra_names = output_extra_names(cfg, ee);
  const std::size_t n_generated = extra_names.size() - cfg.extras.size();

  const Cells cells(data);
  std::vector<ParsedRow> rows;
  rows.reserve(data.rows());
  for (std::size_t r = 0; r < data.rows(); ++r) rows.push_back(parse_row(data, cells, r, cfg, col));

  ImportReport rep;
  rep.data_file = data.file;
  rep.config_file = cfg.file;
  rep.rows_read = rows.size();
  DropLog drops;
  const auto keep = usable_rows(data, cells, rows, cfg, col.time, drops);

  std::vector<Eigen::Matrix3Xd> ref_body_m(nb);
  rep.bodies.resize(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    auto& st = rep.bodies[b];
    st.name = cfg.bodies[b].name;
    st.is_ee = b == ee;
    st.markers = cfg.bodies[b].markers.size();
    ref_body_m[b] = reference_markers(cfg.bodies[b], b, rows, keep, cfg.file, st.reference_rows_used);
  }

  // Fit every body in every usable row; a row without an ee pose is dropped.
  struct Fitted {
    std::size_t row;
    std::vector<std::optional<RigidFit>> fits;
  };
  std::vector<Fitted> out;
  out.reserve(keep.size());
  for (const auto r : keep) {
    Fitted f{r, std::vector<std::optional<RigidFit>>(nb)};
    std::string why, ee_why;
    for (std::size_t b = 0; b < nb; ++b) {
      f.fits[b] = fit_body(cfg.bodies[b], ref_body_m[b], rows[r], b, why);
      if (!f.fits[b] && b == ee) ee_why = why;
    }
    if (!f.fits[ee]) {
      drops.add(fmt::format("body '{}' (the ee): {}", cfg.bodies[ee].name, ee_why), data.row_line[r]);
      continue;
    }
    out.push_back(std::move(f));
  }
  rep.dropped = drops.list();
  if (out.size() < 2)
    throw FormatError({data.file, 0, 0, ""},
                      fmt::format("only {} usable rows of {} (see the dropped rows): a run needs at least 2", out.size(), rows.size()));

  // Samples: time since the first written row, ee pose, wrench in the plate frame, joints, extras.
  const std::size_t n = out.size();
  const bool datetime = cfg.time.format == TimeFormat::datetime;
  const double t0_raw = rows[out.front().row].time_raw;
  const double raw_per_s = datetime ? 1e6 : std::round(1.0 / cfg.time.s_per_unit);  // 1, 1e3, 1e6, 1e9
  ImportedRun run;
  run.extra_names = extra_names;
  run.extra_values = Eigen::MatrixXd::Constant(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(extra_names.size()), kNaN);
  auto& tab = run.table;
  tab.file = "samples.csv";
  tab.samples.resize(n);
  tab.line.resize(n);
  tab.joints_rad.resize(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(col.joints.size()));
  tab.extra_columns = extra_names;
  PoseTrack track;
  const auto& w = cfg.wrench;
  const double sign = w.measured_on_body ? -1.0 : 1.0;
  std::vector<std::optional<Eigen::Quaterniond>> q_prev(nb);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& p = rows[out[i].row];
    const auto ii = static_cast<Eigen::Index>(i);
    auto& s = tab.samples[i];
    tab.line[i] = data.row_line[out[i].row];
    s.t_s = (p.time_raw - t0_raw) / raw_per_s;  // dividing by an exact power of ten keeps 0.006968 short
    s.p_world_ee_m = out[i].fits[ee]->p_world_body_m;
    s.q_world_ee = continuous_quaternion(out[i].fits[ee]->R_world_body, q_prev[ee]);
    q_prev[ee] = s.q_world_ee;
    s.f_fp_n = sign * w.n_per_unit * (w.R_fp_data * p.f_data);
    const Eigen::Vector3d m_point_nm = sign * w.nm_per_unit * (w.R_fp_data * p.m_data);
    s.m_fp_nm = m_point_nm + w.moment_point_fp_m.cross(s.f_fp_n);  // moved to the plate origin
    for (std::size_t j = 0; j < col.joints.size(); ++j) tab.joints_rad(ii, static_cast<Eigen::Index>(j)) = p.joints[j];
    track.t_s.push_back(s.t_s);
    track.p_world_body_m.push_back(s.p_world_ee_m);
    track.q_world_body.push_back(s.q_world_ee);

    auto row = run.extra_values.row(ii);
    Eigen::Index c = 0;
    for (std::size_t b = 0; b < nb; ++b) {
      const auto& f = out[i].fits[b];
      row(c++) = f ? f->residual_rms_m : kNaN;
      row(c++) = static_cast<double>(std::count(p.seen[b].begin(), p.seen[b].end(), true));
      if (b == ee) continue;
      if (f) {
        const auto qb = continuous_quaternion(f->R_world_body, q_prev[b]);
        q_prev[b] = qb;
        row.segment(c, 7) << f->p_world_body_m.x(), f->p_world_body_m.y(), f->p_world_body_m.z(), qb.w(), qb.x(), qb.y(), qb.z();
      }
      c += 7;
    }
    for (std::size_t x = 0; x < p.extras.size(); ++x) {
      row(static_cast<Eigen::Index>(n_generated + x)) = p.extras[x];
      if (std::isnan(p.extras[x])) ++rep.extra_missing;
    }
  }
  const auto tw = twist_from_poses(track, cfg.twist_window_s);
  for (std::size_t i = 0; i < n; ++i) {
    tab.samples[i].v_world_ee_m_per_s = tw.v_world_m_per_s[i];
    tab.samples[i].w_world_ee_rad_per_s = tw.w_world_rad_per_s[i];
  }

  // Report: steps and gaps, per-body fit and motion, wrench range.
  std::vector<double> dts;
  for (std::size_t i = 1; i < n; ++i) dts.push_back(tab.samples[i].t_s - tab.samples[i - 1].t_s);
  rep.rows_written = n;
  rep.duration_s = tab.samples.back().t_s;
  rep.median_dt_s = median(dts);
  rep.min_dt_s = *std::min_element(dts.begin(), dts.end());
  rep.max_dt_s = *std::max_element(dts.begin(), dts.end());
  for (std::size_t i = 1; i < n; ++i)
    if (dts[i - 1] > cfg.time.gap_factor * rep.median_dt_s) rep.gaps.push_back({tab.samples[i].t_s, dts[i - 1], tab.line[i]});
  rep.f_min_n = rep.f_max_n = tab.samples[0].f_fp_n;
  for (const auto& s : tab.samples) rep.f_min_n = rep.f_min_n.cwiseMin(s.f_fp_n), rep.f_max_n = rep.f_max_n.cwiseMax(s.f_fp_n);
  for (std::size_t b = 0; b < nb; ++b) {
    std::vector<const RigidFit*> fits;
    for (const auto& f : out) fits.push_back(f.fits[b] ? &*f.fits[b] : nullptr);
    rep.bodies[b] = body_statistics(rep.bodies[b], fits);
  }

  // run.yaml: start time from the first written row.
  std::int64_t start_us = 0;
  bool start_known = true;
  if (datetime) {
    start_us = static_cast<std::int64_t>(t0_raw);
    if (cfg.time.utc_offset_h) start_us -= static_cast<std::int64_t>(std::llround(*cfg.time.utc_offset_h * 3600e6));
    rep.clock_taken_as_utc = !cfg.time.utc_offset_h;
  } else if (!cfg.time.start_time_utc.empty()) {
    start_us = *parse_iso8601_utc_us(cfg.time.start_time_utc) + std::llround(t0_raw * cfg.time.s_per_unit * 1e6);
  } else {
    start_known = false;
  }
  rep.start_time_utc = format_iso8601_utc_us(start_us);
  auto& info = run.info;
  info.rig = !rig_name.empty() ? rig_name : (!cfg.rig.empty() ? cfg.rig : "imported");
  info.start_time_utc = rep.start_time_utc;
  info.output_rate_hz = 1.0 / rep.median_dt_s;
  info.sources.push_back({cfg.source_name, "import", 1.0 / rep.median_dt_s, ""});
  info.notes = run_notes(rep, cfg, ee, start_known, extra_names);
  run.report = std::move(rep);
  return run;
}

void write_imported_run(const std::string& dir, const ImportedRun& run) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  format::write_run_info((fs::path(dir) / "run.yaml").string(), run.info);
  // The run format's own writer: shortest round-trip numbers, extras after the joints (a NaN
  // extra is written as nan, which readers keep as text).
  format::SamplesWriter w((fs::path(dir) / "samples.csv").string(), static_cast<std::size_t>(run.table.joints_rad.cols()), run.extra_names);
  std::vector<double> joints(static_cast<std::size_t>(run.table.joints_rad.cols()));
  std::vector<double> extras(static_cast<std::size_t>(run.extra_values.cols()));
  for (std::size_t i = 0; i < run.table.size(); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    for (std::size_t j = 0; j < joints.size(); ++j) joints[j] = run.table.joints_rad(ii, static_cast<Eigen::Index>(j));
    for (std::size_t x = 0; x < extras.size(); ++x) extras[x] = run.extra_values(ii, static_cast<Eigen::Index>(x));
    w.append(run.table.samples[i], joints.data(), extras.data());
  }
  w.close();
}

std::string report_text(const ImportReport& r) {
  std::string s = fmt::format("rows: {} read, {} written\n", r.rows_read, r.rows_written);
  for (const auto& d : r.dropped) s += fmt::format("  dropped {}: {} (first on line {})\n", d.count, d.reason, d.first_line);
  s += fmt::format("time: start {}{}, duration {:.3f} s, step median {:.2f} ms (min {:.2f}, max {:.2f})\n", r.start_time_utc,
                   r.clock_taken_as_utc ? " (local clock taken as UTC)" : "", r.duration_s, r.median_dt_s * 1e3, r.min_dt_s * 1e3,
                   r.max_dt_s * 1e3);
  s += fmt::format("gaps: {} (kept)", r.gaps.size());
  for (std::size_t i = 0; i < r.gaps.size() && i < 5; ++i)
    s += fmt::format("{} {:.1f} ms before t={:.3f} s (line {})", i ? "," : ":", r.gaps[i].dt_s * 1e3, r.gaps[i].t_s, r.gaps[i].line);
  if (r.gaps.size() > 5) s += ", ...";
  s += '\n';
  for (const auto& b : r.bodies) {
    s += fmt::format("body {}{}: {} markers, {} rows fitted ({} with markers missing), {} without pose\n", b.name, b.is_ee ? " (ee)" : "",
                     b.markers, b.fitted, b.reduced, b.no_pose);
    s += fmt::format("  fit residual RMS: mean {:.3f} mm, median {:.3f} mm, max {:.3f} mm\n", b.rms_mean_m * 1e3, b.rms_median_m * 1e3,
                     b.rms_max_m * 1e3);
    s += fmt::format("  motion: position range x {:.2f} y {:.2f} z {:.2f} mm (max {:.2f} mm from the first row); "
                     "rotation range x {:.2f} y {:.2f} z {:.2f} mrad (max {:.2f} mrad)\n",
                     b.p_range_m.x() * 1e3, b.p_range_m.y() * 1e3, b.p_range_m.z() * 1e3, b.max_displacement_m * 1e3,
                     b.rot_range_rad.x() * 1e3, b.rot_range_rad.y() * 1e3, b.rot_range_rad.z() * 1e3, b.max_rotation_rad * 1e3);
  }
  s += fmt::format("force on plate: fx {:.1f}..{:.1f}, fy {:.1f}..{:.1f}, fz {:.1f}..{:.1f} N\n", r.f_min_n.x(), r.f_max_n.x(),
                   r.f_min_n.y(), r.f_max_n.y(), r.f_min_n.z(), r.f_max_n.z());
  if (r.extra_missing) s += fmt::format("extra cells empty or NaN (written as nan): {}\n", r.extra_missing);
  return s;
}

}  // namespace hil::import
