#include <hil/services/contact_worker.hpp>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>

#include <hil/messages/sample_msg.hpp>
#include <hil/dds/bus.hpp>
#include <hil/dds/topics.hpp>
#include <hil/format/rig.hpp>
#include <hil/models/contact.hpp>

namespace hil::services {

namespace cid = hil::contact_id;

namespace {
double finite_or(double v, double fallback) { return std::isfinite(v) ? v : fallback; }
}  // namespace

ContactWorker::ContactWorker(dds::Participant& participant, const format::RigSpec& rig) {
  const auto scene = models::scene_from_rig(rig);
  const auto model = models::model_from_rig(rig);
  const double F = rig.model.contact->force_scale_n > 0 ? rig.model.contact->force_scale_n : 50.0;
  const double M = rig.model.contact->moment_scale_nm > 0 ? rig.model.contact->moment_scale_nm : 5.0;
  est_ = std::make_unique<cid::OnlineEstimator>(scene, model.v_tm, F, M);
  writer_ = std::make_unique<dds::Writer<hil_msgs::msg::ContactEstimate>>(participant, dds::topics::kContactEstimate);
  reader_ = std::make_unique<dds::Reader<hil_msgs::msg::PoseWrenchSample>>(participant, dds::topics::kPoseWrenchSample,
                                                                           [this](const hil_msgs::msg::PoseWrenchSample& m, const auto&) {
                                                                             const auto meas =
                                                                                 models::measurement(messages::from_message(m));
                                                                             std::lock_guard<std::mutex> lock(mu_);
                                                                             writer_->write(to_message(est_->update(meas)));
                                                                             ++processed_;
                                                                           });
  spdlog::info("contact worker: {} -> {} (rig {})", dds::topics::kPoseWrenchSample, dds::topics::kContactEstimate, rig.name);
}

contact_id::LinearEstimate ContactWorker::global() const {
  std::lock_guard<std::mutex> lock(mu_);
  return est_->global();
}

void ContactWorker::flush() { writer_->wait_for_acknowledgments(std::chrono::seconds(2)); }

hil_msgs::msg::ContactEstimate to_message(const cid::OnlineEstimate& e) {
  hil_msgs::msg::ContactEstimate m;
  m.stamp(messages::to_time(e.t_s));
  m.t_s(e.t_s);
  m.contact_points(static_cast<uint32_t>(e.contacts));
  m.instantaneous_valid(e.instantaneous_valid);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  m.k_instant_n_per_m(e.instantaneous_valid ? e.K_instant : nan);
  m.mu_instant(e.instantaneous_valid ? e.mu_instant : nan);
  m.k_global_n_per_m(e.global.rank > 0 ? e.global.K : nan);
  m.k_global_std(e.global.rank > 0 ? e.global.K_std : nan);
  m.mu_global(e.global.mu_identifiable ? e.global.mu : nan);
  m.mu_global_std(e.global.mu_identifiable ? e.global.mu_std : nan);
  m.samples_used(static_cast<uint64_t>(e.global.rows / 6));
  m.relative_force_error(finite_or(e.global.relative_force_error, nan));
  return m;
}

}  // namespace hil::services
