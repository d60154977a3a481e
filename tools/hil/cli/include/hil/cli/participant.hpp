#pragma once
// The bus participant of a command, from the global options (--dds-domain, --dds-profile,
// --secure): every command that joins the bus makes its participant through this.
#include <string>

#include <hil/dds/bus.hpp>

namespace hil::cli {

/// Domain, profile and, with --secure KEYSTORE[:NAME], the checked security files. Without
/// --secure-name or :NAME the keystore participant is the role: `name` without "hil-"
/// (hil-replay -> replay). \throws error::FormatError naming a missing or bad keystore file.
dds::ParticipantOptions participant_options(const std::string& name);

/// Only the security part of participant_options(); empty without --secure.
dds::SecurityFiles security_files(const std::string& name);

}  // namespace hil::cli
