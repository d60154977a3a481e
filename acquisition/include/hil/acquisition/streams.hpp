#pragma once
/// \file What the devices hand to acquisition, and what it hands on: timestamped samples.
/// Times are CLOCK_REALTIME nanoseconds since the epoch (the kernel's CAN receive stamps use it).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

#include <hil/format/samples.hpp>
#include <hil/so3/so3.hpp>

namespace hil::acquisition {

using hil::Vector6d;

/// Quality bits, identical to hil_msgs::msg::QUALITY_* on the bus and the recorder's `quality` column.
enum Quality : std::uint32_t {
  kPoseExtrapolated = 1,
  kPoseStale = 2,
  kWrenchStale = 4,
  kWrenchSaturated = 8,
  kDeviceFault = 16,
  kGapBefore = 32,
};

/// One force-plate reading: wrench on the plate, force-plate frame (fx fy fz mx my mz).
struct WrenchReading {
  std::int64_t t_ns = 0;  ///< receive time (kernel stamp for CAN)
  std::uint64_t seq = 0;  ///< device reading counter
  Vector6d wrench_fp = Vector6d::Zero();
  std::uint32_t quality = 0;  ///< e.g. kWrenchSaturated, kDeviceFault
};

/// One robot reading: end-effector pose in world (and joints when read).
struct PoseReading {
  std::int64_t t_ns = 0;    ///< midpoint of request and response
  std::int64_t rtt_ns = 0;  ///< round-trip time of the poll
  std::uint64_t seq = 0;
  Eigen::Vector3d p_world_ee_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_world_ee = Eigen::Quaterniond::Identity();
  Eigen::VectorXd joints_rad;  ///< empty when the map has no joints
  std::uint32_t quality = 0;
};

/// One synchronized output sample, before it becomes a row or a message.
struct SyncedSample {
  std::int64_t t_ns = 0;
  std::uint64_t index = 0;
  Eigen::Vector3d p_world_ee_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_world_ee = Eigen::Quaterniond::Identity();
  Eigen::Vector3d v_world_ee_m_per_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d w_world_ee_rad_per_s = Eigen::Vector3d::Zero();
  Vector6d wrench_fp = Vector6d::Zero();
  Eigen::VectorXd joints_rad;
  std::uint64_t wrench_seq = 0, pose_seq = 0;
  double wrench_age_s = 0.0, pose_age_s = 0.0;
  std::uint32_t quality = 0;
};

/// A synchronized sample as a run-format row with time `t_s` (joints are kept apart).
format::Sample to_row(const SyncedSample& s, double t_s);

}  // namespace hil::acquisition
