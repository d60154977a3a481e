#pragma once
/// \file A run folder: run.yaml + samples.csv (+ rig.yaml, raw/). See docs/formats.md.
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <hil/format/rig.hpp>
#include <hil/format/samples.hpp>

namespace hil::format {

struct SourceSpec {
  std::string name;      ///< e.g. force_plate, robot
  std::string kind;      ///< can | modbus | udp | simulation | import | other
  double rate_hz = 0.0;  ///< nominal device rate; 0 = unknown
  std::string raw;       ///< file under raw/ holding this source's stream, if recorded
  /// What the device said about itself when the run started (serial, firmware, counts, server
  /// id, ...), in the order it was recorded. Keys are names; values are text.
  std::vector<std::pair<std::string, std::string>> identity = {};
};

struct RunInfo {
  int format_version = 1;
  std::string rig;             ///< rig name
  std::string start_time_utc;  ///< ISO 8601, e.g. 2026-11-21T10:00:00.000Z
  double output_rate_hz = 0.0;
  std::vector<SourceSpec> sources;
  std::string notes;
};

struct Run {
  std::string dir;
  RunInfo info;
  SampleTable samples;
  std::optional<RigSpec> rig;  ///< rig.yaml inside the run, if present
};

bool is_iso8601_utc(const std::string& s);

RunInfo load_run_info(const std::string& path);
RunInfo parse_run_info(const std::string& yaml_text, const std::string& display_name);
void write_run_info(const std::string& path, const RunInfo& info);

/// Loads a run folder. The rig comes from `rig_path` when given, else from the run's rig.yaml.
/// Checks that the rig named in run.yaml is the rig given. \throws error::FormatError.
Run load_run(const std::string& dir, const std::string& rig_path = "");

/// What `hil validate` reports about a table.
struct SampleSummary {
  std::size_t count = 0;
  double duration_s = 0.0;
  double median_dt_s = 0.0;
  double rate_hz = 0.0;
  struct Gap {
    double t_s;   ///< time of the sample after the gap
    double dt_s;  ///< length of the gap
    std::size_t line;
  };
  std::vector<Gap> gaps;  ///< steps longer than 1.5 median steps
  struct Range {
    std::string column;
    double min, max;
  };
  std::vector<Range> ranges;
};
SampleSummary summarize(const SampleTable& t);

}  // namespace hil::format
