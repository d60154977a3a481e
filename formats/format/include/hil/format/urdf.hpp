#pragma once
/// \file A robot from its URDF: the chain from a base link to a tip link as the rig's robot
/// (docs/formats.md, "URDF robots"). urdfdom parses the file, kdl_parser builds the Orocos KDL tree
/// and KDL extracts the chain; this reader turns the chain's segments into joint rows (origin in the
/// previous body, axis in the joint frame), lumps fixed links into the body they hang from, and keeps
/// every body's inertial. Bad input throws hil::error::FormatError naming the file and the element.
#include <string>

#include <hil/format/rig.hpp>

namespace hil::format {

/// The chain base_link -> tip_link of the URDF at `path`. T_world_base and T_flange_ee are identity
/// apart from the fixed links after the last moving joint (folded into T_flange_ee).
RobotSpec read_urdf_robot(const std::string& path, const std::string& base_link, const std::string& tip_link);
/// The same from the XML text; `display_name` is used in messages.
RobotSpec parse_urdf_robot(const std::string& xml, const std::string& display_name, const std::string& base_link,
                           const std::string& tip_link);

}  // namespace hil::format
