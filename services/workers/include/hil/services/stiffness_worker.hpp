#pragma once
// The online stiffness worker: reads StiffnessMeasurement samples from the bus, feeds the online
// identifier (a Givens QR update per measurement) and publishes a StiffnessEstimate after each one.
// DDS callbacks only queue; all numerics run on the caller's thread (spin()).
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>

#include <hil/calibration/online.hpp>
#include <hil/dds/bus.hpp>
#include <hil/models/stiffness.hpp>

namespace hil::services::stiffness {

hil_msgs::msg::StiffnessMeasurement to_message(const calibration::Measurement& m);
/// \throws std::invalid_argument if the joint count differs from `dof`.
calibration::Measurement from_message(const hil_msgs::msg::StiffnessMeasurement& msg, int dof);
hil_msgs::msg::StiffnessEstimate to_message(const calibration::OnlineEstimate& e);

class StiffnessWorker {
 public:
  /// `identifier` is taken; the participant is borrowed and must outlive the worker.
  /// `estimate_period` 0: an estimate after every measurement. Positive: every measurement is added
  /// as it comes, but an estimate (a re-reduction, ~1 ms) is computed and published at most once a
  /// period, and one period after the last measurement at the latest: how the worker keeps up
  /// with a 1 kHz bus (docs/calibration.md, "Online worker").
  StiffnessWorker(dds::Participant& participant, std::unique_ptr<calibration::OnlineIdentifier> identifier,
                  std::chrono::microseconds estimate_period = std::chrono::microseconds(0));
  /// Processes queued measurements, waiting up to `timeout` for the first (or for a pending
  /// estimate's period to end). Returns how many measurements it processed.
  std::size_t spin(std::chrono::milliseconds timeout);
  /// Publishes the estimate of measurements added since the last one, if any (at the end of a run).
  void publish_pending() {
    if (pending_) publish_estimate();
  }
  std::size_t estimates() const { return estimates_; }
  /// The most measurements that waited in the queue at once.
  std::size_t max_backlog() const { return max_backlog_; }
  std::size_t processed() const { return processed_; }
  std::size_t rejected() const { return rejected_; }
  const calibration::OnlineEstimate& last() const { return last_; }
  int subscribers() const { return writer_.matched(); }

 private:
  std::unique_ptr<calibration::OnlineIdentifier> id_;
  dds::Writer<hil_msgs::msg::StiffnessEstimate> writer_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<hil_msgs::msg::StiffnessMeasurement> queue_;
  dds::Reader<hil_msgs::msg::StiffnessMeasurement> reader_;
  std::size_t processed_ = 0;
  std::size_t rejected_ = 0;
  std::size_t estimates_ = 0;
  std::size_t max_backlog_ = 0;
  std::chrono::microseconds period_;
  bool pending_ = false;  ///< measurements added since the last estimate
  std::chrono::steady_clock::time_point last_estimate_{};
  void publish_estimate();
  calibration::OnlineEstimate last_;
};

/// `hil stiffness replay`: publishes `table`'s rows (read from `path`, named in errors) on the
/// measurement topic, `rate_hz` a second (0: as fast as possible), after waiting up to `wait_s`
/// for a reader. Returns how many were published.
std::size_t replay_measurements(dds::Participant& participant, const models::StiffnessTable& table, const std::string& path, double rate_hz,
                                double wait_s);

/// What a worker run did.
struct WorkerRun {
  std::size_t processed = 0, rejected = 0;
  int last_rank = 0;
};
/// `hil stiffness worker`: runs `identifier` on the bus until `count` measurements are processed
/// (0: no limit), `timeout_s` passes (0: never) or `stop` is set, logging each estimate;
/// `estimate_period` as for StiffnessWorker.
WorkerRun run_stiffness_worker(dds::Participant& participant, std::unique_ptr<calibration::OnlineIdentifier> identifier, std::size_t count,
                               double timeout_s, const std::atomic<bool>& stop,
                               std::chrono::microseconds estimate_period = std::chrono::microseconds(0));

}  // namespace hil::services::stiffness
