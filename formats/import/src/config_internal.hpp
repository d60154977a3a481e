#pragma once
// Shared by the two import configs (config.cpp: runs, calibration_import.cpp: calibration runs).
#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include <hil/format/yaml.hpp>

namespace hil::import {

/// The `csv` section: delimiter, header, column names (NAME_xyz expanded).
void read_csv_section(const format::YamlNode& n, char& delimiter, bool& header, std::vector<std::string>& columns);
/// The config's `kind` (`run` when absent). \throws FormatError for another value.
std::string config_kind(const YAML::Node& doc, const std::string& display_name);

}  // namespace hil::import
