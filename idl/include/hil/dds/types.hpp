#pragma once
/// \file Maps each bus message to its generated Fast DDS type support, so that the templates in
/// bus.hpp take the message type alone.
#include "builtin_interfacesPubSubTypes.h"
#include "diagnostic_msgsPubSubTypes.h"
#include "geometry_msgsPubSubTypes.h"
#include "hil_msgsPubSubTypes.h"
#include "sensor_msgsPubSubTypes.h"
#include "rosgraph_msgsPubSubTypes.h"
#include "std_msgsPubSubTypes.h"
#include "tf2_msgsPubSubTypes.h"

namespace hil::dds {

template <class Msg>
struct TypeSupportOf;  // specialised below for every bus type

#define HIL_DDS_TYPE(ns, T)         \
  template <>                       \
  struct TypeSupportOf<ns::T> {     \
    using type = ns::T##PubSubType; \
  };
HIL_DDS_TYPE(builtin_interfaces::msg, Time)
HIL_DDS_TYPE(std_msgs::msg, Header)
HIL_DDS_TYPE(geometry_msgs::msg, Vector3)
HIL_DDS_TYPE(geometry_msgs::msg, Point)
HIL_DDS_TYPE(geometry_msgs::msg, Quaternion)
HIL_DDS_TYPE(geometry_msgs::msg, Pose)
HIL_DDS_TYPE(geometry_msgs::msg, PoseStamped)
HIL_DDS_TYPE(geometry_msgs::msg, Twist)
HIL_DDS_TYPE(geometry_msgs::msg, Wrench)
HIL_DDS_TYPE(geometry_msgs::msg, WrenchStamped)
HIL_DDS_TYPE(geometry_msgs::msg, Transform)
HIL_DDS_TYPE(geometry_msgs::msg, TransformStamped)
HIL_DDS_TYPE(sensor_msgs::msg, JointState)
HIL_DDS_TYPE(tf2_msgs::msg, TFMessage)
HIL_DDS_TYPE(rosgraph_msgs::msg, Clock)
HIL_DDS_TYPE(diagnostic_msgs::msg, KeyValue)
HIL_DDS_TYPE(diagnostic_msgs::msg, DiagnosticStatus)
HIL_DDS_TYPE(diagnostic_msgs::msg, DiagnosticArray)
HIL_DDS_TYPE(hil_msgs::msg, PoseWrenchSample)
HIL_DDS_TYPE(hil_msgs::msg, DeviceStatus)
HIL_DDS_TYPE(hil_msgs::msg, StiffnessMeasurement)
HIL_DDS_TYPE(hil_msgs::msg, StiffnessParameter)
HIL_DDS_TYPE(hil_msgs::msg, StiffnessEstimate)
HIL_DDS_TYPE(hil_msgs::msg, ContactEstimate)
#undef HIL_DDS_TYPE

}  // namespace hil::dds
