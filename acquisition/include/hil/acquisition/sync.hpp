#pragma once
/// \file Synchronisation of the pose stream to the wrench stream, with decimation.
///
/// The wrench stream (force plate, ~1 kHz) sets the clock. Readings come with jitter (polls on a
/// busy machine) and sometimes not at all (lost frames), so they are first resampled onto a uniform
/// grid at the nominal rate by linear interpolation between neighbouring readings. The grid is
/// low-pass filtered by a windowed-sinc FIR (cut-off 0.4 x the output rate, Hann window) and
/// decimated to the output rate; each output takes the time of the FIR's centre tap, so the filter
/// adds no phase lag and output times are exactly uniform. A step longer than `gap_periods` nominal
/// periods is bridged but flags the next output kGapBefore; one longer than `reset_gap_s` restarts
/// the filter (nothing is invented across it). The pose (robot, ~125 Hz) is interpolated at each
/// output time: position and joints linearly, orientation by slerp; the twist comes from filtered
/// differences, a least-squares slope over the poses within +-`twist_half_window_s`. An output
/// waits for a pose past that window; after `pose_timeout_s` without one it goes out with the last
/// pose held and flagged (kPoseExtrapolated, kPoseStale past `pose_stale_s`).
/// Pure: no clocks, no threads, no I/O.
#include <deque>
#include <functional>
#include <vector>

#include <hil/acquisition/streams.hpp>

namespace hil::acquisition {

struct SyncConfig {
  double wrench_rate_hz = 1000.0;     ///< nominal input rate of the force plate
  double output_rate_hz = 50.0;       ///< must divide the wrench rate (decimation factor = ratio)
  int fir_half_length = 0;            ///< taps on each side of the centre; 0 = 2 x decimation factor
  double pose_timeout_s = 0.1;        ///< wait at most this long for a pose after a sample's time
  double pose_stale_s = 0.05;         ///< a pose older than this at the sample time is stale
  double twist_half_window_s = 0.02;  ///< poses within +- this fit the twist
  /// A step longer than this many nominal periods is a gap (frames lost). Polling jitter on a
  /// loaded machine makes 1.5-period steps common; 2.5 means at least one reading is missing.
  double gap_periods = 2.5;
  /// A step longer than this restarts the filter (0: the FIR half-length, at least 50 ms).
  double reset_gap_s = 0.0;
};

class Synchronizer {
 public:
  using Sink = std::function<void(const SyncedSample&)>;
  /// \throws std::invalid_argument if the rates do not give an integer decimation factor.
  Synchronizer(const SyncConfig& config, Sink sink);

  /// Feed readings in arrival order (each stream's times non-decreasing).
  void push_wrench(const WrenchReading& r);
  void push_pose(const PoseReading& r);
  /// The robot controller refused a poll (a Modbus exception): the pose was not read. Samples
  /// extrapolated while it refuses, and those interpolated across the refusal once a pose comes
  /// again, carry kDeviceFault.
  void pose_refused();
  /// Emits every pending output with what is there (end of run).
  void flush();

  int decimation() const { return m_; }
  const std::vector<double>& taps() const { return taps_; }
  std::uint64_t emitted() const { return next_index_; }
  std::uint64_t wrench_gaps() const { return gaps_; }

 private:
  struct Pending {
    SyncedSample s;
  };
  void emit_ready(std::int64_t now_ns, bool force);
  bool fill_pose(SyncedSample& s, bool force) const;

  SyncConfig cfg_;
  Sink sink_;
  int m_ = 1;
  int half_ = 0;
  std::vector<double> taps_;
  std::int64_t period_ns_ = 0;
  std::int64_t gap_ns_ = 0;
  void push_grid(std::int64_t t_ns, const Vector6d& w, std::uint32_t quality, std::uint64_t seq);
  std::deque<WrenchReading> window_;  ///< last 2*half+1 grid values
  WrenchReading prev_;                ///< the previous reading (for interpolation)
  bool have_prev_ = false;
  std::int64_t grid_ns_ = 0;  ///< next grid time
  std::int64_t reset_ns_ = 0;
  int since_output_ = 0;
  bool gap_pending_ = false;
  std::uint64_t gaps_ = 0;
  std::deque<PoseReading> poses_;
  bool refused_ = false;  ///< a poll was refused since the last pose
  std::deque<SyncedSample> pending_;
  std::uint64_t next_index_ = 0;
  std::int64_t last_wrench_ns_ = 0;
};

}  // namespace hil::acquisition
