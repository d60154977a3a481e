#pragma once
// The online stiffness worker: reads StiffnessMeasurement samples from the bus, feeds the online
// identifier (a Givens QR update per measurement) and publishes a StiffnessEstimate after each one.
// DDS callbacks only queue; all numerics run on the caller's thread (spin()).
#include <chrono>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>

#include <hil/calibration/online.hpp>
#include <hil/dds/bus.hpp>

namespace hil::services::stiffness {

hil_msgs::msg::StiffnessMeasurement to_message(const calibration::Measurement& m);
/// \throws std::invalid_argument if the joint count differs from `dof`.
calibration::Measurement from_message(const hil_msgs::msg::StiffnessMeasurement& msg, int dof);
hil_msgs::msg::StiffnessEstimate to_message(const calibration::OnlineEstimate& e);

class StiffnessWorker {
 public:
  /// `identifier` is taken; the participant is borrowed and must outlive the worker.
  StiffnessWorker(dds::Participant& participant, std::unique_ptr<calibration::OnlineIdentifier> identifier);
  /// Processes queued measurements, waiting up to `timeout` for the first. Returns how many.
  std::size_t spin(std::chrono::milliseconds timeout);
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
  calibration::OnlineEstimate last_;
};

}  // namespace hil::services::stiffness
