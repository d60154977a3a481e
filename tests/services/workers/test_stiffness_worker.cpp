// The online worker on a real DDS bus (in-process, host-only profile): an estimate is published
// after every measurement, or at most once a period when one is set, and the last one equals the
// batch identification.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <tuple>

#include <hil/calibration/experiment.hpp>
#include <hil/dds/topics.hpp>
#include <hil/services/stiffness_worker.hpp>

namespace hc = hil::calibration;
namespace st = hil::services::stiffness;

TEST(StiffnessMessages, RoundTripAndRefusals) {
  hc::Measurement m;
  m.config = 7;
  m.q_rad = (Eigen::VectorXd(6) << 1, 2, 3, 4, 5, 6).finished();
  m.w_world << 10, 20, 30, 1, 2, 3;
  m.kind = hc::MeasurementKind::pose6;
  m.displacement = (Eigen::VectorXd(6) << 1e-4, 2e-4, 3e-4, 1e-5, 2e-5, 3e-5).finished();
  const auto back = st::from_message(st::to_message(m), 6);
  EXPECT_EQ(back.config, 7);
  EXPECT_EQ(back.kind, hc::MeasurementKind::pose6);
  EXPECT_EQ(back.displacement, m.displacement);
  EXPECT_EQ(back.w_world, m.w_world);
  EXPECT_THAT([&] { st::from_message(st::to_message(m), 5); },
              ::testing::ThrowsMessage<std::invalid_argument>(::testing::HasSubstr("measurement with 6 joints, the robot has 5")));
  m.kind = hc::MeasurementKind::point3;
  m.displacement.conservativeResize(3);
  EXPECT_EQ(st::from_message(st::to_message(m), 6).kind, hc::MeasurementKind::point3);
  m.kind = hc::MeasurementKind::markers;
  EXPECT_THAT([&] { st::to_message(m); }, ::testing::ThrowsMessage<std::invalid_argument>(
                                              ::testing::HasSubstr("marker measurements have no StiffnessMeasurement form")));
}

namespace {

/// A simulated KR-270 stiffness experiment and its six joint springs (the identified set).
struct JointSprings {
  hc::VjmModel model{hc::kr270_like()};
  hc::NoiseModel noise{10e-6, 10e-6};
  std::vector<hc::Measurement> data;
  hc::ParameterSet joints;
  JointSprings(int configurations, std::uint64_t seed) {
    hc::ExperimentPlan plan;
    plan.configurations = configurations;
    plan.moment_nm = 200.0;
    plan.seed = seed;
    data = hc::simulate(model, hc::example_compliance(model), plan, noise);
    for (int j = 1; j <= 6; ++j) joints.push_back({model.joint_spring(j), 0, 0, false, "J" + std::to_string(j) + ".k"});
  }
  std::unique_ptr<hc::OnlineIdentifier> identifier() const {
    return std::make_unique<hc::OnlineIdentifier>(model, joints, hc::ParameterSet{}, Eigen::VectorXd(), noise);
  }
};

}  // namespace

TEST(StiffnessWorker, PublishesAnEstimateAfterEachMeasurement) {
  const JointSprings springs(20, 77);
  const auto& [model, noise, data, joints] = std::tie(springs.model, springs.noise, springs.data, springs.joints);

  const int domain = 150 + static_cast<int>(getpid() % 50);
  hil::dds::Participant p({domain, "", "hil_localhost", "test-stiffness"});
  st::StiffnessWorker worker(p, springs.identifier());
  std::mutex mu;
  std::vector<hil_msgs::msg::StiffnessEstimate> got;
  hil::dds::Reader<hil_msgs::msg::StiffnessEstimate> reader(p, hil::dds::topics::kStiffnessEstimate,
                                                            [&](const hil_msgs::msg::StiffnessEstimate& e, const auto&) {
                                                              std::lock_guard<std::mutex> lock(mu);
                                                              got.push_back(e);
                                                            });
  hil::dds::Writer<hil_msgs::msg::StiffnessMeasurement> writer(p, hil::dds::topics::kStiffnessMeasurement);
  ASSERT_TRUE(writer.wait_for_readers(1, std::chrono::seconds(10))) << "the worker's reader did not match (DDS discovery)";
  ASSERT_TRUE(reader.wait_for_writers(1, std::chrono::seconds(10))) << "the estimate reader did not match (DDS discovery)";
  for (const auto& d : data) ASSERT_TRUE(writer.write(st::to_message(d)));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (worker.processed() < data.size() && std::chrono::steady_clock::now() < deadline) worker.spin(std::chrono::milliseconds(100));
  ASSERT_EQ(worker.processed(), data.size());
  EXPECT_EQ(worker.rejected(), 0u);
  while (std::chrono::steady_clock::now() < deadline) {
    {
      std::lock_guard<std::mutex> lock(mu);
      if (got.size() >= data.size()) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::lock_guard<std::mutex> lock(mu);
  ASSERT_EQ(got.size(), data.size());
  EXPECT_EQ(got.back().configurations(), 20u);
  EXPECT_EQ(got.back().rank(), 6u);
  ASSERT_EQ(got.back().parameters().size(), 6u);
  EXPECT_EQ(got.back().residual_rms().size(), 6u);
  const auto batch = hc::identify_fixed_set(model, joints, data, noise);
  for (std::size_t k = 0; k < 6; ++k) {
    const auto& prm = got.back().parameters()[k];
    EXPECT_EQ(prm.name(), batch.kept[k].parameter.name);
    EXPECT_NEAR(prm.value(), batch.kept[k].value, 1e-9 * std::abs(batch.kept[k].value));
    EXPECT_NEAR(prm.std_dev(), batch.kept[k].std_dev, 1e-6 * batch.kept[k].std_dev);
    EXPECT_EQ(prm.identifiability(), hc::to_string(batch.kept[k].cls));
  }
}

TEST(StiffnessWorker, WithAnEstimatePeriodEstimatesAtMostOnceAPeriodAndAfterTheLastMeasurement) {
  // Measurements at about 1 kHz, an estimate period of 50 ms: every measurement is added, the
  // estimates (a re-reduction each) come at most once a period, and the last one covers them all.
  const JointSprings springs(300, 78);
  const auto& [model, noise, data, joints] = std::tie(springs.model, springs.noise, springs.data, springs.joints);

  const int domain = 100 + static_cast<int>(getpid() % 50);
  hil::dds::Participant p({domain, "", "hil_localhost", "test-stiffness-period"});
  const auto period = std::chrono::milliseconds(50);
  st::StiffnessWorker worker(p, springs.identifier(), period);
  std::atomic<std::size_t> received{0};
  hil::dds::Reader<hil_msgs::msg::StiffnessEstimate> reader(p, hil::dds::topics::kStiffnessEstimate,
                                                            [&](const hil_msgs::msg::StiffnessEstimate&, const auto&) { ++received; });
  hil::dds::Writer<hil_msgs::msg::StiffnessMeasurement> writer(p, hil::dds::topics::kStiffnessMeasurement);
  ASSERT_TRUE(writer.wait_for_readers(1, std::chrono::seconds(10))) << "the worker's reader did not match (DDS discovery)";
  ASSERT_TRUE(reader.wait_for_writers(1, std::chrono::seconds(10))) << "the estimate reader did not match (DDS discovery)";
  const auto start = std::chrono::steady_clock::now();
  std::thread publisher([&] {
    auto next = std::chrono::steady_clock::now();
    for (const auto& d : data) {
      next += std::chrono::milliseconds(1);
      std::this_thread::sleep_until(next);
      writer.write(st::to_message(d));
    }
  });
  const auto deadline = start + std::chrono::seconds(20);
  while (worker.processed() < data.size() && std::chrono::steady_clock::now() < deadline) worker.spin(std::chrono::milliseconds(100));
  publisher.join();
  ASSERT_EQ(worker.processed(), data.size());
  // The last measurements' estimate comes within a period of the last one, by spin alone.
  const auto last_in = std::chrono::steady_clock::now();
  while (worker.last().measurements < data.size() && std::chrono::steady_clock::now() < last_in + 4 * period)
    worker.spin(std::chrono::milliseconds(100));
  const double elapsed_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(worker.last().measurements, data.size());
  EXPECT_GE(worker.estimates(), 2u);
  EXPECT_LE(static_cast<double>(worker.estimates()), elapsed_ms / 50.0 + 2.0) << "over " << elapsed_ms << " ms";
  const auto batch = hc::identify_fixed_set(model, joints, data, noise);
  ASSERT_EQ(worker.last().kept.size(), 6u);
  for (std::size_t k = 0; k < 6; ++k) EXPECT_NEAR(worker.last().kept[k].value, batch.kept[k].value, 1e-9 * std::abs(batch.kept[k].value));
  const auto wait = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (received < worker.estimates() && std::chrono::steady_clock::now() < wait)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(received.load(), worker.estimates());
}
