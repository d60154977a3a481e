#pragma once
/// \file Topic names on the hil bus. ROS 2 maps a topic /x/y to the DDS topic rt/x/y, so a ROS 2
/// node subscribing to /hil/wrench receives rt/hil/wrench.
namespace hil::dds::topics {
inline constexpr const char* kPoseWrenchSample = "rt/hil/pose_wrench";  ///< hil_msgs/PoseWrenchSample
inline constexpr const char* kDeviceStatus = "rt/hil/device_status";    ///< hil_msgs/DeviceStatus
inline constexpr const char* kWrench = "rt/hil/wrench";                 ///< geometry_msgs/WrenchStamped
inline constexpr const char* kPose = "rt/hil/pose";                     ///< geometry_msgs/PoseStamped
inline constexpr const char* kTwist = "rt/hil/twist";                   ///< geometry_msgs/Twist
inline constexpr const char* kJointStates = "rt/hil/joint_states";      ///< sensor_msgs/JointState
/// ROS 2's well-known topics: the rig's fixed frames (tf2 static broadcaster QoS) and device health.
inline constexpr const char* kTfStatic = "rt/tf_static";       ///< tf2_msgs/TFMessage
inline constexpr const char* kTf = "rt/tf";                    ///< tf2_msgs/TFMessage: the moving edge, per sample
inline constexpr const char* kDiagnostics = "rt/diagnostics";  ///< diagnostic_msgs/DiagnosticArray
inline constexpr const char* kClock = "rt/clock";              ///< rosgraph_msgs/Clock (hil replay --clock)
inline constexpr const char* kStiffnessMeasurement = "rt/hil/stiffness/measurement";
inline constexpr const char* kStiffnessEstimate = "rt/hil/stiffness/estimate";
inline constexpr const char* kContactEstimate = "rt/hil/contact/estimate";
}  // namespace hil::dds::topics
