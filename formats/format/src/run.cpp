#include <hil/format/run.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <hil/error/error.hpp>
#include <hil/format/yaml.hpp>

namespace hil::format {
using YNode = YamlNode;

bool is_iso8601_utc(const std::string& s) {
  static const std::regex re(R"(^\d{4}-(0[1-9]|1[0-2])-(0[1-9]|[12]\d|3[01])T([01]\d|2[0-3]):[0-5]\d:[0-5]\d(\.\d{1,9})?Z$)");
  return std::regex_match(s, re);
}

RunInfo parse_run_info(const std::string& text, const std::string& display_name) {
  const YAML::Node doc = load_yaml(text, display_name);
  if (!doc.IsDefined() || doc.IsNull()) throw error::FormatError({display_name, 0, 0, ""}, "empty run.yaml");
  const YNode root(doc, "", &display_name);
  root.only({"format_version", "rig", "start_time", "output_rate_hz", "sources", "notes"});
  RunInfo r;
  r.format_version = static_cast<int>(root.req("format_version").integer());
  if (r.format_version != 1)
    root.child("format_version").fail("this hil reads run format version 1, found " + std::to_string(r.format_version));
  r.rig = root.req("rig").str();
  r.start_time_utc = root.req("start_time").str();
  if (!is_iso8601_utc(r.start_time_utc))
    root.child("start_time").fail("expected UTC ISO 8601 like 2026-11-21T10:00:00.000Z, found '" + r.start_time_utc + "'");
  r.output_rate_hz = root.req("output_rate_hz").num_positive();
  if (root.has("sources")) {
    for (const auto& s : root.child("sources").seq()) {
      s.only({"name", "kind", "rate_hz", "raw", "identity"});
      SourceSpec src;
      src.name = s.req("name").str();
      src.kind = s.req("kind").str();
      static const std::vector<std::string> kinds{"can", "modbus", "udp", "serial", "simulation", "import", "other"};
      if (std::find(kinds.begin(), kinds.end(), src.kind) == kinds.end())
        s.child("kind").fail("expected can, modbus, udp, serial, simulation, import or other, found '" + src.kind + "'");
      if (s.has("rate_hz")) src.rate_hz = s.child("rate_hz").num_positive();
      src.raw = s.str("raw", "");
      if (s.has("identity")) {
        const YNode id = s.child("identity");
        id.expect_map();
        for (const auto& kv : id.raw()) {
          if (!kv.first.IsScalar()) id.fail("identity keys are names (letters, digits, _), found a null, list or mapping");
          const auto key = kv.first.as<std::string>();
          if (key.empty() || key.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_") != std::string::npos)
            id.fail("identity keys are names (letters, digits, _), found '" + key + "'");
          if (!kv.second.IsScalar()) id.child(key).fail("expected a single value (text or number)");
          src.identity.emplace_back(key, kv.second.as<std::string>());
        }
      }
      r.sources.push_back(src);
    }
  }
  r.notes = root.str("notes", "");
  return r;
}

RunInfo load_run_info(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw error::FormatError({path, 0, 0, ""}, "cannot open run.yaml");
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_run_info(ss.str(), path);
}

void write_run_info(const std::string& path, const RunInfo& info) {
  YAML::Emitter e;
  e << YAML::BeginMap;
  e << YAML::Key << "format_version" << YAML::Value << info.format_version;
  e << YAML::Key << "rig" << YAML::Value << info.rig;
  e << YAML::Key << "start_time" << YAML::Value << info.start_time_utc;
  e << YAML::Key << "output_rate_hz" << YAML::Value << info.output_rate_hz;
  e << YAML::Key << "sources" << YAML::Value << YAML::BeginSeq;
  for (const auto& s : info.sources) {
    e << YAML::BeginMap << YAML::Key << "name" << YAML::Value << s.name << YAML::Key << "kind" << YAML::Value << s.kind;
    if (s.rate_hz > 0) e << YAML::Key << "rate_hz" << YAML::Value << s.rate_hz;
    if (!s.raw.empty()) e << YAML::Key << "raw" << YAML::Value << s.raw;
    if (!s.identity.empty()) {
      e << YAML::Key << "identity" << YAML::Value << YAML::BeginMap;
      // Quoted: a serial like 0123 or a firmware like 1.10 must read back as the same text.
      for (const auto& [k, v] : s.identity) e << YAML::Key << k << YAML::Value << YAML::DoubleQuoted << v;
      e << YAML::EndMap;
    }
    e << YAML::EndMap;
  }
  e << YAML::EndSeq;
  if (!info.notes.empty()) e << YAML::Key << "notes" << YAML::Value << YAML::Literal << info.notes;
  e << YAML::EndMap;
  // Written beside and renamed over: a recorder rewrites run.yaml while recording (device
  // identity, the closing summary), and a crash must leave the old or the new file, never half.
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out << e.c_str() << '\n';
    out.flush();
    if (!out) throw std::runtime_error(tmp + ": cannot write run.yaml");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error(path + ": cannot replace run.yaml: " + ec.message());
}

Run load_run(const std::string& dir, const std::string& rig_path) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(dir))
    throw error::FormatError({dir, 0, 0, ""}, "not a run folder (expected a directory with run.yaml and samples.csv)");
  Run run;
  run.dir = dir;
  const auto info_path = (fs::path(dir) / "run.yaml").string();
  const auto samples_path = (fs::path(dir) / "samples.csv").string();
  if (!fs::exists(info_path)) throw error::FormatError({info_path, 0, 0, ""}, "missing: a run folder needs run.yaml");
  if (!fs::exists(samples_path)) throw error::FormatError({samples_path, 0, 0, ""}, "missing: a run folder needs samples.csv");
  run.info = load_run_info(info_path);
  run.samples = read_samples(samples_path);
  const auto own_rig = (fs::path(dir) / "rig.yaml").string();
  if (!rig_path.empty()) run.rig = load_rig(rig_path);
  else if (fs::exists(own_rig)) run.rig = load_rig(own_rig);
  if (run.rig && run.rig->name != run.info.rig)
    throw error::FormatError({info_path, 0, 0, "rig"}, "run was recorded on rig '" + run.info.rig + "' but the rig file '" +
                                                           run.rig->source + "' describes '" + run.rig->name + "'");
  return run;
}

SampleSummary summarize(const SampleTable& t) {
  SampleSummary s;
  s.count = t.size();
  if (t.size() == 0) return s;
  s.duration_s = t.samples.back().t_s - t.samples.front().t_s;
  if (t.size() > 1) {
    std::vector<double> dt(t.size() - 1);
    for (std::size_t i = 1; i < t.size(); ++i) dt[i - 1] = t.samples[i].t_s - t.samples[i - 1].t_s;
    std::vector<double> sorted = dt;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
    s.median_dt_s = sorted[sorted.size() / 2];
    s.rate_hz = s.median_dt_s > 0 ? 1.0 / s.median_dt_s : 0.0;
    for (std::size_t i = 0; i < dt.size(); ++i)
      if (dt[i] > 1.5 * s.median_dt_s) s.gaps.push_back({t.samples[i + 1].t_s, dt[i], t.line.empty() ? 0 : t.line[i + 1]});
  }
  auto range = [&](const std::string& name, auto get) {
    double lo = get(t.samples[0]), hi = lo;
    for (const auto& x : t.samples) lo = std::min(lo, get(x)), hi = std::max(hi, get(x));
    s.ranges.push_back({name, lo, hi});
  };
  const char* axes[] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) range(std::string("p") + axes[k], [k](const Sample& x) { return x.p_world_ee_m[k]; });
  for (int k = 0; k < 3; ++k) range(std::string("v") + axes[k], [k](const Sample& x) { return x.v_world_ee_m_per_s[k]; });
  for (int k = 0; k < 3; ++k) range(std::string("w") + axes[k], [k](const Sample& x) { return x.w_world_ee_rad_per_s[k]; });
  for (int k = 0; k < 3; ++k) range(std::string("f") + axes[k], [k](const Sample& x) { return x.f_fp_n[k]; });
  for (int k = 0; k < 3; ++k) range(std::string("m") + axes[k], [k](const Sample& x) { return x.m_fp_nm[k]; });
  for (Eigen::Index j = 0; j < t.joints_rad.cols(); ++j) {
    const auto c = t.joints_rad.col(j);
    s.ranges.push_back({"j" + std::to_string(j + 1), c.minCoeff(), c.maxCoeff()});
  }
  return s;
}

}  // namespace hil::format
