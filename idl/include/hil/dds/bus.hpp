#pragma once
/// \file RAII wrappers over Fast DDS: one participant per process, typed writers and readers.
/// Every entity created here is deleted in the destructor of the object that created it.
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include <hil/dds/types.hpp>

namespace hil::dds {

/// DDS Security (docs/security.md): one participant's identity and permissions, as file paths.
/// All empty: no security beyond what the profile sets.
struct SecurityFiles {
  std::string identity_ca;           ///< CA that signed every participant's certificate
  std::string identity_certificate;  ///< this participant's certificate (PEM)
  std::string private_key;           ///< its private key (PEM)
  std::string permissions_ca;        ///< CA that signed governance and permissions
  std::string governance;            ///< signed governance document (S/MIME)
  std::string permissions;           ///< this participant's signed permissions (S/MIME)
  bool enabled() const { return !identity_certificate.empty(); }
};

struct ParticipantOptions {
  int domain_id = 0;
  /// XML profile file; empty = hil's host-only profile (default_profile_path()).
  std::string profile_file;
  /// Participant profile inside the file.
  std::string profile_name = "hil_localhost";
  std::string name = "hil";
  /// Not owned; must outlive the participant. Sees discovery of other participants.
  eprosima::fastdds::dds::DomainParticipantListener* listener = nullptr;
  /// When enabled: authentication, access control and encryption with these files.
  SecurityFiles security{};
  /// A DDS partition for every writer and reader: only participants in the same partition
  /// exchange data (a run kept apart from others on the same domain). Empty: none, as ROS 2 nodes
  /// use, so they match.
  std::string partition{};
};

/// The host-only profile: $HIL_DDS_PROFILE if set, else the installed copy, else the source tree's.
std::string default_profile_path();

/// The DDS domain id: $HIL_DDS_DOMAIN (hil's own variable wins), else $ROS_DOMAIN_ID (so hil
/// joins the ROS 2 nodes of the same shell), else `fallback`. An empty variable counts as unset.
/// \throws error::FormatError naming the variable when its value is not an integer 0..232.
int domain_from_env(int fallback = 0);
/// The same precedence on given values (null or empty = unset); pure, for tests.
int domain_from(const char* hil_dds_domain, const char* ros_domain_id, int fallback = 0);
/// `command_line` (--dds-domain) when >= 0, else domain_from_env(fallback).
int resolve_domain(int command_line, int fallback = 0);

/// One DDS domain participant. Not copyable; topics are shared by the writers and readers made from it.
class Participant {
 public:
  /// \throws std::runtime_error if the profile cannot be loaded or the participant not created.
  explicit Participant(const ParticipantOptions& options = {});
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  eprosima::fastdds::dds::DomainParticipant* get() const { return participant_; }
  eprosima::fastdds::dds::Publisher* publisher() const { return publisher_; }
  eprosima::fastdds::dds::Subscriber* subscriber() const { return subscriber_; }
  int domain_id() const { return domain_id_; }
  /// True when this participant runs with DDS Security (its permissions decide what it may do).
  bool secure() const { return secure_; }

  /// Registers the type if needed and returns the topic (one per name).
  eprosima::fastdds::dds::Topic* topic(const std::string& name, eprosima::fastdds::dds::TypeSupport type);

 private:
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
  std::map<std::string, eprosima::fastdds::dds::Topic*> topics_;
  std::mutex mutex_;
  int domain_id_ = 0;
  bool secure_ = false;
};

/// Quality of service for a stream.
struct StreamQos {
  bool reliable = true;
  /// 0 = keep all (reliable streams lose nothing while the reader keeps up); else keep last N.
  int history_depth = 0;
  /// Late-joining readers get the last N samples (transient local) when > 0.
  int durable_depth = 0;
};

namespace detail {
eprosima::fastdds::dds::DataWriterQos writer_qos(const Participant& p, const StreamQos& q);
eprosima::fastdds::dds::DataReaderQos reader_qos(const Participant& p, const StreamQos& q);
bool wait_matched(const std::function<int()>& count, int n, std::chrono::milliseconds timeout);
/// Why a writer or reader could not be made: with security, most likely its permissions.
std::string refused(const Participant& p, const char* what, const std::string& topic);
}  // namespace detail

/// Publishes messages of type Msg on one topic.
template <class Msg>
class Writer {
 public:
  Writer(Participant& p, const std::string& topic, const StreamQos& qos = {}) : p_(p) {
    eprosima::fastdds::dds::TypeSupport ts(new typename TypeSupportOf<Msg>::type());
    writer_ = p.publisher()->create_datawriter(p.topic(topic, ts), detail::writer_qos(p, qos));
    if (!writer_) throw std::runtime_error(detail::refused(p, "writer", topic));
  }
  ~Writer() { p_.publisher()->delete_datawriter(writer_); }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// Returns false if DDS refused the sample (e.g. history full past the blocking time).
  bool write(const Msg& m) { return writer_->write(const_cast<Msg*>(&m)); }
  int matched() const {
    eprosima::fastdds::dds::PublicationMatchedStatus s;
    writer_->get_publication_matched_status(s);
    return s.current_count;
  }
  bool wait_for_readers(int n, std::chrono::milliseconds timeout) {
    return detail::wait_matched([this] { return matched(); }, n, timeout);
  }
  /// Blocks until every reader acknowledged what was written (reliable streams).
  bool wait_for_acknowledgments(std::chrono::milliseconds timeout) {
    return writer_->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(static_cast<double>(timeout.count()) / 1e3)) ==
           ReturnCode_t::RETCODE_OK;
  }

 private:
  Participant& p_;
  eprosima::fastdds::dds::DataWriter* writer_ = nullptr;
};

/// Receives messages of type Msg on one topic and hands each to a callback on the DDS thread.
/// The callback must not throw (exceptions are caught and counted, never reach Fast DDS).
template <class Msg>
class Reader : private eprosima::fastdds::dds::DataReaderListener {
 public:
  using Callback = std::function<void(const Msg&, const eprosima::fastdds::dds::SampleInfo&)>;

  Reader(Participant& p, const std::string& topic, Callback cb, const StreamQos& qos = {}) : p_(p), cb_(std::move(cb)) {
    eprosima::fastdds::dds::TypeSupport ts(new typename TypeSupportOf<Msg>::type());
    reader_ = p.subscriber()->create_datareader(p.topic(topic, ts), detail::reader_qos(p, qos), this);
    if (!reader_) throw std::runtime_error(detail::refused(p, "reader", topic));
  }
  ~Reader() override {
    reader_->set_listener(nullptr);
    p_.subscriber()->delete_datareader(reader_);
  }
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  int matched() const {
    eprosima::fastdds::dds::SubscriptionMatchedStatus s;
    reader_->get_subscription_matched_status(s);
    return s.current_count;
  }
  bool wait_for_writers(int n, std::chrono::milliseconds timeout) {
    return detail::wait_matched([this] { return matched(); }, n, timeout);
  }
  std::uint64_t callback_errors() const { return errors_; }

 private:
  void on_data_available(eprosima::fastdds::dds::DataReader* r) override {
    Msg m;
    eprosima::fastdds::dds::SampleInfo info;
    while (r->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      try {
        cb_(m, info);
      } catch (...) {
        ++errors_;
      }
    }
  }

  Participant& p_;
  Callback cb_;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;
  std::atomic<std::uint64_t> errors_{0};
};

}  // namespace hil::dds
