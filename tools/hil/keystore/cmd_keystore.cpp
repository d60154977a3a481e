// `hil keystore create|add|check`: the DDS Security keystore (docs/security.md).
#include <fmt/format.h>

#include <filesystem>
#include <iostream>

#include <hil/cli/commands.hpp>
#include <hil/keystore/keystore.hpp>

namespace hil::cli {
namespace {
struct KeystoreOptions {
  std::string dir, name;
  int days = 365;
  std::vector<std::string> publish, subscribe;
};

std::vector<std::string> dds_topics(const std::vector<std::string>& topics, const char* option) {
  std::vector<std::string> out;
  for (const auto& t : topics) out.push_back(keystore::dds_topic(t, option));
  return out;
}
}  // namespace

void add_keystore(CLI::App& app) {
  auto* cmd = app.add_subcommand("keystore", "DDS Security: make a keystore (CAs, governance) and participants' certificates "
                                             "and permissions (docs/security.md)");
  cmd->require_subcommand(1);
  static KeystoreOptions o;

  auto* create = cmd->add_subcommand("create", "Make DIR: an identity CA, a permissions CA and the signed governance");
  create->add_option("DIR", o.dir, "keystore directory (made if missing)")->required();
  create->add_option("--days", o.days, "validity of the CA certificates in days")->capture_default_str();
  create->callback([] {
    set_action([] {
      keystore::create(o.dir, o.days);
      std::cout << fmt::format("keystore {}: ca/identity_ca.pem, ca/permissions_ca.pem, governance.p7s (keep ca/*.key.pem private)\n",
                               o.dir);
      return 0;
    });
  });

  auto* add = cmd->add_subcommand("add", "Add participant NAME: key, certificate and signed permissions for its topics");
  add->add_option("DIR", o.dir, "keystore directory")->required();
  add->add_option("NAME", o.name, "participant name (its certificate's CN; hil --secure DIR:NAME)")->required();
  add->add_option("--publish", o.publish, "topics it may publish (rt/hil/pose_wrench or /hil/pose_wrench; '*' allowed), comma-separated")
      ->delimiter(',');
  add->add_option("--subscribe", o.subscribe, "topics it may subscribe to, comma-separated")->delimiter(',');
  add->add_option("--days", o.days, "validity of the certificate and permissions in days")->capture_default_str();
  add->callback([] {
    set_action([] {
      keystore::add(o.dir, o.name, {dds_topics(o.publish, "--publish"), dds_topics(o.subscribe, "--subscribe")}, o.days);
      std::cout << fmt::format("participant {}: {}/participants/{}/{{key.pem,cert.pem,permissions.p7s}}\n", o.name, o.dir, o.name);
      return 0;
    });
  });

  auto* check = cmd->add_subcommand("check", "Check participant NAME's files: signatures, key, subject (what --secure checks)");
  check->add_option("DIR", o.dir, "keystore directory")->required();
  check->add_option("NAME", o.name, "participant name")->required();
  check->callback([] {
    set_action([] {
      const auto f = keystore::participant_files(o.dir, o.name);
      std::cout << fmt::format("participant {}: ok ({}, {})\n", o.name, f.identity_certificate, f.permissions);
      return 0;
    });
  });
}

}  // namespace hil::cli
