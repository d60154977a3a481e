#pragma once
/// \file A ros2 bag's metadata.yaml: which files hold its messages. Pure (text in, names out), apart
/// from ros_import.cpp so that its fuzz target builds without the rest of acquisition.
#include <string>
#include <vector>

namespace hil::acquisition {

/// The files metadata.yaml lists (`display_name` names it in errors), relative to the bag folder,
/// in its order. \throws error::FormatError for another storage than MCAP, file compression, an
/// absolute or empty name, or no file.
std::vector<std::string> parse_bag_metadata(const std::string& yaml_text, const std::string& display_name);

}  // namespace hil::acquisition
