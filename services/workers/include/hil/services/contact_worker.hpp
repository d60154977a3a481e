#pragma once
/// \file The online contact worker of `hil contact worker` and `hil demo`: subscribes to PoseWrenchSample, publishes ContactEstimate.
#include <atomic>
#include <memory>
#include <mutex>

#include <hil/contact_id/online.hpp>
#include <hil/dds/bus.hpp>
#include <hil/format/rig.hpp>
#include "hil_msgsPubSubTypes.h"

namespace hil::services {

/// The online contact worker: from construction on, every PoseWrenchSample on the participant's
/// domain updates the estimator and a ContactEstimate is published.
class ContactWorker {
 public:
  ContactWorker(dds::Participant& participant, const format::RigSpec& rig);
  long processed() const { return processed_.load(); }
  contact_id::LinearEstimate global() const;
  /// Waits until the estimates written so far are acknowledged (or the timeout passes).
  void flush();

 private:
  std::unique_ptr<contact_id::OnlineEstimator> est_;
  mutable std::mutex mu_;
  std::atomic<long> processed_{0};
  std::unique_ptr<dds::Writer<hil_msgs::msg::ContactEstimate>> writer_;
  std::unique_ptr<dds::Reader<hil_msgs::msg::PoseWrenchSample>> reader_;
};

/// The ContactEstimate message for one online estimate.
hil_msgs::msg::ContactEstimate to_message(const contact_id::OnlineEstimate& e);

}  // namespace hil::services
