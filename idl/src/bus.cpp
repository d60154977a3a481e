#include <hil/dds/bus.hpp>

#include <hil/error/error.hpp>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <thread>

namespace hil::dds {
using namespace eprosima::fastdds::dds;

namespace {
// <prefix>/<datadir>/hil/dds_localhost.xml for a program in <prefix>/<bindir>: an installed tree
// that was moved, or installed with another --prefix than the one configured, still finds it.
std::filesystem::path profile_beside_program() {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path prefix = fs::read_symlink("/proc/self/exe", ec).parent_path();
  if (ec) return {};
  for (const auto& part : fs::path(HIL_INSTALL_BINDIR))
    if (!part.empty()) prefix = prefix.parent_path();
  return (prefix / HIL_INSTALL_DATADIR / "hil" / "dds_localhost.xml").lexically_normal();
}
}  // namespace

std::string default_profile_path() {
  if (const char* env = std::getenv("HIL_DDS_PROFILE"); env && *env) return env;
  std::error_code ec;
  if (const auto beside = profile_beside_program(); !beside.empty() && std::filesystem::exists(beside, ec)) return beside.string();
  if (std::filesystem::exists(HIL_DDS_PROFILE_INSTALLED, ec)) return HIL_DDS_PROFILE_INSTALLED;
  return HIL_DDS_PROFILE_SOURCE;
}

namespace {
int parse_domain(const char* variable, const char* value) {
  // 232: the largest id whose default RTPS ports (7400 + 250 * domain + offsets) fit in 16 bits,
  // the same limit ROS 2 documents for ROS_DOMAIN_ID.
  const std::string v(value);
  const bool digits = !v.empty() && v.size() <= 3 && std::all_of(v.begin(), v.end(), [](char c) { return c >= '0' && c <= '9'; });
  const int d = digits ? std::stoi(v) : -1;
  if (d < 0 || d > 232)
    throw error::FormatError({std::string("$") + variable, 0, 0, ""}, "expected a DDS domain id, an integer 0..232, found '" + v + "'");
  return d;
}
}  // namespace

int domain_from(const char* hil_dds_domain, const char* ros_domain_id, int fallback) {
  if (hil_dds_domain && *hil_dds_domain) return parse_domain("HIL_DDS_DOMAIN", hil_dds_domain);
  if (ros_domain_id && *ros_domain_id) return parse_domain("ROS_DOMAIN_ID", ros_domain_id);
  return fallback;
}

int domain_from_env(int fallback) { return domain_from(std::getenv("HIL_DDS_DOMAIN"), std::getenv("ROS_DOMAIN_ID"), fallback); }

int resolve_domain(int command_line, int fallback) { return command_line >= 0 ? command_line : domain_from_env(fallback); }

namespace {
// Fast DDS reads the files itself and only logs why it failed: check here, so the error names the file.
void check_readable(const std::string& path, const char* what) {
  std::error_code ec;
  if (path.empty() || !std::filesystem::is_regular_file(path, ec))
    throw error::FormatError({path.empty() ? std::string("DDS Security") : path, 0, 0, ""}, std::string(what) + " not found");
  if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
    std::fclose(f);
  } else {
    throw error::FormatError({path, 0, 0, ""}, std::string(what) + " not readable: " + std::strerror(errno));
  }
}

std::string file_uri(const std::string& path) { return "file://" + std::filesystem::absolute(path).lexically_normal().string(); }

void apply_security(const SecurityFiles& s, DomainParticipantQos& qos) {
  check_readable(s.identity_ca, "identity CA certificate");
  check_readable(s.identity_certificate, "participant certificate");
  check_readable(s.private_key, "participant private key");
  check_readable(s.permissions_ca, "permissions CA certificate");
  check_readable(s.governance, "governance document");
  check_readable(s.permissions, "permissions document");
  auto& props = qos.properties().properties();
  const auto set = [&](const std::string& name, const std::string& value) {
    for (auto& p : props)
      if (p.name() == name) {
        p.value() = value;
        return;
      }
    props.emplace_back(name, value);
  };
  set("dds.sec.auth.plugin", "builtin.PKI-DH");
  set("dds.sec.auth.builtin.PKI-DH.identity_ca", file_uri(s.identity_ca));
  set("dds.sec.auth.builtin.PKI-DH.identity_certificate", file_uri(s.identity_certificate));
  set("dds.sec.auth.builtin.PKI-DH.private_key", file_uri(s.private_key));
  set("dds.sec.access.plugin", "builtin.Access-Permissions");
  set("dds.sec.access.builtin.Access-Permissions.permissions_ca", file_uri(s.permissions_ca));
  set("dds.sec.access.builtin.Access-Permissions.governance", file_uri(s.governance));
  set("dds.sec.access.builtin.Access-Permissions.permissions", file_uri(s.permissions));
  set("dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
}

bool has_security(const DomainParticipantQos& qos) {
  for (const auto& p : qos.properties().properties())
    if (p.name() == "dds.sec.auth.plugin") return true;
  return false;
}
}  // namespace

Participant::Participant(const ParticipantOptions& o) : domain_id_(o.domain_id) {
  auto* factory = DomainParticipantFactory::get_instance();
  const std::string file = o.profile_file.empty() ? default_profile_path() : o.profile_file;
  if (!std::filesystem::exists(file)) throw std::runtime_error("DDS profile file not found: " + file);
  spdlog::debug("DDS: profile '{}' from {}, domain {}", o.profile_name, file, o.domain_id);
  if (factory->load_XML_profiles_file(file) != ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("DDS profile file could not be loaded (XML error?): " + file);
  DomainParticipantQos qos;
  if (factory->get_participant_qos_from_profile(o.profile_name, qos) != ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("DDS profile '" + o.profile_name + "' not found in " + file);
  qos.name(o.name);
  if (o.security.enabled()) apply_security(o.security, qos);
  secure_ = has_security(qos);
  // The participant listener must not take data events: with them in its mask Fast DDS routes
  // data to the participant's (empty) on_data_on_readers and the readers' callbacks never run.
  StatusMask mask = StatusMask::all();
  mask >> StatusMask::data_on_readers() >> StatusMask::data_available();
  participant_ = factory->create_participant(static_cast<DomainId_t>(o.domain_id), qos, o.listener, mask);
  if (!participant_ && secure_)
    throw std::runtime_error("DDS Security refused to create the participant in domain " + std::to_string(o.domain_id) +
                             (o.security.enabled()
                                  ? " with certificate " + o.security.identity_certificate + " and permissions " + o.security.permissions
                                  : std::string(" (security properties of profile '") + o.profile_name + "')") +
                             " (Fast DDS logs why)");
  if (!participant_) throw std::runtime_error("DDS: cannot create a participant in domain " + std::to_string(o.domain_id));
  PublisherQos pub_qos = PUBLISHER_QOS_DEFAULT;
  SubscriberQos sub_qos = SUBSCRIBER_QOS_DEFAULT;
  if (!o.partition.empty()) {
    pub_qos.partition().push_back(o.partition.c_str());
    sub_qos.partition().push_back(o.partition.c_str());
  }
  publisher_ = participant_->create_publisher(pub_qos);
  subscriber_ = participant_->create_subscriber(sub_qos);
  if (!publisher_ || !subscriber_) {
    factory->delete_participant(participant_);
    throw std::runtime_error("DDS: cannot create publisher/subscriber");
  }
}

Participant::~Participant() {
  if (!participant_) return;
  participant_->delete_contained_entities();
  DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

Topic* Participant::topic(const std::string& name, TypeSupport type) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (auto it = topics_.find(name); it != topics_.end()) {
    if (it->second->get_type_name() != type.get_type_name())
      throw std::runtime_error("DDS: topic " + name + " already carries " + it->second->get_type_name());
    return it->second;
  }
  if (participant_->find_type(type.get_type_name()) == nullptr) type.register_type(participant_);
  Topic* t = participant_->create_topic(name, type.get_type_name(), TOPIC_QOS_DEFAULT);
  if (!t) throw std::runtime_error("DDS: cannot create topic " + name);
  topics_[name] = t;
  return t;
}

namespace detail {

DataWriterQos writer_qos(const Participant& p, const StreamQos& q) {
  DataWriterQos qos = p.publisher()->get_default_datawriter_qos();
  qos.reliability().kind = q.reliable ? RELIABLE_RELIABILITY_QOS : BEST_EFFORT_RELIABILITY_QOS;
  if (q.history_depth == 0) {
    qos.history().kind = KEEP_ALL_HISTORY_QOS;
  } else {
    qos.history().kind = KEEP_LAST_HISTORY_QOS;
    qos.history().depth = q.history_depth;
  }
  if (q.durable_depth > 0) {
    qos.durability().kind = TRANSIENT_LOCAL_DURABILITY_QOS;
    if (q.history_depth == 0) {
      qos.history().kind = KEEP_LAST_HISTORY_QOS;
      qos.history().depth = q.durable_depth;
    }
  } else {
    // Fast DDS's default writer is transient-local: a late transient-local reader (a bag recorder
    // adapting to the publisher) would get up to the history depth of old samples as new.
    qos.durability().kind = VOLATILE_DURABILITY_QOS;
  }
  // Keep-all writers block rather than drop when readers lag; bound the wait.
  qos.reliability().max_blocking_time = eprosima::fastrtps::Duration_t(1.0);
  return qos;
}

DataReaderQos reader_qos(const Participant& p, const StreamQos& q) {
  DataReaderQos qos = p.subscriber()->get_default_datareader_qos();
  qos.reliability().kind = q.reliable ? RELIABLE_RELIABILITY_QOS : BEST_EFFORT_RELIABILITY_QOS;
  if (q.history_depth == 0) {
    qos.history().kind = KEEP_ALL_HISTORY_QOS;
  } else {
    qos.history().kind = KEEP_LAST_HISTORY_QOS;
    qos.history().depth = q.history_depth;
  }
  qos.durability().kind = q.durable_depth > 0 ? TRANSIENT_LOCAL_DURABILITY_QOS : VOLATILE_DURABILITY_QOS;
  return qos;
}

std::string refused(const Participant& p, const char* what, const std::string& topic) {
  std::string m = std::string("DDS: cannot create a ") + what + " on " + topic;
  if (p.secure())
    m += std::string(" (DDS Security: this participant's permissions do not allow ") +
         (std::string(what) == "writer" ? "publishing" : "subscribing to") + " it)";
  return m;
}

bool wait_matched(const std::function<int()>& count, int n, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (count() < n) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

}  // namespace detail
}  // namespace hil::dds
