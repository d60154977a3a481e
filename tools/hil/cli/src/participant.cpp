#include <hil/cli/participant.hpp>

#include <filesystem>

#include <hil/cli/commands.hpp>
#include <hil/keystore/keystore.hpp>

namespace hil::cli {

dds::SecurityFiles security_files(const std::string& name) {
  const auto& g = globals();
  if (g.secure.empty()) return {};
  // KEYSTORE[:NAME]: split at the last ':' only when what precedes it is a directory.
  std::string dir = g.secure, who = g.secure_name;
  if (const auto colon = dir.rfind(':'); colon != std::string::npos && colon > 0) {
    std::error_code ec;
    if (std::filesystem::is_directory(dir.substr(0, colon), ec)) {
      if (who.empty()) who = dir.substr(colon + 1);
      dir = dir.substr(0, colon);
    }
  }
  if (who.empty()) who = name.rfind("hil-", 0) == 0 ? name.substr(4) : name;
  return keystore::participant_files(dir, who);
}

dds::ParticipantOptions participant_options(const std::string& name) {
  const auto& g = globals();
  dds::ParticipantOptions o;
  o.domain_id = g.dds_domain >= 0 ? g.dds_domain : dds::domain_from_env();
  o.profile_file = g.dds_profile;
  o.profile_name = g.dds_profile_name;
  o.partition = g.dds_partition;
  o.name = name;
  o.security = security_files(name);
  return o;
}

}  // namespace hil::cli
