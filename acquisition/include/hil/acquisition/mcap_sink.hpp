#pragma once
// `hil acquire --mcap`: run.mcap beside the CSV run, from the same samples and the live device
// status. The CSV stays the primary record; the MCAP is a view of it for ROS 2 tools.
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <hil/acquisition/monitor.hpp>
#include <hil/acquisition/streams.hpp>
#include <hil/format/rig.hpp>
#include <hil/mcap/recording.hpp>

namespace hil::acquisition {

class McapSink {
 public:
  /// \param tf  the moving edge on /tf with every sample (mcap::RecordingOptions::tf).
  McapSink(const std::string& path, const format::RigSpec& rig, std::size_t joint_count, std::int64_t start_ns,
           mcap::Compression compression, bool tf = true);
  /// A synchronized sample, as the recorder gets it (pipeline thread).
  void sample(const acquisition::SyncedSample& s);
  /// The devices' health now: a DeviceStatus for each device whose state changed, and for every
  /// device once per `period_s` (main thread).
  void health(const std::vector<acquisition::DeviceHealth>& devices, std::int64_t now_ns, bool force = false);
  /// Closes the open chunk: what a crash loses is at most what came since (called once a second).
  void flush();
  void close();
  std::uint64_t messages();

 private:
  std::mutex mutex_;  // samples come from a device thread, status and flushes from the main thread
  mcap::RunMcapWriter writer_;
  std::int64_t start_ns_;
  std::size_t joints_;
  std::vector<double> joints_buf_;
  std::uint64_t rows_ = 0;
  std::map<std::string, acquisition::DeviceState> last_state_;
  std::int64_t last_periodic_ns_ = 0;
  double period_s_ = 1.0;
};

}  // namespace hil::acquisition
