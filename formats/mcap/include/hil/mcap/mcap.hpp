#pragma once
/// \file MCAP record codec (https://mcap.dev/spec): a chunked writer with message indexes, the
/// summary section and every CRC, and a reader that checks all of it. Only what recordings need:
/// no attachments or metadata records (the reader skips them, as it skips unknown opcodes).
/// Byte strings are std::string (bytes, not text).
#include <cstdint>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace hil::mcap {

/// The 8 bytes that start and end every MCAP file.
inline constexpr char kMagic[8] = {'\x89', 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum class Opcode : std::uint8_t {
  header = 0x01,
  footer = 0x02,
  schema = 0x03,
  channel = 0x04,
  message = 0x05,
  chunk = 0x06,
  message_index = 0x07,
  chunk_index = 0x08,
  attachment = 0x09,
  attachment_index = 0x0A,
  statistics = 0x0B,
  metadata = 0x0C,
  metadata_index = 0x0D,
  summary_offset = 0x0E,
  data_end = 0x0F,
};

/// Chunk compression: "" (none), "zstd" or "lz4" (LZ4 frame format).
enum class Compression { none, zstd, lz4 };
/// "none" | "zstd" | "lz4" (the command-line words). \throws std::invalid_argument otherwise.
Compression parse_compression(const std::string& word);
/// The word in the file's chunk records: "", "zstd", "lz4".
const char* record_name(Compression c);

struct Header {
  std::string profile;  ///< "ros2" for ROS 2 bags
  std::string library;
};
struct Schema {
  std::uint16_t id = 0;  ///< 0 is reserved (no schema)
  std::string name, encoding, data;
};
struct Channel {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;
  std::string topic, message_encoding;
  std::map<std::string, std::string> metadata;
};
struct Message {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time_ns = 0, publish_time_ns = 0;
  std::string data;
};
/// A chunk as found in the file (its records are decoded into the other lists).
struct ChunkInfo {
  std::uint64_t offset = 0;  ///< file offset of the chunk record (its opcode)
  std::uint64_t message_start_time_ns = 0, message_end_time_ns = 0;
  std::uint64_t uncompressed_size = 0, compressed_size = 0;
  std::uint32_t uncompressed_crc = 0;
  std::string compression;
};
struct MessageIndex {
  std::uint64_t offset = 0;  ///< file offset of the record
  std::uint16_t channel_id = 0;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> entries;  ///< (log_time, offset in the chunk's records)
};
struct ChunkIndex {
  std::uint64_t message_start_time_ns = 0, message_end_time_ns = 0;
  std::uint64_t chunk_start_offset = 0, chunk_length = 0;
  std::map<std::uint16_t, std::uint64_t> message_index_offsets;
  std::uint64_t message_index_length = 0;
  std::string compression;
  std::uint64_t compressed_size = 0, uncompressed_size = 0;
};
struct Statistics {
  std::uint64_t message_count = 0;
  std::uint16_t schema_count = 0;
  std::uint32_t channel_count = 0, attachment_count = 0, metadata_count = 0, chunk_count = 0;
  std::uint64_t message_start_time_ns = 0, message_end_time_ns = 0;
  std::map<std::uint16_t, std::uint64_t> channel_message_counts;
};
struct SummaryOffset {
  std::uint8_t group_opcode = 0;
  std::uint64_t group_start = 0, group_length = 0;
};
struct Footer {
  std::uint64_t summary_start = 0, summary_offset_start = 0;
  std::uint32_t summary_crc = 0;
};

struct WriterOptions {
  Compression compression = Compression::zstd;
  std::size_t chunk_size_bytes = 1 << 20;  ///< a chunk closes once its records reach this size
  std::size_t chunk_messages = 0;          ///< ... or this many messages (0: no limit)
  std::string profile;                     ///< Header.profile, e.g. "ros2"
  std::string library = "hil";
};

/// Writes an MCAP file: magic and Header at construction, schemas and channels into the data
/// section as they are added, messages into chunks (each followed by its message indexes), then
/// at close() DataEnd with the data-section CRC, the summary (schemas, channels, statistics, chunk
/// indexes), the summary offsets and the footer. A file not closed (process killed) ends after
/// its last complete chunk: stream readers read it up to there.
class Writer {
 public:
  /// \throws std::runtime_error when the file cannot be created.
  Writer(const std::string& path, WriterOptions options);
  ~Writer();  ///< closes, swallowing errors (call close() to see them)
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// \returns the new schema's id (1, 2, ...).
  std::uint16_t add_schema(const std::string& name, const std::string& encoding, const std::string& data);
  /// \returns the new channel's id (0, 1, ...).
  std::uint16_t add_channel(std::uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                            const std::map<std::string, std::string>& metadata = {});
  /// \pre the channel was added. \throws std::invalid_argument for an unknown channel.
  void write(const Message& m);
  /// Closes the open chunk (if any) and hands the bytes to the kernel.
  void flush();
  /// Finishes the file. Idempotent. \throws std::runtime_error on I/O failure.
  void close();

  const std::string& path() const { return path_; }
  std::uint64_t messages() const { return stats_.message_count; }

 private:
  void put(const std::string& bytes);  // appends to the file, updating the data-section CRC
  void close_chunk();

  std::string path_;
  WriterOptions opt_;
  std::FILE* file_ = nullptr;
  std::uint64_t pos_ = 0;
  std::uint32_t data_crc_ = 0;
  bool closed_ = false;
  std::vector<Schema> schemas_;
  std::vector<Channel> channels_;
  Statistics stats_;
  std::vector<ChunkIndex> chunk_indexes_;
  // The open chunk.
  std::string chunk_records_;
  std::size_t chunk_count_ = 0;
  std::uint64_t chunk_start_ns_ = 0, chunk_end_ns_ = 0;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index_entries_;
};

/// Everything in a file, records in file order within each list. Messages come out of their
/// chunks in the order they were written.
struct File {
  std::string path;
  Header header;
  std::vector<Schema> schemas;  ///< from the data section (summary copies are checked against them)
  std::vector<Channel> channels;
  std::vector<Message> messages;
  std::vector<ChunkInfo> chunks;
  std::vector<MessageIndex> message_indexes;
  std::uint32_t data_section_crc = 0;
  // Summary section.
  std::vector<Schema> summary_schemas;
  std::vector<Channel> summary_channels;
  std::optional<Statistics> statistics;
  std::vector<ChunkIndex> chunk_indexes;
  std::vector<SummaryOffset> summary_offsets;
  Footer footer;

  const Channel* channel(const std::string& topic) const;
  const Schema* schema(std::uint16_t id) const;
  /// Messages on `topic`, in file order.
  std::vector<const Message*> messages_on(const std::string& topic) const;
};

/// Reads and checks a whole file: both magics, record lengths, every CRC (data section, chunks,
/// summary), chunk and message indexes against the chunks, statistics against the messages.
/// \throws error::FormatError naming the file, the byte offset and what is wrong.
File read_file(const std::string& path);
/// The same on bytes in memory (`display_name` names them in errors).
File read_bytes(const std::string& bytes, const std::string& display_name);

/// What recover_file() could read of a file.
struct Recovery {
  bool complete = true;           ///< the whole file read and checked as read_file() does
  std::uint64_t bytes_total = 0;  ///< the file's size
  std::uint64_t bytes_read = 0;   ///< where reading stopped: every record before it is kept
  std::size_t chunks = 0, messages = 0;
  std::string stopped;  ///< why reading stopped (offset and reason); empty when complete
};
/// A recording that was not closed (killed, power lost) or is damaged at its end: its records
/// from the start, chunk by chunk, up to the first that is incomplete or fails its checks (length,
/// CRC, decompression); the records before it are kept, nothing after it is trusted. A complete
/// file is read exactly as read_file() reads it. \throws error::FormatError when not even the
/// magic and the Header are there.
File recover_file(const std::string& path, Recovery& recovery);
File recover_bytes(const std::string& bytes, const std::string& display_name, Recovery& recovery);

/// CRC-32 (ISO-HDLC, as zlib and the MCAP spec) of `n` bytes, continuing from `crc`.
std::uint32_t crc32(const void* data, std::size_t n, std::uint32_t crc = 0);

}  // namespace hil::mcap
