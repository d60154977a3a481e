// MCAP writer: records laid out as in the specification (https://mcap.dev/spec).
#include <fmt/format.h>
#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "bytes.hpp"
#include <hil/mcap/mcap.hpp>

namespace hil::mcap {
using namespace detail;

std::uint32_t crc32(const void* data, std::size_t n, std::uint32_t crc) {
  // zlib's crc32 takes uInt lengths: feed large buffers in pieces.
  const auto* p = static_cast<const Bytef*>(data);
  uLong c = crc;
  while (n > 0) {
    const auto k = static_cast<uInt>(std::min<std::size_t>(n, 1u << 30));
    c = ::crc32(c, p, k);
    p += k;
    n -= k;
  }
  return static_cast<std::uint32_t>(c);
}

Compression parse_compression(const std::string& word) {
  if (word == "none") return Compression::none;
  if (word == "zstd") return Compression::zstd;
  if (word == "lz4") return Compression::lz4;
  throw std::invalid_argument(fmt::format("unknown compression '{}' (expected none, zstd or lz4)", word));
}

const char* record_name(Compression c) {
  switch (c) {
    case Compression::zstd: return "zstd";
    case Compression::lz4: return "lz4";
    case Compression::none: break;
  }
  return "";
}

namespace {

std::string compress(Compression c, const std::string& in) {
  std::string out;
  if (c == Compression::zstd) {
    out.resize(ZSTD_compressBound(in.size()));
    const auto n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 3);
    if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
    out.resize(n);
  } else if (c == Compression::lz4) {
    LZ4F_preferences_t prefs;
    std::memset(&prefs, 0, sizeof prefs);
    prefs.frameInfo.contentSize = in.size();  // lets readers size their buffer
    out.resize(LZ4F_compressFrameBound(in.size(), &prefs));
    const auto n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), &prefs);
    if (LZ4F_isError(n)) throw std::runtime_error(std::string("lz4: ") + LZ4F_getErrorName(n));
    out.resize(n);
  } else {
    out = in;
  }
  return out;
}

std::string header_record(const Header& h) {
  std::string c;
  put_str(c, h.profile);
  put_str(c, h.library);
  std::string r;
  put_record(r, static_cast<std::uint8_t>(Opcode::header), c);
  return r;
}

std::string schema_record(const Schema& s) {
  std::string c;
  put_u16(c, s.id);
  put_str(c, s.name);
  put_str(c, s.encoding);
  put_str(c, s.data);  // bytes with a u32 length, like a string
  std::string r;
  put_record(r, static_cast<std::uint8_t>(Opcode::schema), c);
  return r;
}

std::string channel_record(const Channel& ch) {
  std::string c;
  put_u16(c, ch.id);
  put_u16(c, ch.schema_id);
  put_str(c, ch.topic);
  put_str(c, ch.message_encoding);
  std::string map;
  for (const auto& [k, v] : ch.metadata) {
    put_str(map, k);
    put_str(map, v);
  }
  put_str(c, map);  // a map is its byte length then the pairs
  std::string r;
  put_record(r, static_cast<std::uint8_t>(Opcode::channel), c);
  return r;
}

std::string statistics_record(const Statistics& s) {
  std::string c;
  put_u64(c, s.message_count);
  put_u16(c, s.schema_count);
  put_u32(c, s.channel_count);
  put_u32(c, s.attachment_count);
  put_u32(c, s.metadata_count);
  put_u32(c, s.chunk_count);
  put_u64(c, s.message_start_time_ns);
  put_u64(c, s.message_end_time_ns);
  put_u32(c, static_cast<std::uint32_t>(s.channel_message_counts.size() * 10));
  for (const auto& [id, n] : s.channel_message_counts) {
    put_u16(c, id);
    put_u64(c, n);
  }
  std::string r;
  put_record(r, static_cast<std::uint8_t>(Opcode::statistics), c);
  return r;
}

std::string chunk_index_record(const ChunkIndex& ci) {
  std::string c;
  put_u64(c, ci.message_start_time_ns);
  put_u64(c, ci.message_end_time_ns);
  put_u64(c, ci.chunk_start_offset);
  put_u64(c, ci.chunk_length);
  put_u32(c, static_cast<std::uint32_t>(ci.message_index_offsets.size() * 10));
  for (const auto& [id, off] : ci.message_index_offsets) {
    put_u16(c, id);
    put_u64(c, off);
  }
  put_u64(c, ci.message_index_length);
  put_str(c, ci.compression);
  put_u64(c, ci.compressed_size);
  put_u64(c, ci.uncompressed_size);
  std::string r;
  put_record(r, static_cast<std::uint8_t>(Opcode::chunk_index), c);
  return r;
}

}  // namespace

Writer::Writer(const std::string& path, WriterOptions options) : path_(path), opt_(std::move(options)) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) throw std::runtime_error(fmt::format("{}: cannot create: {}", path, std::strerror(errno)));
  put(std::string(kMagic, sizeof kMagic));
  put(header_record({opt_.profile, opt_.library}));
}

Writer::~Writer() {
  try {
    close();
  } catch (...) {  // a destructor must not throw; close() reports the error to callers that ask
  }
  if (file_) std::fclose(file_);
}

void Writer::put(const std::string& bytes) {
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size())
    throw std::runtime_error(fmt::format("{}: write failed: {}", path_, std::strerror(errno)));
  data_crc_ = crc32(bytes.data(), bytes.size(), data_crc_);
  pos_ += bytes.size();
}

std::uint16_t Writer::add_schema(const std::string& name, const std::string& encoding, const std::string& data) {
  if (closed_) throw std::logic_error("mcap: add_schema after close");
  close_chunk();  // schemas go between chunks, before any message that needs them
  Schema s{static_cast<std::uint16_t>(schemas_.size() + 1), name, encoding, data};
  put(schema_record(s));
  schemas_.push_back(std::move(s));
  return schemas_.back().id;
}

std::uint16_t Writer::add_channel(std::uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                                  const std::map<std::string, std::string>& metadata) {
  if (closed_) throw std::logic_error("mcap: add_channel after close");
  if (schema_id > schemas_.size()) throw std::invalid_argument(fmt::format("mcap: unknown schema id {}", schema_id));
  close_chunk();
  Channel c{static_cast<std::uint16_t>(channels_.size()), schema_id, topic, message_encoding, metadata};
  put(channel_record(c));
  channels_.push_back(std::move(c));
  return channels_.back().id;
}

void Writer::write(const Message& m) {
  if (closed_) throw std::logic_error("mcap: write after close");
  if (m.channel_id >= channels_.size()) throw std::invalid_argument(fmt::format("mcap: unknown channel id {}", m.channel_id));
  if (chunk_count_ == 0) {
    chunk_start_ns_ = m.log_time_ns;
    chunk_end_ns_ = m.log_time_ns;
  }
  chunk_start_ns_ = std::min(chunk_start_ns_, m.log_time_ns);
  chunk_end_ns_ = std::max(chunk_end_ns_, m.log_time_ns);
  chunk_index_entries_[m.channel_id].emplace_back(m.log_time_ns, chunk_records_.size());
  std::string c;
  put_u16(c, m.channel_id);
  put_u32(c, m.sequence);
  put_u64(c, m.log_time_ns);
  put_u64(c, m.publish_time_ns);
  c += m.data;  // the payload is the rest of the record
  put_record(chunk_records_, static_cast<std::uint8_t>(Opcode::message), c);
  ++chunk_count_;

  if (stats_.message_count == 0) stats_.message_start_time_ns = stats_.message_end_time_ns = m.log_time_ns;
  stats_.message_start_time_ns = std::min(stats_.message_start_time_ns, m.log_time_ns);
  stats_.message_end_time_ns = std::max(stats_.message_end_time_ns, m.log_time_ns);
  ++stats_.message_count;
  ++stats_.channel_message_counts[m.channel_id];

  if (chunk_records_.size() >= opt_.chunk_size_bytes || (opt_.chunk_messages > 0 && chunk_count_ >= opt_.chunk_messages)) close_chunk();
}

void Writer::close_chunk() {
  if (chunk_count_ == 0) return;
  const auto compressed = compress(opt_.compression, chunk_records_);
  ChunkIndex ci;
  ci.message_start_time_ns = chunk_start_ns_;
  ci.message_end_time_ns = chunk_end_ns_;
  ci.chunk_start_offset = pos_;
  ci.compression = record_name(opt_.compression);
  ci.compressed_size = compressed.size();
  ci.uncompressed_size = chunk_records_.size();

  std::string c;
  put_u64(c, chunk_start_ns_);
  put_u64(c, chunk_end_ns_);
  put_u64(c, chunk_records_.size());
  put_u32(c, crc32(chunk_records_.data(), chunk_records_.size()));
  put_str(c, ci.compression);
  put_u64(c, compressed.size());
  c += compressed;
  std::string rec;
  put_record(rec, static_cast<std::uint8_t>(Opcode::chunk), c);
  ci.chunk_length = rec.size();
  put(rec);

  // One message index per channel with messages in the chunk, right after it.
  const auto index_start = pos_;
  for (const auto& [id, entries] : chunk_index_entries_) {
    std::string mc;
    put_u16(mc, id);
    put_u32(mc, static_cast<std::uint32_t>(entries.size() * 16));
    for (const auto& [t, off] : entries) {
      put_u64(mc, t);
      put_u64(mc, off);
    }
    std::string mr;
    put_record(mr, static_cast<std::uint8_t>(Opcode::message_index), mc);
    ci.message_index_offsets[id] = pos_;
    put(mr);
  }
  ci.message_index_length = pos_ - index_start;
  chunk_indexes_.push_back(std::move(ci));
  ++stats_.chunk_count;

  chunk_records_.clear();
  chunk_index_entries_.clear();
  chunk_count_ = 0;
}

void Writer::flush() {
  if (closed_) return;
  close_chunk();
  if (std::fflush(file_) != 0) throw std::runtime_error(fmt::format("{}: write failed: {}", path_, std::strerror(errno)));
}

void Writer::close() {
  if (closed_ || !file_) return;
  closed_ = true;
  close_chunk();
  {
    std::string c;
    put_u32(c, data_crc_);
    std::string r;
    put_record(r, static_cast<std::uint8_t>(Opcode::data_end), c);
    put(r);
  }
  // Summary: each group of records remembered for its SummaryOffset.
  const auto summary_start = pos_;
  std::string summary;
  std::vector<SummaryOffset> offsets;
  auto group = [&](Opcode op, const std::string& records) {
    if (records.empty()) return;
    offsets.push_back({static_cast<std::uint8_t>(op), summary_start + summary.size(), records.size()});
    summary += records;
  };
  std::string g;
  for (const auto& s : schemas_) g += schema_record(s);
  group(Opcode::schema, g);
  g.clear();
  for (const auto& ch : channels_) g += channel_record(ch);
  group(Opcode::channel, g);
  stats_.schema_count = static_cast<std::uint16_t>(schemas_.size());
  stats_.channel_count = static_cast<std::uint32_t>(channels_.size());
  group(Opcode::statistics, statistics_record(stats_));
  g.clear();
  for (const auto& ci : chunk_indexes_) g += chunk_index_record(ci);
  group(Opcode::chunk_index, g);

  const auto summary_offset_start = summary_start + summary.size();
  for (const auto& o : offsets) {
    std::string c;
    put_u8(c, o.group_opcode);
    put_u64(c, o.group_start);
    put_u64(c, o.group_length);
    put_record(summary, static_cast<std::uint8_t>(Opcode::summary_offset), c);
  }
  // Footer: the summary CRC covers the summary up to and including summary_offset_start.
  std::string footer;
  put_u8(footer, static_cast<std::uint8_t>(Opcode::footer));
  put_u64(footer, 8 + 8 + 4);
  put_u64(footer, summary_start);
  put_u64(footer, summary_offset_start);
  std::uint32_t crc = crc32(summary.data(), summary.size());
  crc = crc32(footer.data(), footer.size(), crc);
  put_u32(footer, crc);
  put(summary + footer + std::string(kMagic, sizeof kMagic));
  if (std::fflush(file_) != 0) throw std::runtime_error(fmt::format("{}: write failed: {}", path_, std::strerror(errno)));
  std::fclose(file_);
  file_ = nullptr;
}

}  // namespace hil::mcap
