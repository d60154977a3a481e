// The keystore through Debian's `openssl` command rather than libcrypto: the same commands the
// DDS Security documents and Fast DDS's examples use, so a lab can redo or audit each step by hand
// (docs/security.md), and no key handling code of our own.
#include <hil/keystore/keystore.hpp>

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <hil/error/error.hpp>

namespace hil::keystore {
namespace fs = std::filesystem;
namespace {

struct Result {
  int status = -1;
  std::string output;  // stdout and stderr together
};

// Runs openssl with `args`, no shell; its output is captured, never printed.
Result openssl(const std::vector<std::string>& args) {
  // argv before fork: other threads (Fast DDS's, in hil demo) may exist, so the child only execs.
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>("openssl"));
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error(std::string("keystore: pipe: ") + std::strerror(errno));
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("keystore: fork: ") + std::strerror(errno));
  if (pid == 0) {
    dup2(fds[1], 1);
    dup2(fds[1], 2);
    close(fds[0]);
    close(fds[1]);
    execvp("openssl", argv.data());
    _exit(127);
  }
  close(fds[1]);
  Result r;
  char buf[4096];
  for (ssize_t n; (n = read(fds[0], buf, sizeof buf)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    r.output.append(buf, static_cast<std::size_t>(n));
  }
  close(fds[0]);
  int st = 0;
  while (waitpid(pid, &st, 0) < 0 && errno == EINTR) {
  }
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  if (r.status == 127) throw std::runtime_error("keystore: cannot run openssl (apt-get install openssl)");
  return r;
}

// The last meaningful line of openssl's complaint, for one-line errors. OpenSSL 3 error lines read
// "THREAD:error:CODE:LIBRARY:FUNCTION:REASON:FILE:LINE:": keep FUNCTION: REASON.
std::string reason(const std::string& output) {
  std::istringstream in(output);
  std::string line, last;
  while (std::getline(in, line)) {
    if (line.empty() || line.rfind("Verification failure", 0) == 0) continue;
    if (line.find("error") != std::string::npos || last.empty()) last = line;
  }
  if (const auto e = last.find(":error:"); e != std::string::npos) {
    std::vector<std::string> f;
    std::istringstream parts(last.substr(e + 7));
    for (std::string p; std::getline(parts, p, ':');) f.push_back(p);
    if (f.size() >= 4) return f[2] + ": " + f[3];
  }
  return last.empty() ? "openssl gave no reason" : last;
}

void run_or_throw(const std::vector<std::string>& args, const std::string& what) {
  const auto r = openssl(args);
  if (r.status != 0) throw std::runtime_error("keystore: " + what + ": openssl failed: " + reason(r.output));
}

void write_file(const fs::path& p, const std::string& text) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f << text;
  if (!f.flush()) throw std::runtime_error("keystore: cannot write " + p.string());
}

std::string read_file(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

void private_file(const fs::path& p) { fs::permissions(p, fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace); }

// Extensions for both CAs and for participants; our own file so the result does not depend on the
// machine's openssl.cnf.
constexpr const char* kOpensslConfig = R"([req]
distinguished_name = dn
prompt = no
[dn]
[ca_ext]
basicConstraints = critical,CA:TRUE
keyUsage = critical,keyCertSign,cRLSign,digitalSignature
subjectKeyIdentifier = hash
[participant_ext]
basicConstraints = critical,CA:FALSE
keyUsage = critical,digitalSignature,keyAgreement
subjectKeyIdentifier = hash
authorityKeyIdentifier = keyid
)";

std::string utc(std::chrono::system_clock::time_point t) {
  const std::time_t tt = std::chrono::system_clock::to_time_t(t);
  std::tm tm{};
  gmtime_r(&tt, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  return buf;
}

// hil's topics, each encrypted and access-controlled; the last rule covers any other topic the same
// way, so no topic on a secure domain is open.
std::string governance_xml() {
  std::string rules;
  for (const char* expr : {"rt/hil/*", "rt/tf_static", "rt/diagnostics", "*"})
    rules += fmt::format(R"(        <topic_rule>
          <topic_expression>{}</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
)",
                         expr);
  return fmt::format(R"(<?xml version="1.0" encoding="UTF-8"?>
<!-- hil keystore governance (docs/security.md): every domain, only authenticated participants with
     permissions join, discovery, liveliness and hil's topics (every submessage and payload)
     encrypted. rtps_protection_kind is NONE: Fast DDS 2.9 can abort in encode_rtps_message when a
     peer leaves while this participant tears down (docs/security.md, "Why not rtps_protection"). -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains>
        <id_range><min>0</min><max>232</max></id_range>
      </domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>NONE</rtps_protection_kind>
      <topic_access_rules>
{}      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
)",
                     rules);
}

std::string topics_xml(const char* tag, const std::vector<std::string>& topics) {
  if (topics.empty()) return "";
  std::string s = fmt::format("        <{}>\n          <topics>\n", tag);
  for (const auto& t : topics) s += fmt::format("            <topic>{}</topic>\n", t);
  return s + fmt::format("          </topics>\n        </{}>\n", tag);
}

std::string permissions_xml(const std::string& name, const std::string& subject, const Grants& g, int days) {
  const auto now = std::chrono::system_clock::now();
  return fmt::format(R"(<?xml version="1.0" encoding="UTF-8"?>
<!-- hil keystore permissions of participant '{0}' (docs/security.md). -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="hil_{0}">
      <subject_name>{1}</subject_name>
      <validity>
        <not_before>{2}</not_before>
        <not_after>{3}</not_after>
      </validity>
      <allow_rule>
        <domains>
          <id_range><min>0</min><max>232</max></id_range>
        </domains>
{4}{5}      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
)",
                     name, subject, utc(now - std::chrono::hours(1)), utc(now + std::chrono::hours(24) * days),
                     topics_xml("publish", g.publish), topics_xml("subscribe", g.subscribe));
}

void check_days(int days) {
  if (days < 1 || days > 36500)
    throw error::FormatError({"command line", 0, 0, "--days"}, fmt::format("expected 1..36500, found {}", days));
}

void check_name(const std::string& name) {
  const bool ok = !name.empty() && name.size() <= 64 && name.front() != '.' && std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
  });
  if (!ok)
    throw error::FormatError({"command line", 0, 0, "NAME"},
                             "expected a participant name of letters, digits, '_', '-' or '.' (at most 64), found '" + name + "'");
}

struct Layout {
  fs::path dir;
  fs::path ca() const { return dir / "ca"; }
  fs::path identity_ca() const { return ca() / "identity_ca.pem"; }
  fs::path identity_ca_key() const { return ca() / "identity_ca.key.pem"; }
  fs::path permissions_ca() const { return ca() / "permissions_ca.pem"; }
  fs::path permissions_ca_key() const { return ca() / "permissions_ca.key.pem"; }
  fs::path config() const { return ca() / "openssl.cnf"; }
  fs::path governance() const { return dir / "governance.p7s"; }
  fs::path participant(const std::string& name) const { return dir / "participants" / name; }
};

void need(const fs::path& p, const std::string& what, const std::string& hint) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) throw error::FormatError({p.string(), 0, 0, ""}, what + " not found" + hint);
  if (!std::ifstream(p)) throw error::FormatError({p.string(), 0, 0, ""}, what + " not readable: " + std::strerror(errno));
}

void sign(const Layout& k, const fs::path& xml, const fs::path& p7s) {
  run_or_throw({"smime", "-sign", "-text", "-in", xml.string(), "-out", p7s.string(), "-signer", k.permissions_ca().string(), "-inkey",
                k.permissions_ca_key().string()},
               "signing " + xml.string());
}

void verify_signed(const Layout& k, const fs::path& p7s) {
  const auto r = openssl({"smime", "-verify", "-in", p7s.string(), "-CAfile", k.permissions_ca().string(), "-purpose", "any", "-out",
                          "/dev/null"});
  if (r.status != 0)
    throw error::FormatError({p7s.string(), 0, 0, ""}, "signature does not verify against the permissions CA " +
                                                           k.permissions_ca().string() +
                                                           " (changed after signing, or signed by another CA): " + reason(r.output));
}

std::string subject_rfc2253(const fs::path& cert) {
  const auto r = openssl({"x509", "-noout", "-subject", "-nameopt", "RFC2253", "-in", cert.string()});
  if (r.status != 0) throw error::FormatError({cert.string(), 0, 0, ""}, "not a PEM certificate: " + reason(r.output));
  std::string s = r.output.substr(0, r.output.find('\n'));
  if (s.rfind("subject=", 0) == 0) s = s.substr(8);
  return s;
}

std::string public_key(const std::vector<std::string>& args, const fs::path& file, const std::string& what) {
  const auto r = openssl(args);
  if (r.status != 0) throw error::FormatError({file.string(), 0, 0, ""}, "not a PEM " + what + ": " + reason(r.output));
  return r.output;
}

}  // namespace

std::string dds_topic(const std::string& topic, const std::string& where) {
  std::string t = topic;
  if (t.rfind("rt/", 0) != 0 && !t.empty() && t.front() == '/') t = "rt" + t;
  const bool ok = t.rfind("rt/", 0) == 0 && t.size() > 3 && std::all_of(t.begin(), t.end(), [](char c) {
                    return std::isalnum(static_cast<unsigned char>(c)) || std::strchr("_/*?.-", c) != nullptr;
                  });
  if (!ok)
    throw error::FormatError({"command line", 0, 0, where}, "expected a DDS topic (rt/hil/pose_wrench) or a ROS 2 topic "
                                                            "(/hil/pose_wrench), '*' allowed, found '" +
                                                                topic + "'");
  return t;
}

void create(const std::string& dir, int days) {
  check_days(days);
  const Layout k{dir};
  std::error_code ec;
  if (fs::exists(k.identity_ca(), ec) || fs::exists(k.governance(), ec))
    throw error::FormatError({dir, 0, 0, ""}, "already holds a keystore (a new CA would orphan its participants)");
  fs::create_directories(k.ca());
  fs::create_directories(k.dir / "participants");
  write_file(k.config(), kOpensslConfig);
  const auto ca = [&](const fs::path& cert, const fs::path& key, const char* cn) {
    run_or_throw({"req",
                  "-x509",
                  "-new",
                  "-config",
                  k.config().string(),
                  "-extensions",
                  "ca_ext",
                  "-newkey",
                  "ec",
                  "-pkeyopt",
                  "ec_paramgen_curve:prime256v1",
                  "-nodes",
                  "-sha256",
                  "-days",
                  std::to_string(days),
                  "-subj",
                  std::string("/O=hil/CN=") + cn,
                  "-keyout",
                  key.string(),
                  "-out",
                  cert.string()},
                 std::string("making the ") + cn);
    private_file(key);
  };
  ca(k.identity_ca(), k.identity_ca_key(), "hil identity CA");
  ca(k.permissions_ca(), k.permissions_ca_key(), "hil permissions CA");
  write_file(k.dir / "governance.xml", governance_xml());
  sign(k, k.dir / "governance.xml", k.governance());
}

void add(const std::string& dir, const std::string& name, const Grants& g, int days) {
  check_days(days);
  check_name(name);
  if (g.publish.empty() && g.subscribe.empty())
    throw error::FormatError({"command line", 0, 0, "--publish/--subscribe"}, "participant '" + name + "' would be allowed no topic");
  const Layout k{dir};
  const std::string hint = " (make the keystore with: hil keystore create " + dir + ")";
  need(k.identity_ca_key(), "identity CA key", hint);
  need(k.permissions_ca_key(), "permissions CA key", hint);
  const fs::path p = k.participant(name);
  fs::create_directories(p);
  const fs::path key = p / "key.pem", csr = p / "cert.csr", cert = p / "cert.pem";
  run_or_throw({"req", "-new", "-config", k.config().string(), "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes",
                "-sha256", "-subj", "/O=hil/CN=" + name, "-keyout", key.string(), "-out", csr.string()},
               "making the key of " + name);
  private_file(key);
  run_or_throw({"x509",
                "-req",
                "-in",
                csr.string(),
                "-CA",
                k.identity_ca().string(),
                "-CAkey",
                k.identity_ca_key().string(),
                "-CAcreateserial",
                "-CAserial",
                (k.ca() / "identity_ca.srl").string(),
                "-sha256",
                "-days",
                std::to_string(days),
                "-extfile",
                k.config().string(),
                "-extensions",
                "participant_ext",
                "-out",
                cert.string()},
               "signing the certificate of " + name);
  fs::remove(csr);
  write_file(p / "permissions.xml", permissions_xml(name, subject_rfc2253(cert), g, days));
  sign(k, p / "permissions.xml", p / "permissions.p7s");
}

dds::SecurityFiles participant_files(const std::string& dir, const std::string& name) {
  check_name(name);
  const Layout k{dir};
  const fs::path p = k.participant(name);
  std::error_code ec;
  if (!fs::is_directory(k.dir, ec)) throw error::FormatError({dir, 0, 0, ""}, "keystore not found");
  const std::string create_hint = " (make the keystore with: hil keystore create " + dir + ")";
  need(k.identity_ca(), "identity CA certificate", create_hint);
  need(k.permissions_ca(), "permissions CA certificate", create_hint);
  need(k.governance(), "governance document", create_hint);
  const std::string add_hint = " (make participant '" + name + "' with: hil keystore add " + dir + " " + name +
                               " --publish/--subscribe TOPICS)";
  need(p / "cert.pem", "certificate of participant '" + name + "'", add_hint);
  need(p / "key.pem", "private key of participant '" + name + "'", add_hint);
  need(p / "permissions.p7s", "permissions of participant '" + name + "'", add_hint);

  const auto v = openssl({"verify", "-CAfile", k.identity_ca().string(), (p / "cert.pem").string()});
  if (v.status != 0)
    throw error::FormatError({(p / "cert.pem").string(), 0, 0, ""},
                             "certificate does not verify against the identity CA " + k.identity_ca().string() + ": " + reason(v.output));
  if (public_key({"x509", "-noout", "-pubkey", "-in", (p / "cert.pem").string()}, p / "cert.pem", "certificate") !=
      public_key({"pkey", "-pubout", "-in", (p / "key.pem").string()}, p / "key.pem", "private key"))
    throw error::FormatError({(p / "key.pem").string(), 0, 0, ""}, "private key does not belong to " + (p / "cert.pem").string());
  verify_signed(k, k.governance());
  verify_signed(k, p / "permissions.p7s");
  // Fast DDS matches the grant to the certificate by subject; a mixed-up file is named here.
  const std::string text = read_file(p / "permissions.p7s"), subject = subject_rfc2253(p / "cert.pem");
  const auto b = text.find("<subject_name>"), e = text.find("</subject_name>");
  if (b == std::string::npos || e == std::string::npos || text.substr(b + 14, e - b - 14) != subject)
    throw error::FormatError({(p / "permissions.p7s").string(), 0, 0, "subject_name"},
                             "the grant is not for this participant's certificate (" + subject + ")");

  dds::SecurityFiles f;
  f.identity_ca = k.identity_ca().string();
  f.identity_certificate = (p / "cert.pem").string();
  f.private_key = (p / "key.pem").string();
  f.permissions_ca = k.permissions_ca().string();
  f.governance = k.governance().string();
  f.permissions = (p / "permissions.p7s").string();
  return f;
}

}  // namespace hil::keystore
