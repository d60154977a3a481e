#include <hil/services/stiffness_worker.hpp>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>

#include <hil/dds/topics.hpp>
#include <hil/error/error.hpp>

namespace hil::services::stiffness {
namespace hc = hil::calibration;

namespace {
builtin_interfaces::msg::Time now_stamp() {
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  builtin_interfaces::msg::Time t;
  t.sec(static_cast<std::int32_t>(ns / 1000000000));
  t.nanosec(static_cast<std::uint32_t>(ns % 1000000000));
  return t;
}
}  // namespace

hil_msgs::msg::StiffnessMeasurement to_message(const hc::Measurement& m) {
  if (m.kind == hc::MeasurementKind::markers)
    throw std::invalid_argument("marker measurements have no StiffnessMeasurement form on the bus (tool displacement only)");
  hil_msgs::msg::StiffnessMeasurement msg;
  msg.stamp(now_stamp());
  msg.config(static_cast<std::uint32_t>(m.config));
  msg.joints_rad(std::vector<double>(m.q_rad.data(), m.q_rad.data() + m.q_rad.size()));
  msg.load_world().force().x(m.w_world[0]);
  msg.load_world().force().y(m.w_world[1]);
  msg.load_world().force().z(m.w_world[2]);
  msg.load_world().torque().x(m.w_world[3]);
  msg.load_world().torque().y(m.w_world[4]);
  msg.load_world().torque().z(m.w_world[5]);
  msg.displacement_world_m().x(m.displacement[0]);
  msg.displacement_world_m().y(m.displacement[1]);
  msg.displacement_world_m().z(m.displacement[2]);
  msg.has_rotation(m.kind == hc::MeasurementKind::pose6);
  if (msg.has_rotation()) {
    msg.rotation_world_rad().x(m.displacement[3]);
    msg.rotation_world_rad().y(m.displacement[4]);
    msg.rotation_world_rad().z(m.displacement[5]);
  }
  return msg;
}

hc::Measurement from_message(const hil_msgs::msg::StiffnessMeasurement& msg, int dof) {
  if (static_cast<int>(msg.joints_rad().size()) != dof)
    throw std::invalid_argument("measurement with " + std::to_string(msg.joints_rad().size()) + " joints, the robot has " +
                                std::to_string(dof));
  hc::Measurement m;
  m.config = static_cast<int>(msg.config());
  m.q_rad = Eigen::Map<const Eigen::VectorXd>(msg.joints_rad().data(), dof);
  const auto& w = msg.load_world();
  m.w_world << w.force().x(), w.force().y(), w.force().z(), w.torque().x(), w.torque().y(), w.torque().z();
  m.kind = msg.has_rotation() ? hc::MeasurementKind::pose6 : hc::MeasurementKind::point3;
  m.displacement.resize(msg.has_rotation() ? 6 : 3);
  m.displacement.head<3>() << msg.displacement_world_m().x(), msg.displacement_world_m().y(), msg.displacement_world_m().z();
  if (msg.has_rotation())
    m.displacement.tail<3>() << msg.rotation_world_rad().x(), msg.rotation_world_rad().y(), msg.rotation_world_rad().z();
  for (Eigen::Index i = 0; i < m.displacement.size(); ++i)
    if (!std::isfinite(m.displacement[i])) throw std::invalid_argument("non-finite displacement");
  return m;
}

hil_msgs::msg::StiffnessEstimate to_message(const hc::OnlineEstimate& e) {
  hil_msgs::msg::StiffnessEstimate msg;
  msg.stamp(now_stamp());
  msg.configurations(static_cast<std::uint32_t>(e.configurations));
  msg.rank(static_cast<std::uint32_t>(e.rank));
  for (const auto& p : e.kept) {
    hil_msgs::msg::StiffnessParameter sp;
    sp.name(p.parameter.name);
    sp.value(p.value);
    sp.std_dev(p.std_dev);
    sp.pnr(p.pnr);
    sp.identifiability(hc::to_string(p.cls));
    msg.parameters().push_back(sp);
  }
  for (double r : e.residual_rms) msg.residual_rms().push_back(r);
  return msg;
}

StiffnessWorker::StiffnessWorker(dds::Participant& participant, std::unique_ptr<hc::OnlineIdentifier> identifier,
                                 std::chrono::microseconds estimate_period)
    : id_(std::move(identifier)), writer_(participant, dds::topics::kStiffnessEstimate, dds::StreamQos{true, 0, 1}),
      reader_(participant, dds::topics::kStiffnessMeasurement,
              [this](const hil_msgs::msg::StiffnessMeasurement& m, const auto&) {
                {
                  std::lock_guard<std::mutex> lock(mutex_);
                  queue_.push_back(m);
                }
                cv_.notify_one();
              }),
      period_(estimate_period) {}

void StiffnessWorker::publish_estimate() {
  last_ = id_->estimate();
  last_estimate_ = std::chrono::steady_clock::now();
  pending_ = false;
  ++estimates_;
  if (!writer_.write(to_message(last_))) spdlog::warn("stiffness worker: estimate not published");
}

std::size_t StiffnessWorker::spin(std::chrono::milliseconds timeout) {
  std::deque<hil_msgs::msg::StiffnessMeasurement> batch;
  {
    // With an estimate pending, wait no longer than its period has left.
    auto wait = std::chrono::duration_cast<std::chrono::steady_clock::duration>(timeout);
    if (pending_)
      wait = std::min(wait,
                      std::max(std::chrono::steady_clock::duration::zero(), last_estimate_ + period_ - std::chrono::steady_clock::now()));
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_for(lock, wait, [this] { return !queue_.empty(); });
    max_backlog_ = std::max(max_backlog_, queue_.size());
    batch.swap(queue_);
  }
  std::size_t n = 0;
  for (const auto& msg : batch) {
    try {
      id_->add(from_message(msg, id_->model().dof()));
    } catch (const std::exception& e) {
      ++rejected_;
      spdlog::warn("stiffness worker: measurement of configuration {} rejected: {}", msg.config(), e.what());
      continue;
    }
    ++processed_;
    ++n;
    pending_ = true;
    if (period_.count() == 0) publish_estimate();
  }
  if (pending_ && std::chrono::steady_clock::now() - last_estimate_ >= period_) publish_estimate();
  return n;
}

std::size_t replay_measurements(dds::Participant& participant, const models::StiffnessTable& table, const std::string& path, double rate_hz,
                                double wait_s) {
  dds::Writer<hil_msgs::msg::StiffnessMeasurement> w(participant, dds::topics::kStiffnessMeasurement);
  if (wait_s > 0 && !w.wait_for_readers(1, std::chrono::milliseconds(static_cast<long>(wait_s * 1e3))))
    spdlog::warn("replay: no reader matched within {} s; publishing anyway", wait_s);
  std::size_t i = 0;
  for (const auto& m : table.rows) {
    hil_msgs::msg::StiffnessMeasurement msg;
    try {
      msg = to_message(m);
    } catch (const std::invalid_argument& e) {
      throw error::FormatError({path, table.lines[i], 0, "m1_dx"}, e.what());
    }
    if (!w.write(msg)) throw std::runtime_error("replay: DDS refused a sample");
    ++i;
    if (rate_hz > 0) std::this_thread::sleep_for(std::chrono::duration<double>(1.0 / rate_hz));
  }
  w.wait_for_acknowledgments(std::chrono::seconds(10));
  return i;
}

WorkerRun run_stiffness_worker(dds::Participant& participant, std::unique_ptr<hc::OnlineIdentifier> identifier, std::size_t count,
                               double timeout_s, const std::atomic<bool>& stop, std::chrono::microseconds estimate_period) {
  StiffnessWorker w(participant, std::move(identifier), estimate_period);
  spdlog::info("stiffness worker: listening on {}, publishing on {}", dds::topics::kStiffnessMeasurement, dds::topics::kStiffnessEstimate);
  const auto start = std::chrono::steady_clock::now();
  while (!stop && (count == 0 || w.processed() < count)) {
    if (timeout_s > 0 && std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > timeout_s) break;
    const std::size_t estimates = w.estimates();
    w.spin(std::chrono::milliseconds(200));
    if (w.estimates() > estimates) {
      const auto& e = w.last();
      spdlog::info("estimate after {} measurements ({} configurations): rank {}, {} parameters", e.measurements, e.configurations, e.rank,
                   e.kept.size());
    }
  }
  w.spin(std::chrono::milliseconds(0));
  w.publish_pending();
  return {w.processed(), w.rejected(), w.last().rank};
}

}  // namespace hil::services::stiffness
