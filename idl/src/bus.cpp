#include "hil/dds/bus.hpp"

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <thread>

namespace hil::dds {
using namespace eprosima::fastdds::dds;

std::string default_profile_path() {
  if (const char* env = std::getenv("HIL_DDS_PROFILE"); env && *env) return env;
  if (std::filesystem::exists(HIL_DDS_PROFILE_INSTALLED)) return HIL_DDS_PROFILE_INSTALLED;
  return HIL_DDS_PROFILE_SOURCE;
}

int domain_from_env(int fallback) {
  if (const char* env = std::getenv("HIL_DDS_DOMAIN"); env && *env) {
    char* end = nullptr;
    const long d = std::strtol(env, &end, 10);
    if (*end != '\0' || d < 0 || d > 232) throw std::runtime_error(std::string("HIL_DDS_DOMAIN: expected 0..232, found '") + env + "'");
    return static_cast<int>(d);
  }
  return fallback;
}

Participant::Participant(const ParticipantOptions& o) : domain_id_(o.domain_id) {
  auto* factory = DomainParticipantFactory::get_instance();
  const std::string file = o.profile_file.empty() ? default_profile_path() : o.profile_file;
  if (!std::filesystem::exists(file)) throw std::runtime_error("DDS profile file not found: " + file);
  if (factory->load_XML_profiles_file(file) != ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("DDS profile file could not be loaded (XML error?): " + file);
  DomainParticipantQos qos;
  if (factory->get_participant_qos_from_profile(o.profile_name, qos) != ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("DDS profile '" + o.profile_name + "' not found in " + file);
  qos.name(o.name);
  // The participant listener must not take data events: with them in its mask Fast DDS routes
  // data to the participant's (empty) on_data_on_readers and the readers' callbacks never run.
  StatusMask mask = StatusMask::all();
  mask >> StatusMask::data_on_readers() >> StatusMask::data_available();
  participant_ = factory->create_participant(static_cast<DomainId_t>(o.domain_id), qos, o.listener, mask);
  if (!participant_) throw std::runtime_error("DDS: cannot create a participant in domain " + std::to_string(o.domain_id));
  publisher_ = participant_->create_publisher(PUBLISHER_QOS_DEFAULT);
  subscriber_ = participant_->create_subscriber(SUBSCRIBER_QOS_DEFAULT);
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
  if (q.durable_depth > 0) qos.durability().kind = TRANSIENT_LOCAL_DURABILITY_QOS;
  return qos;
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
