// Every bus type survives CDR serialization unchanged, and carries its ROS 2 type name.
#include <gtest/gtest.h>

#include <fastrtps/rtps/common/SerializedPayload.h>

#include <hil/messages/sample_msg.hpp>
#include <hil/dds/types.hpp>

namespace {

template <class Msg>
Msg roundtrip(const Msg& in, const std::string& expected_type_name) {
  typename hil::dds::TypeSupportOf<Msg>::type ts;
  EXPECT_EQ(std::string(ts.getName()), expected_type_name);
  const auto size = ts.getSerializedSizeProvider(const_cast<Msg*>(&in))();
  eprosima::fastrtps::rtps::SerializedPayload_t payload(size);
  EXPECT_TRUE(ts.serialize(const_cast<Msg*>(&in), &payload));
  Msg out;
  EXPECT_TRUE(ts.deserialize(&payload, &out));
  return out;
}

geometry_msgs::msg::Vector3 v3(double x, double y, double z) {
  geometry_msgs::msg::Vector3 v;
  v.x(x), v.y(y), v.z(z);
  return v;
}

std_msgs::msg::Header header() {
  std_msgs::msg::Header h;
  h.stamp().sec(1763715600);
  h.stamp().nanosec(123456789);
  h.frame_id("force_plate");
  return h;
}

}  // namespace

TEST(BusTypes, Ros2Types) {
  builtin_interfaces::msg::Time t;
  t.sec(-5), t.nanosec(999999999);
  EXPECT_EQ(roundtrip(t, "builtin_interfaces::msg::dds_::Time_"), t);
  EXPECT_EQ(roundtrip(header(), "std_msgs::msg::dds_::Header_"), header());
  EXPECT_EQ(roundtrip(v3(1, -2, 3.5), "geometry_msgs::msg::dds_::Vector3_"), v3(1, -2, 3.5));
  geometry_msgs::msg::Point p;
  p.x(0.1), p.y(0.2), p.z(0.3);
  EXPECT_EQ(roundtrip(p, "geometry_msgs::msg::dds_::Point_"), p);
  geometry_msgs::msg::Quaternion q;
  q.x(0.5), q.y(0.5), q.z(0.5), q.w(0.5);
  EXPECT_EQ(roundtrip(q, "geometry_msgs::msg::dds_::Quaternion_"), q);
  geometry_msgs::msg::Pose pose;
  pose.position(p), pose.orientation(q);
  EXPECT_EQ(roundtrip(pose, "geometry_msgs::msg::dds_::Pose_"), pose);
  geometry_msgs::msg::PoseStamped ps;
  ps.header(header()), ps.pose(pose);
  EXPECT_EQ(roundtrip(ps, "geometry_msgs::msg::dds_::PoseStamped_"), ps);
  geometry_msgs::msg::Twist tw;
  tw.linear(v3(1, 2, 3)), tw.angular(v3(-1, -2, -3));
  EXPECT_EQ(roundtrip(tw, "geometry_msgs::msg::dds_::Twist_"), tw);
  geometry_msgs::msg::Wrench w;
  w.force(v3(10, 20, -600)), w.torque(v3(0.1, 0.2, 0.3));
  EXPECT_EQ(roundtrip(w, "geometry_msgs::msg::dds_::Wrench_"), w);
  geometry_msgs::msg::WrenchStamped ws;
  ws.header(header()), ws.wrench(w);
  EXPECT_EQ(roundtrip(ws, "geometry_msgs::msg::dds_::WrenchStamped_"), ws);
  sensor_msgs::msg::JointState js;
  js.header(header());
  js.name({"j1", "j2", "j3"});
  js.position({0.1, 0.2, 0.3});
  js.velocity({});
  js.effort({1.0, 2.0, 3.0});
  EXPECT_EQ(roundtrip(js, "sensor_msgs::msg::dds_::JointState_"), js);
}

TEST(BusTypes, HilTypes) {
  hil::format::Sample s;
  s.t_s = 12.345678901;
  s.p_world_ee_m = {0.1, 0.2, 0.3};
  s.q_world_ee = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()));
  s.v_world_ee_m_per_s = {0.01, 0, -0.02};
  s.w_world_ee_rad_per_s = {0, 0.1, 0};
  s.f_fp_n = {1, 2, -700};
  s.m_fp_nm = {0.5, -0.5, 0.01};
  Eigen::RowVectorXd q(6);
  q << 0.1, 0.2, 0.3, 0.4, 0.5, 0.6;
  auto m = hil::messages::to_message(s, 42, q);
  m.wrench_seq(7), m.pose_seq(3), m.wrench_age_s(0.001), m.pose_age_s(0.004);
  m.quality_flags(hil_msgs::msg::QUALITY_POSE_EXTRAPOLATED | hil_msgs::msg::QUALITY_GAP_BEFORE);
  const auto back = roundtrip(m, "hil_msgs::msg::dds_::PoseWrenchSample_");
  EXPECT_EQ(back, m);
  Eigen::VectorXd joints;
  const auto s2 = hil::messages::from_message(back, &joints);
  EXPECT_EQ(s2.t_s, s.t_s);
  EXPECT_EQ(s2.f_fp_n, s.f_fp_n);
  EXPECT_EQ(joints, q.transpose());
  EXPECT_NEAR(hil::messages::from_time(back.header().stamp()), s.t_s, 1e-9);

  hil_msgs::msg::DeviceStatus d;
  d.device("force_plate"), d.state(hil_msgs::msg::DEVICE_DEGRADED), d.connected(true), d.rate_hz(999.5);
  d.last_sample_age_s(0.002), d.samples(100000), d.frames_dropped(3), d.errors(1), d.device_faults(4), d.last_error("bus-off");
  EXPECT_EQ(roundtrip(d, "hil_msgs::msg::dds_::DeviceStatus_"), d);

  hil_msgs::msg::StiffnessMeasurement sm;
  sm.config(3), sm.joints_rad({0, 1, 2, 3, 4, 5});
  sm.load_world().force(v3(0, 0, -1000));
  sm.displacement_world_m(v3(1e-4, 2e-4, -3e-3)), sm.has_rotation(false);
  EXPECT_EQ(roundtrip(sm, "hil_msgs::msg::dds_::StiffnessMeasurement_"), sm);

  hil_msgs::msg::StiffnessParameter sp;
  sp.name("k_link2_xx"), sp.value(1e-6), sp.std_dev(1e-8), sp.pnr(100), sp.identifiability("G1+");
  EXPECT_EQ(roundtrip(sp, "hil_msgs::msg::dds_::StiffnessParameter_"), sp);
  hil_msgs::msg::StiffnessEstimate se;
  se.configurations(10), se.rank(30), se.parameters({sp, sp}), se.residual_rms({1e-5, 2e-5, 3e-5});
  EXPECT_EQ(roundtrip(se, "hil_msgs::msg::dds_::StiffnessEstimate_"), se);

  hil_msgs::msg::ContactEstimate ce;
  ce.t_s(1.5), ce.contact_points(4), ce.instantaneous_valid(true), ce.k_instant_n_per_m(1.8e5), ce.mu_instant(0.2);
  ce.k_global_n_per_m(1.79e5), ce.k_global_std(1e3), ce.mu_global(0.19), ce.mu_global_std(0.01), ce.samples_used(100);
  ce.relative_force_error(0.05);
  EXPECT_EQ(roundtrip(ce, "hil_msgs::msg::dds_::ContactEstimate_"), ce);
}

TEST(BusTypes, TimeConversionCarries) {
  const auto t = hil::messages::to_time(2.9999999999);
  EXPECT_EQ(t.sec(), 3);
  EXPECT_EQ(t.nanosec(), 0u);
}
