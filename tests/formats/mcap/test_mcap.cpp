// MCAP codec and hil recording: round trips for every record kind and compression, CRCs, corrupt
// files refused with file + offset + what, and the export of the shipped run.
#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include <hil/error/error.hpp>
#include <hil/format/ros_frames.hpp>
#include <hil/format/run.hpp>
#include <hil/mcap/mcap.hpp>
#include <hil/dds/qos.hpp>
#include <hil/mcap/recording.hpp>
#include <hil/test/files.hpp>

namespace fs = std::filesystem;
using hil::error::FormatError;
using testing::HasSubstr;
using testing::ThrowsMessage;
using namespace hil::mcap;

namespace {

fs::path temp_dir() { return fs::temp_directory_path() / ("hil-test-mcap-" + std::to_string(::getpid())); }

std::string temp_path(const std::string& name) {
  fs::create_directories(temp_dir());
  return (temp_dir() / name).string();
}

// The files written here go when the tests end.
class TempCleanup : public ::testing::Environment {
 public:
  void TearDown() override { fs::remove_all(temp_dir()); }
};
const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new TempCleanup);

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A file with two schemas, three channels (one with metadata, one with no messages), 23
// messages in chunks of 5, out-of-order log times within a chunk.
std::string write_sample_file(Compression c, const std::string& name) {
  const auto path = temp_path(name);
  WriterOptions o;
  o.compression = c;
  o.chunk_messages = 5;
  o.profile = "test-profile";
  o.library = "hil-test-lib";
  Writer w(path, o);
  const auto s1 = w.add_schema("pkg/msg/A", "ros2msg", "float64 x\n");
  const auto s2 = w.add_schema("pkg/msg/B", "ros2msg", std::string("bytes\0with nul", 14));
  EXPECT_EQ(s1, 1);
  EXPECT_EQ(s2, 2);
  const auto a = w.add_channel(s1, "/a", "cdr", {{"offered_qos_profiles", ""}, {"k", "v"}});
  const auto b = w.add_channel(s2, "/b", "cdr");
  const auto e = w.add_channel(s1, "/empty", "cdr");
  EXPECT_EQ(e, 2);
  for (std::uint32_t i = 0; i < 23; ++i) {
    const std::uint64_t t = 1'000'000'000ull + (i % 5 == 3 ? i * 100 - 150 : i * 100);
    w.write({i % 3 == 0 ? b : a, i, t, t + 7, "PAYLOAD-" + std::to_string(i)});
  }
  w.close();
  return path;
}

class RoundTrip : public ::testing::TestWithParam<Compression> {};

TEST_P(RoundTrip, EveryRecordKindReadsBack) {
  const auto c = GetParam();
  const auto path = write_sample_file(c, std::string("rt-") + record_name(c) + ".mcap");
  const auto f = read_file(path);
  EXPECT_EQ(f.header.profile, "test-profile");
  EXPECT_EQ(f.header.library, "hil-test-lib");
  ASSERT_EQ(f.schemas.size(), 2u);
  EXPECT_EQ(f.schemas[1].name, "pkg/msg/B");
  EXPECT_EQ(f.schemas[1].data, std::string("bytes\0with nul", 14));
  ASSERT_EQ(f.channels.size(), 3u);
  EXPECT_EQ(f.channels[0].topic, "/a");
  EXPECT_EQ(f.channels[0].metadata.at("k"), "v");
  EXPECT_EQ(f.channels[0].metadata.count("offered_qos_profiles"), 1u);
  EXPECT_EQ(f.channels[1].schema_id, 2);
  ASSERT_EQ(f.messages.size(), 23u);
  for (std::uint32_t i = 0; i < 23; ++i) {
    const auto& m = f.messages[i];
    EXPECT_EQ(m.sequence, i);
    EXPECT_EQ(m.channel_id, i % 3 == 0 ? 1 : 0);
    EXPECT_EQ(m.publish_time_ns, m.log_time_ns + 7);
    EXPECT_EQ(m.data, "PAYLOAD-" + std::to_string(i));
  }
  // 5 chunks (5+5+5+5+3), each with its compression, message indexes and chunk index.
  ASSERT_EQ(f.chunks.size(), 5u);
  for (const auto& ch : f.chunks) {
    EXPECT_EQ(ch.compression, record_name(c));
    EXPECT_NE(ch.uncompressed_crc, 0u);
    EXPECT_LE(ch.message_start_time_ns, ch.message_end_time_ns);
  }
  if (c != Compression::none) {
    EXPECT_NE(f.chunks[0].compressed_size, f.chunks[0].uncompressed_size);
  }
  EXPECT_EQ(f.chunks[0].message_start_time_ns, 1'000'000'000ull);  // message 3 is earlier than 4 but not than 0
  EXPECT_EQ(f.chunks[1].message_start_time_ns, 1'000'000'000ull + 500);
  EXPECT_EQ(f.chunks[1].message_end_time_ns, 1'000'000'000ull + 900);
  std::size_t index_entries = 0;
  for (const auto& mi : f.message_indexes) index_entries += mi.entries.size();
  EXPECT_EQ(index_entries, 23u);
  EXPECT_EQ(f.message_indexes.size(), 10u);  // both channels in every chunk
  ASSERT_EQ(f.chunk_indexes.size(), 5u);
  EXPECT_EQ(f.chunk_indexes[2].chunk_start_offset, f.chunks[2].offset);
  EXPECT_EQ(f.chunk_indexes[2].message_index_offsets.size(), 2u);
  // Summary: schemas, channels, statistics, chunk indexes; one summary offset per group.
  EXPECT_EQ(f.summary_schemas.size(), 2u);
  EXPECT_EQ(f.summary_channels.size(), 3u);
  ASSERT_TRUE(f.statistics.has_value());
  EXPECT_EQ(f.statistics->message_count, 23u);
  EXPECT_EQ(f.statistics->schema_count, 2);
  EXPECT_EQ(f.statistics->channel_count, 3u);
  EXPECT_EQ(f.statistics->chunk_count, 5u);
  EXPECT_EQ(f.statistics->channel_message_counts.at(1), 8u);
  EXPECT_EQ(f.statistics->channel_message_counts.at(0), 15u);
  EXPECT_EQ(f.statistics->channel_message_counts.count(2), 0u);
  EXPECT_EQ(f.statistics->message_start_time_ns, 1'000'000'000ull);
  EXPECT_EQ(f.statistics->message_end_time_ns, 1'000'000'000ull + 2200);
  ASSERT_EQ(f.summary_offsets.size(), 4u);
  EXPECT_EQ(f.summary_offsets[0].group_opcode, static_cast<std::uint8_t>(Opcode::schema));
  EXPECT_EQ(f.summary_offsets[3].group_opcode, static_cast<std::uint8_t>(Opcode::chunk_index));
  EXPECT_NE(f.data_section_crc, 0u);
  EXPECT_NE(f.footer.summary_crc, 0u);
  EXPECT_EQ(f.footer.summary_start, f.summary_offsets[0].group_start);
  EXPECT_EQ(f.messages_on("/b").size(), 8u);
  EXPECT_TRUE(f.messages_on("/empty").empty());
}

INSTANTIATE_TEST_SUITE_P(Compressions, RoundTrip, ::testing::Values(Compression::none, Compression::zstd, Compression::lz4),
                         [](const auto& p) { return std::string(p.param == Compression::none ? "none" : record_name(p.param)); });

TEST(Mcap, FileWithoutMessagesReads) {
  const auto path = temp_path("empty.mcap");
  {
    Writer w(path, {});
    w.add_channel(w.add_schema("pkg/msg/A", "ros2msg", "int32 a\n"), "/a", "cdr");
  }  // the destructor closes
  const auto f = read_file(path);
  EXPECT_TRUE(f.messages.empty());
  EXPECT_TRUE(f.chunks.empty());
  ASSERT_TRUE(f.statistics);
  EXPECT_EQ(f.statistics->message_count, 0u);
  EXPECT_EQ(f.channels.size(), 1u);
}

TEST(Mcap, WriterRefusesUnknownChannelAndCompression) {
  Writer w(temp_path("refuse.mcap"), {});
  EXPECT_THAT([&] { w.write({3, 0, 0, 0, "x"}); }, ThrowsMessage<std::invalid_argument>(HasSubstr("unknown channel id 3")));
  EXPECT_THAT([&] { w.add_channel(9, "/x", "cdr"); }, ThrowsMessage<std::invalid_argument>(HasSubstr("unknown schema id 9")));
  EXPECT_THAT([] { parse_compression("gzip"); },
              ThrowsMessage<std::invalid_argument>(HasSubstr("unknown compression 'gzip' (expected none, zstd or lz4)")));
  EXPECT_EQ(parse_compression("none"), Compression::none);
}

TEST(Mcap, Crc32IsTheIsoHdlcOne) {
  EXPECT_EQ(crc32("123456789", 9), 0xCBF43926u);  // the standard check value
}

// ---- corrupt files ---------------------------------------------------------------------------

void expect_refused(const std::string& bytes, const std::string& name, const std::string& what) {
  try {
    read_bytes(bytes, name);
    ADD_FAILURE() << "accepted a corrupt file, expected: " << what;
  } catch (const FormatError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(name), std::string::npos) << msg;
    EXPECT_NE(msg.find("offset "), std::string::npos) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << msg;
  }
}

std::size_t find_once(const std::string& hay, const std::string& needle) {
  const auto p = hay.find(needle);
  EXPECT_NE(p, std::string::npos) << needle;
  return p;
}

TEST(McapCorrupt, BadMagic) {
  auto b = slurp(write_sample_file(Compression::none, "magic.mcap"));
  b[1] = 'X';
  expect_refused(b, "magic.mcap", "bad magic");
  expect_refused("", "empty.mcap", "bad magic");
  auto c = slurp(write_sample_file(Compression::none, "magic2.mcap"));
  c[c.size() - 2] = '?';
  expect_refused(c, "magic2.mcap", "bad closing magic");
}

TEST(McapCorrupt, ChunkCrcMismatchIsDetected) {
  auto b = slurp(write_sample_file(Compression::none, "crc.mcap"));
  b[find_once(b, "PAYLOAD-7") + 3] = 'X';
  expect_refused(b, "crc.mcap", "CRC mismatch of its records");
}

TEST(McapCorrupt, DataSectionCrcMismatchIsDetected) {
  auto b = slurp(write_sample_file(Compression::zstd, "datacrc.mcap"));
  b[find_once(b, "hil-test-lib")] = 'X';  // the header: covered by the data-section CRC only
  expect_refused(b, "datacrc.mcap", "CRC mismatch of the data section");
}

TEST(McapCorrupt, SummaryCrcMismatchIsDetected) {
  auto b = slurp(write_sample_file(Compression::zstd, "sumcrc.mcap"));
  b[b.rfind("/empty") + 1] = 'X';  // the summary's copy of a channel
  expect_refused(b, "sumcrc.mcap", "CRC mismatch of the summary");
}

TEST(McapCorrupt, TruncatedFiles) {
  const auto b = slurp(write_sample_file(Compression::lz4, "trunc.mcap"));
  expect_refused(b.substr(0, b.size() - 4), "trunc.mcap", "closing magic is missing");
  expect_refused(b.substr(0, b.size() - 20), "trunc.mcap", "runs past the end of the file");
  expect_refused(b.substr(0, b.size() / 2), "trunc.mcap", "runs past the end of the file");
  expect_refused(b.substr(0, 12), "trunc.mcap", "truncated record header");
}

TEST(McapCorrupt, RecordLengthPastTheEnd) {
  auto b = slurp(write_sample_file(Compression::none, "len.mcap"));
  b[8 + 1 + 6] = '\x01';  // the Header's length, byte 6: ~2^48
  expect_refused(b, "len.mcap", "Header record of");
}

TEST(McapCorrupt, UnknownCompression) {
  auto b = slurp(write_sample_file(Compression::zstd, "comp.mcap"));
  b.replace(find_once(b, "zstd"), 4, "brot");
  expect_refused(b, "comp.mcap", "unknown compression 'brot'");
}

TEST(McapCorrupt, CompressedDataThatDoesNotDecompress) {
  for (const auto c : {Compression::zstd, Compression::lz4}) {
    auto b = slurp(write_sample_file(c, "bits.mcap"));
    const auto at = find_once(b, record_name(c)) + 4 + 8 + 6;  // inside the compressed records
    b[at] = static_cast<char>(b[at] ^ 0x5A);
    try {
      read_bytes(b, "bits.mcap");
      ADD_FAILURE() << "accepted corrupt " << record_name(c) << " data";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find("bits.mcap: offset "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("Chunk"), std::string::npos) << e.what();
    }
  }
}

TEST(McapCorrupt, AChunkClaimingMoreThanItsDataCanHoldIsRefusedBeforeAllocating) {
  // Found by fuzz_mcap: the chunk's uncompressed size was allocated before decompressing.
  for (const auto c : {Compression::zstd, Compression::lz4}) {
    auto b = slurp(write_sample_file(c, "huge.mcap"));
    const auto size_at = find_once(b, record_name(c)) - 4 - 4 - 8;  // uncompressed_size, crc, the name's length
    const std::uint64_t claim = std::uint64_t{1} << 33;             // 8 GiB
    for (int i = 0; i < 8; ++i) b[size_at + static_cast<std::size_t>(i)] = static_cast<char>((claim >> (8 * i)) & 0xFF);
    expect_refused(b, "huge.mcap", "uncompressed size 8589934592 is more than");
  }
}

// ---- recovery of a file that was not closed ---------------------------------------------------

void expect_same_message(const Message& a, const Message& b, const std::string& where) {
  EXPECT_EQ(a.channel_id, b.channel_id) << where;
  EXPECT_EQ(a.sequence, b.sequence) << where;
  EXPECT_EQ(a.log_time_ns, b.log_time_ns) << where;
  EXPECT_EQ(a.data, b.data) << where;
}

TEST(McapRecovery, EveryCutKeepsTheWholeChunksBeforeItAndNothingElse) {
  for (const auto c : {Compression::none, Compression::zstd, Compression::lz4}) {
    const auto b = slurp(write_sample_file(c, std::string("cut-") + record_name(c) + ".mcap"));
    const auto full = read_bytes(b, "full.mcap");
    const auto header_end = find_once(b, "hil-test-lib") + 12;  // magic, then the Header record
    std::size_t previous = 0;
    for (std::size_t cut = 0; cut <= b.size(); ++cut) {
      const auto where = std::string(record_name(c)) + " cut at " + std::to_string(cut) + " of " + std::to_string(b.size());
      Recovery r;
      if (cut < header_end) {
        EXPECT_THROW(recover_bytes(b.substr(0, cut), "cut.mcap", r), FormatError) << where;
        continue;
      }
      const auto f = recover_bytes(b.substr(0, cut), "cut.mcap", r);
      EXPECT_EQ(r.complete, cut == b.size()) << where;
      EXPECT_EQ(r.bytes_total, cut) << where;
      EXPECT_LE(r.bytes_read, cut) << where;
      EXPECT_EQ(r.messages, f.messages.size()) << where;
      EXPECT_EQ(r.stopped.empty(), r.complete) << where;
      // Whole chunks of 5 messages (the last holds 3), a prefix of the file's, never fewer as the cut grows.
      ASSERT_LE(f.messages.size(), full.messages.size()) << where;
      EXPECT_TRUE(f.messages.size() % 5 == 0 || f.messages.size() == full.messages.size()) << where << ": " << f.messages.size();
      EXPECT_GE(f.messages.size(), previous) << where;
      previous = f.messages.size();
      for (std::size_t i = 0; i < f.messages.size(); ++i) expect_same_message(f.messages[i], full.messages[i], where);
    }
    EXPECT_EQ(previous, full.messages.size());
  }
}

TEST(McapRecovery, ACorruptChunkEndsTheRecoveryBeforeIt) {
  auto b = slurp(write_sample_file(Compression::none, "rcrc.mcap"));
  b[find_once(b, "PAYLOAD-7") + 3] = 'X';  // the second chunk (messages 5-9)
  Recovery r;
  const auto f = recover_bytes(b, "rcrc.mcap", r);
  EXPECT_FALSE(r.complete);
  EXPECT_EQ(f.messages.size(), 5u);
  EXPECT_EQ(r.chunks, 1u);
  EXPECT_NE(r.stopped.find("CRC mismatch of its records"), std::string::npos) << r.stopped;
  EXPECT_EQ(r.stopped.rfind("offset ", 0), 0u) << r.stopped;
}

TEST(McapRecovery, ARewrittenRecoveryIsACompleteFileWithTheSameRecords) {
  const auto b = slurp(write_sample_file(Compression::zstd, "rw.mcap"));
  const auto full = read_bytes(b, "rw.mcap");
  Recovery r;
  const auto part = recover_bytes(b.substr(0, b.size() * 3 / 4), "rw-cut.mcap", r);
  ASSERT_FALSE(r.complete);
  ASSERT_GT(part.messages.size(), 0u);
  const auto out = temp_path("rw-fixed.mcap");
  EXPECT_EQ(rewrite(part, out, Compression::lz4), part.messages.size());
  const auto fixed = read_file(out);  // strict: footer, summary, every CRC
  EXPECT_EQ(fixed.header.profile, "test-profile");
  ASSERT_EQ(fixed.schemas.size(), full.schemas.size());
  for (std::size_t i = 0; i < fixed.schemas.size(); ++i) EXPECT_EQ(fixed.schemas[i].data, full.schemas[i].data);
  ASSERT_EQ(fixed.channels.size(), full.channels.size());
  EXPECT_EQ(fixed.channels[0].metadata, full.channels[0].metadata);
  ASSERT_EQ(fixed.messages.size(), part.messages.size());
  for (std::size_t i = 0; i < fixed.messages.size(); ++i) {
    EXPECT_EQ(fixed.channels[fixed.messages[i].channel_id].topic, full.channels[full.messages[i].channel_id].topic) << i;
    EXPECT_EQ(fixed.messages[i].data, full.messages[i].data) << i;
    EXPECT_EQ(fixed.messages[i].log_time_ns, full.messages[i].log_time_ns) << i;
  }
}

// ---- hil recordings --------------------------------------------------------------------------

const std::string kRun = std::string(HIL_SOURCE_DIR) + "/examples/runs/press_slide";
const std::string kRig = std::string(HIL_SOURCE_DIR) + "/examples/rigs/press_bench.yaml";

TEST(Recording, SchemasAreRos2BagStyleWithTheHilMsgsPackageTexts) {
  const auto ws = ros2msg_schema("geometry_msgs/msg/WrenchStamped");
  EXPECT_EQ(ws.rfind("std_msgs/Header header\nWrench wrench\n"), ws.find("std_msgs/Header header"));
  for (const auto* dep :
       {"MSG: std_msgs/Header\n", "MSG: builtin_interfaces/Time\n", "MSG: geometry_msgs/Wrench\n", "MSG: geometry_msgs/Vector3\n"}) {
    const auto p = ws.find(dep);
    ASSERT_NE(p, std::string::npos) << dep;
    EXPECT_EQ(ws.substr(p - 82, 82), "\n" + std::string(80, '=') + "\n");
    EXPECT_EQ(ws.find(dep, p + 1), std::string::npos) << "twice: " << dep;
  }
  const auto pws = ros2msg_schema("hil_msgs/msg/PoseWrenchSample");
  const auto msg = slurp(std::string(HIL_SOURCE_DIR) + "/ros/hil_msgs/msg/PoseWrenchSample.msg");
  ASSERT_FALSE(msg.empty());
  EXPECT_EQ(pws.substr(0, msg.size()), msg);
  EXPECT_NE(pws.find("MSG: geometry_msgs/Twist\n"), std::string::npos);
  const auto ds = ros2msg_schema("hil_msgs/msg/DeviceStatus");
  EXPECT_EQ(ds.substr(0, ds.find("\n=====")), slurp(std::string(HIL_SOURCE_DIR) + "/ros/hil_msgs/msg/DeviceStatus.msg"));
  EXPECT_NE(ros2msg_schema("tf2_msgs/msg/TFMessage").find("MSG: geometry_msgs/Transform\n"), std::string::npos);
  EXPECT_THAT([] { ros2msg_schema("nav_msgs/msg/Odometry"); },
              ThrowsMessage<std::invalid_argument>(HasSubstr("no ros2msg definition for nav_msgs/msg/Odometry")));
}

TEST(Recording, UtcTimes) {
  EXPECT_EQ(parse_utc_ns("1970-01-01T00:00:01.5Z"), 1'500'000'000);
  EXPECT_EQ(parse_utc_ns("2026-11-21T09:00:00.000Z") - parse_utc_ns("2026-11-21T08:59:59Z"), 1'000'000'000);
  EXPECT_THAT([] { parse_utc_ns("2026-11-21 09:00:00"); },
              ThrowsMessage<std::invalid_argument>(HasSubstr("not an ISO 8601 UTC time: '2026-11-21 09:00:00'")));
  const auto t = to_ros_time(1'700'000'000'123'456'789);
  EXPECT_EQ(t.sec(), 1'700'000'000);
  EXPECT_EQ(t.nanosec(), 123'456'789u);
}

class ExportPressSlide : public ::testing::TestWithParam<Compression> {};

TEST_P(ExportPressSlide, ChannelsCountsAndValues) {
  const auto run = hil::format::load_run(kRun, kRig);
  const auto out = temp_path(std::string("press_slide-") + (GetParam() == Compression::none ? "none" : record_name(GetParam())) + ".mcap");
  RecordingOptions o;
  o.compression = GetParam();
  o.chunk_size_bytes = 16 * 1024;  // several chunks
  export_run(run, out, o);
  const auto f = read_file(out);
  const auto n = run.samples.size();
  ASSERT_GT(n, 10u);
  EXPECT_EQ(f.header.profile, "ros2");
  EXPECT_GT(f.chunks.size(), 1u);
  for (const auto& ch : f.channels) {
    EXPECT_EQ(ch.message_encoding, "cdr") << ch.topic;
    // The ros2 profile requires the QoS: the live writer's, from the one table (/tf_static latched,
    // durability 1; the rest volatile, 2; keep last N: history 1, depth N).
    const auto q = hil::dds::qos_of("rt" + ch.topic);
    const auto& offered = ch.metadata.at("offered_qos_profiles");
    EXPECT_NE(offered.find(q.durable_depth > 0 ? "durability: 1\n" : "durability: 2\n"), std::string::npos) << ch.topic;
    EXPECT_NE(offered.find("- history: 1\n  depth: " + std::to_string(q.history_depth) + "\n  reliability: 1\n"), std::string::npos)
        << ch.topic << ":\n"
        << offered;
    EXPECT_EQ(f.schema(ch.schema_id)->encoding, "ros2msg") << ch.topic;
  }
  EXPECT_EQ(f.schema(f.channel(topic::kWrench)->schema_id)->name, "geometry_msgs/msg/WrenchStamped");
  EXPECT_EQ(f.schema(f.channel(topic::kTfStatic)->schema_id)->name, "tf2_msgs/msg/TFMessage");
  EXPECT_EQ(f.messages_on(topic::kWrench).size(), n);
  EXPECT_EQ(f.messages_on(topic::kPose).size(), n);
  EXPECT_EQ(f.messages_on(topic::kPoseWrench).size(), n);
  EXPECT_EQ(f.messages_on(topic::kJointStates).size(), 0u);  // press_slide has no joint columns
  ASSERT_NE(f.channel(topic::kDeviceStatus), nullptr);       // declared, no record of it in a run
  EXPECT_EQ(f.messages_on(topic::kDeviceStatus).size(), 0u);
  ASSERT_EQ(f.messages_on(topic::kTfStatic).size(), 1u);
  EXPECT_EQ(f.messages_on(topic::kTf).size(), n);  // the moving robot base -> ee, one per sample
  ASSERT_TRUE(f.statistics);
  EXPECT_EQ(f.statistics->message_count, 4 * n + 1);

  const auto start_ns = parse_utc_ns(run.info.start_time_utc);
  const auto samples = read_pose_wrench(f);
  ASSERT_EQ(samples.size(), n);
  const auto wrenches = f.messages_on(topic::kWrench);
  for (std::size_t i = 0; i < n; i += 7) {
    const auto& s = run.samples.samples[i];
    const auto& m = samples[i];
    EXPECT_EQ(m.sample_index(), i);
    EXPECT_EQ(m.t_s(), s.t_s);
    EXPECT_EQ(m.pose_world_ee().position().x(), s.p_world_ee_m.x());
    EXPECT_EQ(m.pose_world_ee().position().z(), s.p_world_ee_m.z());
    EXPECT_EQ(m.pose_world_ee().orientation().w(), s.q_world_ee.w());
    EXPECT_EQ(m.wrench_fp().force().x(), s.f_fp_n.x());
    EXPECT_EQ(m.wrench_fp().torque().z(), s.m_fp_nm.z());
    EXPECT_EQ(m.twist_world_ee().linear().z(), s.v_world_ee_m_per_s.z());
    const auto t_ns = static_cast<std::uint64_t>(start_ns + std::llround(s.t_s * 1e9));
    EXPECT_EQ(wrenches[i]->log_time_ns, t_ns);
    EXPECT_EQ(wrenches[i]->publish_time_ns, t_ns);
    geometry_msgs::msg::WrenchStamped w;
    from_cdr(wrenches[i]->data, w, "test");
    EXPECT_EQ(w.header().frame_id(), "force_plate");
    EXPECT_EQ(w.wrench().force().z(), s.f_fp_n.z());
    EXPECT_EQ(static_cast<std::int64_t>(w.header().stamp().sec()) * 1'000'000'000 + w.header().stamp().nanosec(),
              static_cast<std::int64_t>(t_ns));
    EXPECT_EQ(wrenches[i]->data.substr(0, 4), std::string("\x00\x01\x00\x00", 4));  // CDR, little endian
  }
  const auto tf = tf_message_from_cdr(f.messages_on(topic::kTfStatic)[0]->data, "test");
  const auto expected = hil::format::static_frames(*run.rig);
  ASSERT_EQ(tf.size(), expected.size());
  ASSERT_GE(tf.size(), 3u);  // force_plate, object2, object1, robot_base
  for (std::size_t i = 0; i < tf.size(); ++i) {
    EXPECT_EQ(tf[i].parent, expected[i].parent);
    EXPECT_EQ(tf[i].child, expected[i].child);
    EXPECT_TRUE(tf[i].T_parent_child.translation_m.isApprox(expected[i].T_parent_child.translation_m)) << tf[i].child;
  }
  EXPECT_EQ(f.messages_on(topic::kTfStatic)[0]->log_time_ns, static_cast<std::uint64_t>(start_ns));
}

INSTANTIATE_TEST_SUITE_P(Compressions, ExportPressSlide, ::testing::Values(Compression::none, Compression::zstd, Compression::lz4),
                         [](const auto& p) { return std::string(p.param == Compression::none ? "none" : record_name(p.param)); });

TEST(Recording, WithoutARigNoTfStaticAndJointsNamedJ1ToJn) {
  const auto out = temp_path("joints.mcap");
  {
    RunMcapWriter w(out, nullptr, 3, 1'000'000'000'000, {});
    hil::format::Sample s;
    const double q[3] = {0.1, -0.2, 0.3};
    for (int i = 0; i < 4; ++i) {
      s.t_s = 0.01 * i;
      s.f_fp_n.z() = -i;
      w.write_sample(s, static_cast<std::uint64_t>(i), q,
                     {.wrench_seq = 9, .pose_seq = 8, .wrench_age_s = 0.001, .pose_age_s = 0.002, .quality = 32});
    }
    hil_msgs::msg::DeviceStatus st;
    st.stamp(to_ros_time(1'000'000'000'050));
    st.device("robot");
    st.state(2);
    st.last_error("exception 4");
    w.write_status(st);
    w.close();
  }
  const auto f = read_file(out);
  EXPECT_EQ(f.messages_on(topic::kTfStatic).size(), 0u);
  ASSERT_NE(f.channel(topic::kTfStatic), nullptr);
  const auto js = f.messages_on(topic::kJointStates);
  ASSERT_EQ(js.size(), 4u);
  sensor_msgs::msg::JointState j;
  from_cdr(js[2]->data, j, "test");
  EXPECT_EQ(j.name(), (std::vector<std::string>{"j1", "j2", "j3"}));
  EXPECT_EQ(j.position(), (std::vector<double>{0.1, -0.2, 0.3}));
  EXPECT_EQ(js[2]->log_time_ns, 1'000'000'000'000ull + 20'000'000ull);
  const auto samples = read_pose_wrench(f);
  ASSERT_EQ(samples.size(), 4u);
  EXPECT_EQ(samples[3].quality_flags(), 32u);
  EXPECT_EQ(samples[3].wrench_seq(), 9u);
  EXPECT_EQ(samples[3].pose_age_s(), 0.002);
  EXPECT_EQ(samples[3].joint_positions_rad().size(), 3u);
  EXPECT_EQ(samples[3].wrench_fp().force().z(), -3.0);
  const auto st = f.messages_on(topic::kDeviceStatus);
  ASSERT_EQ(st.size(), 1u);
  EXPECT_EQ(st[0]->log_time_ns, 1'000'000'000'050ull);
  hil_msgs::msg::DeviceStatus d;
  from_cdr(st[0]->data, d, "test");
  EXPECT_EQ(d.device(), "robot");
  EXPECT_EQ(d.state(), 2);
  EXPECT_EQ(d.last_error(), "exception 4");
}

TEST(Recording, ReadPoseWrenchRefusesAFileWithoutTheChannel) {
  const auto path = write_sample_file(Compression::none, "nochannel.mcap");
  try {
    read_pose_wrench(read_file(path));
    ADD_FAILURE() << "accepted";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("no /hil/pose_wrench channel"), std::string::npos) << e.what();
  }
}

TEST(Recording, CorruptPayloadIsNamed) {
  hil_msgs::msg::PoseWrenchSample m;
  EXPECT_TRUE(hil::test::fails_with([&] { from_cdr(std::string("\x00\x01\x00\x00\x01", 5), m, "x.mcap: /hil/pose_wrench message 3"); }, 0,
                                    "", "x.mcap: /hil/pose_wrench message 3: CDR payload of 5 bytes does not decode"));
  EXPECT_TRUE(hil::test::fails_with([] { tf_message_from_cdr(std::string("\x00\x01\x00\x00\xff\xff\x00\x00", 8), "x"); }, 0, "",
                                    "x: CDR payload of 8 bytes does not decode"));
}

}  // namespace
