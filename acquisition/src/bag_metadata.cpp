#include <hil/acquisition/bag_metadata.hpp>

#include <fmt/format.h>

#include <filesystem>

#include <hil/error/error.hpp>
#include <hil/format/yaml.hpp>

namespace hil::acquisition {
namespace fs = std::filesystem;

std::vector<std::string> parse_bag_metadata(const std::string& text, const std::string& meta_path) {
  const auto doc = format::load_yaml(text, meta_path);
  if (!doc.IsMap()) throw error::FormatError({meta_path, 0, 0, ""}, "not a rosbag2 metadata.yaml (a mapping)");
  const format::YamlNode root(doc, "", &meta_path);
  const auto info = root.req("rosbag2_bagfile_information");
  const auto storage = info.req("storage_identifier").str();
  if (storage != "mcap")
    info.child("storage_identifier")
        .fail(fmt::format("storage '{}': hil reads MCAP storage (convert with `ros2 bag convert -i {} -o out.yaml`, out.yaml "
                          "naming storage_id: mcap)",
                          storage, fs::path(meta_path).parent_path().string()));
  if (info.has("compression_format") && !info.child("compression_format").str().empty())
    info.child("compression_format")
        .fail(fmt::format("a file-compressed bag ({}): decompress it first (`ros2 bag decompress`)",
                          info.child("compression_format").str()));
  std::vector<std::string> files;
  for (const auto& f : info.req("relative_file_paths").seq()) {
    const auto name = f.str();
    if (name.empty() || fs::path(name).is_absolute()) f.fail("expected a file name relative to the bag folder, found '" + name + "'");
    files.push_back(name);
  }
  if (files.empty()) info.child("relative_file_paths").fail("the bag lists no file");
  return files;
}

}  // namespace hil::acquisition
