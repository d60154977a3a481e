#pragma once
/// \file The QoS of every topic hil writes, by intent: one table that the writers, the MCAP
/// metadata (offered_qos_profiles) and docs/ros.md follow, and that tests/ros checks on the wire.
#include <string>
#include <vector>

#include <hil/dds/bus.hpp>

namespace hil::dds {

struct TopicQos {
  const char* topic;  ///< DDS name (rt/...)
  const char* type;   ///< ROS 2 type name
  StreamQos qos;
  /// A sensor stream: reliable by default, best effort (ROS 2's SensorDataQoS: keep last 5) when
  /// chosen (`hil acquire --sensor-qos best-effort`).
  bool sensor;
};

/// The table, in docs/ros.md's order.
const std::vector<TopicQos>& qos_table();

/// `topic`'s QoS (rt/... name); a sensor stream best effort when `sensor_best_effort`.
/// \throws std::invalid_argument for a topic not in the table.
StreamQos qos_of(const std::string& topic, bool sensor_best_effort = false);

}  // namespace hil::dds
