#pragma once
/// \file What the devices say about themselves, as the key/value lists run.yaml keeps under each
/// source's `identity` and `hil acquire --check` prints.
#include <string>
#include <utility>
#include <vector>

#include <hil/drivers/force_plate.hpp>
#include <hil/drivers/robot_controller.hpp>

namespace hil::acquisition {

using Identity = std::vector<std::pair<std::string, std::string>>;

/// Protocol, serial, firmware, units and counts (those the protocol reports).
Identity plate_identity(const drivers::ForcePlateInfo& info);
/// The link, the register map and the controller's Report Server ID answer (or why none).
Identity robot_identity(const drivers::ModbusConfig& cfg, const drivers::ControllerIdentity& id);

}  // namespace hil::acquisition
