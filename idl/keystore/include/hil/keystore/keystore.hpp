#pragma once
/// \file A DDS Security keystore made and checked with Debian's `openssl` command (docs/security.md):
///   DIR/ca/identity_ca.pem, identity_ca.key.pem       signs participants' certificates
///   DIR/ca/permissions_ca.pem, permissions_ca.key.pem  signs governance and permissions
///   DIR/governance.xml, governance.p7s                 the domain's rules (signed)
///   DIR/participants/NAME/{key.pem,cert.pem,permissions.xml,permissions.p7s}
#include <string>
#include <vector>

#include <hil/dds/bus.hpp>

namespace hil::keystore {

/// Makes DIR with both CAs and the signed governance; DIR must not hold a keystore already.
/// \throws error::FormatError on a bad argument, std::runtime_error when openssl fails.
void create(const std::string& dir, int days);

/// Topics a participant may use, as DDS names (`rt/hil/pose_wrench`; wildcards allowed).
struct Grants {
  std::vector<std::string> publish;
  std::vector<std::string> subscribe;
};

/// Makes participants/NAME: key, certificate signed by the identity CA, permissions signed by the
/// permissions CA (allow rules for `grants`, default DENY). Replaces an existing NAME.
void add(const std::string& dir, const std::string& name, const Grants& grants, int days);

/// `rt/hil/x` as is, ROS 2's `/hil/x` as `rt/hil/x`; anything else is a FormatError naming `where`.
std::string dds_topic(const std::string& topic, const std::string& where);

/// The files of participant NAME in DIR, each checked before Fast DDS sees them: present, the
/// certificate signed by the identity CA and matching the key, governance and permissions signed by
/// the permissions CA. \throws error::FormatError naming the file and what is wrong.
dds::SecurityFiles participant_files(const std::string& dir, const std::string& name);

}  // namespace hil::keystore
