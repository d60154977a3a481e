#include <hil/dds/qos.hpp>

#include <stdexcept>

#include <hil/dds/topics.hpp>

namespace hil::dds {

const std::vector<TopicQos>& qos_table() {
  // Keep-last 5000 (5 s at 1 kHz) for the streams: a slow reader never blocks acquisition and has
  // time to catch up; the ROS 2 tools' QoS for the rest (tf2's broadcasters, diagnostic_updater,
  // rclcpp's ClockQoS).
  static const std::vector<TopicQos> table = {
      {topics::kWrench, "geometry_msgs/msg/WrenchStamped", {true, 5000, 0}, true},
      {topics::kPose, "geometry_msgs/msg/PoseStamped", {true, 5000, 0}, true},
      {topics::kJointStates, "sensor_msgs/msg/JointState", {true, 5000, 0}, true},
      {topics::kTfStatic, "tf2_msgs/msg/TFMessage", {true, 1, 1}, false},
      {topics::kTf, "tf2_msgs/msg/TFMessage", {true, 100, 0}, true},
      {topics::kDiagnostics, "diagnostic_msgs/msg/DiagnosticArray", {true, 10, 0}, false},
      {topics::kPoseWrenchSample, "hil_msgs/msg/PoseWrenchSample", {true, 5000, 0}, false},
      {topics::kDeviceStatus, "hil_msgs/msg/DeviceStatus", {true, 10, 10}, false},
      {topics::kClock, "rosgraph_msgs/msg/Clock", {false, 1, 0}, false},
  };
  return table;
}

StreamQos qos_of(const std::string& topic, bool sensor_best_effort) {
  for (const auto& t : qos_table())
    if (topic == t.topic) return t.sensor && sensor_best_effort ? StreamQos{false, 5, 0} : t.qos;
  throw std::invalid_argument("no QoS for topic " + topic);
}

}  // namespace hil::dds
