#pragma once
/// \file Records synchronized samples as a run folder (docs/formats.md), append-only.
/// run.yaml and rig.yaml are written first, so a run killed at any moment is readable; rows are
/// flushed to the kernel every `flush_period_s` of sample time, so `kill -9` loses at most that.
/// Each row carries the extra columns `quality` (bit flags, see streams.hpp), `wrench_age_s` and
/// `pose_age_s`: gaps and faults stay visible in the recording.
#include <memory>
#include <string>
#include <vector>

#include <hil/acquisition/streams.hpp>
#include <hil/format/run.hpp>
#include <hil/format/samples.hpp>

namespace hil::acquisition {

class RunRecorder {
 public:
  /// Creates `dir` (and `dir/raw`); refuses an existing non-empty folder. `rig_yaml_text` is
  /// copied as rig.yaml when not empty. `start_ns` is the run's t = 0.
  RunRecorder(const std::string& dir, format::RunInfo info, const std::string& rig_yaml_text, std::int64_t start_ns,
              std::size_t joint_count, double flush_period_s = 1.0);
  ~RunRecorder();
  RunRecorder(const RunRecorder&) = delete;
  RunRecorder& operator=(const RunRecorder&) = delete;

  void append(const SyncedSample& s);
  void flush();
  /// Records what a device said about itself under its source in run.yaml (rewritten at once).
  /// \throws std::invalid_argument when the run has no source of that name.
  void set_source_identity(const std::string& source, std::vector<std::pair<std::string, std::string>> identity);
  const format::RunInfo& info() const { return info_; }
  /// Flushes, closes and rewrites run.yaml with a summary in its notes. Idempotent.
  void close(const std::string& summary_notes = "");

  std::string raw_path(const std::string& file) const;
  const std::string& dir() const { return dir_; }
  std::uint64_t rows() const { return rows_; }
  std::int64_t start_ns() const { return start_ns_; }
  std::uint64_t gaps() const { return gaps_; }

 private:
  std::string dir_;
  format::RunInfo info_;
  std::int64_t start_ns_;
  std::size_t joints_;
  std::int64_t flush_period_ns_;
  std::int64_t last_flush_ns_ = 0;
  std::vector<double> joints_buf_;
  std::unique_ptr<format::SamplesWriter> writer_;
  std::uint64_t rows_ = 0, gaps_ = 0;
  bool closed_ = false;
};

/// ISO 8601 UTC text for a CLOCK_REALTIME time, to the nanosecond (2026-11-28T10:00:00.123456789Z).
std::string iso8601_utc(std::int64_t t_ns);
/// CLOCK_REALTIME now.
std::int64_t realtime_ns();

}  // namespace hil::acquisition
