#pragma once
/// \file Conversions between run-format samples and bus messages.
#include <Eigen/Core>

#include <hil/dds/types.hpp>
#include <hil/format/samples.hpp>

namespace hil::messages {

/// Time since the epoch (or since run start) in seconds -> ROS 2 Time.
builtin_interfaces::msg::Time to_time(double t_s);
/// The same from integer ns since the epoch, exactly: every stamp of a sample (live, run folder,
/// MCAP) goes through this one (a double of epoch seconds resolves only ~240 ns).
builtin_interfaces::msg::Time to_time_ns(std::int64_t t_ns);
double from_time(const builtin_interfaces::msg::Time& t);

/// A sample as a PoseWrenchSample; `index` becomes sample_index, stamp = t_s.
hil_msgs::msg::PoseWrenchSample to_message(const format::Sample& s, std::uint64_t index,
                                           const Eigen::Ref<const Eigen::RowVectorXd>& joints_rad);
/// Back to a sample (joints into `joints_rad`, resized).
format::Sample from_message(const hil_msgs::msg::PoseWrenchSample& m, Eigen::VectorXd* joints_rad = nullptr);

}  // namespace hil::messages
