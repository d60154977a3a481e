#include <hil/acquisition/recorder.hpp>

#include <hil/messages/sample_msg.hpp>

#include <fmt/format.h>

#include <ctime>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace hil::acquisition {
namespace fs = std::filesystem;

std::int64_t realtime_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

std::string iso8601_utc(std::int64_t t_ns) {
  const std::time_t sec = static_cast<std::time_t>(t_ns / 1'000'000'000);
  std::tm tm{};
  gmtime_r(&sec, &tm);
  // Nanoseconds: run.yaml's start plus a sample's t is the instant the live stamps carry, to the ns.
  return fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}.{:09}Z", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min,
                     tm.tm_sec, t_ns % 1'000'000'000);
}

RunRecorder::RunRecorder(const std::string& dir, format::RunInfo info, const std::string& rig_yaml_text, std::int64_t start_ns,
                         std::size_t joint_count, double flush_period_s)
    : dir_(dir), info_(std::move(info)), start_ns_(start_ns), joints_(joint_count),
      flush_period_ns_(static_cast<std::int64_t>(flush_period_s * 1e9)), joints_buf_(joint_count) {
  if (fs::exists(dir_) && !fs::is_empty(dir_)) throw std::runtime_error(dir_ + ": exists and is not empty; refusing to overwrite a run");
  fs::create_directories(fs::path(dir_) / "raw");
  info_.start_time_utc = iso8601_utc(start_ns_);
  format::write_run_info((fs::path(dir_) / "run.yaml").string(), info_);
  if (!rig_yaml_text.empty()) {
    std::ofstream out(fs::path(dir_) / "rig.yaml", std::ios::binary);
    out << rig_yaml_text;
    if (!out) throw std::runtime_error(dir_ + "/rig.yaml: cannot write");
  }
  writer_ = std::make_unique<format::SamplesWriter>((fs::path(dir_) / "samples.csv").string(), joints_,
                                                    std::vector<std::string>{"quality", "wrench_age_s", "pose_age_s"});
}

RunRecorder::~RunRecorder() {
  try {
    close();
  } catch (...) {
    // close() explicitly to see errors
  }
}

void RunRecorder::append(const SyncedSample& s) {
  const auto row = to_row(s, static_cast<double>(s.t_ns - start_ns_) * 1e-9);
  // A sample without joints (no pose yet) writes zeros in the joint columns.
  for (std::size_t j = 0; j < joints_; ++j)
    joints_buf_[j] = j < static_cast<std::size_t>(s.joints_rad.size()) ? s.joints_rad[static_cast<Eigen::Index>(j)] : 0.0;
  const double extras[3] = {static_cast<double>(s.quality), s.wrench_age_s, std::isfinite(s.pose_age_s) ? s.pose_age_s : -1.0};
  writer_->append(row, joints_buf_.data(), extras);
  ++rows_;
  if (s.quality & kGapBefore) ++gaps_;
  if (s.t_ns - last_flush_ns_ >= flush_period_ns_) {
    writer_->flush();
    last_flush_ns_ = s.t_ns;
  }
}

void RunRecorder::flush() { writer_->flush(); }

void RunRecorder::set_source_identity(const std::string& source, std::vector<std::pair<std::string, std::string>> identity) {
  for (auto& s : info_.sources) {
    if (s.name != source) continue;
    s.identity = std::move(identity);
    format::write_run_info((fs::path(dir_) / "run.yaml").string(), info_);
    return;
  }
  throw std::invalid_argument("run has no source named '" + source + "'");
}

void RunRecorder::close(const std::string& summary_notes) {
  if (closed_) return;
  closed_ = true;
  writer_->close();
  if (!summary_notes.empty()) {
    info_.notes += (info_.notes.empty() ? "" : "\n") + summary_notes;
    format::write_run_info((fs::path(dir_) / "run.yaml").string(), info_);
  }
}

std::string RunRecorder::raw_path(const std::string& file) const { return (fs::path(dir_) / "raw" / file).string(); }

}  // namespace hil::acquisition
