// MCAP reader: the whole file in memory, every record and CRC checked. Recordings are tens of
// MB at most; a seeking reader would only matter for files far beyond what hil writes.
#include <fmt/format.h>
#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <tuple>

#include <hil/error/error.hpp>
#include <hil/mcap/mcap.hpp>

namespace hil::mcap {
namespace {

/// Reads fields of one record; every read past the record's end is an error naming the record.
class Cursor {
 public:
  Cursor(const std::string& file, const char* data, std::size_t size, std::uint64_t base, std::string what)
      : file_(file), p_(data), n_(size), base_(base), what_(std::move(what)) {}
  [[noreturn]] void fail(const std::string& msg) const {
    throw error::FormatError({file_, 0, 0, ""}, fmt::format("offset {}: {}: {}", base_, what_, msg));
  }
  void need(std::size_t k, const char* field) const {
    if (n_ - i_ < k) fail(fmt::format("field {} runs past the end of the record ({} bytes)", field, n_));
  }
  template <class T>
  T le(const char* field) {
    need(sizeof(T), field);
    std::uint64_t v = 0;
    for (std::size_t k = 0; k < sizeof(T); ++k) v |= static_cast<std::uint64_t>(static_cast<unsigned char>(p_[i_ + k])) << (8 * k);
    i_ += sizeof(T);
    return static_cast<T>(v);
  }
  std::uint8_t u8(const char* f) { return le<std::uint8_t>(f); }
  std::uint16_t u16(const char* f) { return le<std::uint16_t>(f); }
  std::uint32_t u32(const char* f) { return le<std::uint32_t>(f); }
  std::uint64_t u64(const char* f) { return le<std::uint64_t>(f); }
  std::string bytes(std::uint64_t k, const char* field) {
    if (k > n_ - i_) fail(fmt::format("field {} of {} bytes runs past the end of the record ({} bytes)", field, k, n_));
    std::string s(p_ + i_, static_cast<std::size_t>(k));
    i_ += static_cast<std::size_t>(k);
    return s;
  }
  std::string str(const char* field) { return bytes(u32(field), field); }
  std::string rest() { return bytes(n_ - i_, "data"); }
  /// A u32-length-prefixed map or array, as its own cursor.
  Cursor sub(const char* field) {
    const auto k = u32(field);
    if (k > n_ - i_) fail(fmt::format("field {} of {} bytes runs past the end of the record ({} bytes)", field, k, n_));
    Cursor c(file_, p_ + i_, k, base_, what_ + " " + field);
    i_ += k;
    return c;
  }
  bool done() const { return i_ >= n_; }

 private:
  const std::string& file_;
  const char* p_;
  std::size_t n_;
  std::size_t i_ = 0;
  std::uint64_t base_;
  std::string what_;
};

[[noreturn]] void raise(const std::string& file, std::uint64_t offset, const std::string& msg) {
  throw error::FormatError({file, 0, 0, ""}, fmt::format("offset {}: {}", offset, msg));
}

const char* opcode_name(std::uint8_t op) {
  switch (static_cast<Opcode>(op)) {
    case Opcode::header: return "Header";
    case Opcode::footer: return "Footer";
    case Opcode::schema: return "Schema";
    case Opcode::channel: return "Channel";
    case Opcode::message: return "Message";
    case Opcode::chunk: return "Chunk";
    case Opcode::message_index: return "MessageIndex";
    case Opcode::chunk_index: return "ChunkIndex";
    case Opcode::attachment: return "Attachment";
    case Opcode::attachment_index: return "AttachmentIndex";
    case Opcode::statistics: return "Statistics";
    case Opcode::metadata: return "Metadata";
    case Opcode::metadata_index: return "MetadataIndex";
    case Opcode::summary_offset: return "SummaryOffset";
    case Opcode::data_end: return "DataEnd";
  }
  return "unknown record";
}

Schema parse_schema(Cursor& c) {
  Schema s;
  s.id = c.u16("id");
  s.name = c.str("name");
  s.encoding = c.str("encoding");
  s.data = c.str("data");
  return s;
}

Channel parse_channel(Cursor& c) {
  Channel ch;
  ch.id = c.u16("id");
  ch.schema_id = c.u16("schema_id");
  ch.topic = c.str("topic");
  ch.message_encoding = c.str("message_encoding");
  auto m = c.sub("metadata");
  while (!m.done()) {
    auto k = m.str("key");
    ch.metadata[k] = m.str("value");
  }
  return ch;
}

Message parse_message(Cursor& c) {
  Message m;
  m.channel_id = c.u16("channel_id");
  m.sequence = c.u32("sequence");
  m.log_time_ns = c.u64("log_time");
  m.publish_time_ns = c.u64("publish_time");
  m.data = c.rest();
  return m;
}

std::string decompress(const std::string& file, std::uint64_t offset, const std::string& compression, const std::string& in,
                       std::uint64_t size) {
  auto fail = [&](const std::string& msg) { raise(file, offset, "Chunk: " + msg); };
  if (compression.empty()) {
    if (in.size() != size) fail(fmt::format("uncompressed records are {} bytes, the chunk says {}", in.size(), size));
    return in;
  }
  if (compression != "zstd" && compression != "lz4")
    fail(fmt::format("unknown compression '{}' (this reader knows '', 'zstd', 'lz4')", compression));
  if (size > (std::uint64_t{1} << 34)) fail(fmt::format("uncompressed size {} is beyond any recording", size));
  // The output is allocated before decompressing, so a size the data cannot hold is refused first
  // (found by fuzz_mcap: a 250-byte chunk claiming gigabytes). Neither format expands without bound:
  // a zstd RLE block turns 4 bytes into at most 128 KiB (ratio 32,768), an LZ4 sequence spends one
  // byte per 255 bytes of match length; the bounds below leave a factor of 2 over those.
  const std::uint64_t most = compression == "zstd" ? (std::uint64_t{1} << 16) * in.size() : 512 * in.size() + 1024;
  if (size > most) fail(fmt::format("uncompressed size {} is more than {} bytes of {} data can hold", size, in.size(), compression));
  std::string out(static_cast<std::size_t>(size), '\0');
  if (compression == "zstd") {
    const auto n = ZSTD_decompress(out.data(), out.size(), in.data(), in.size());
    if (ZSTD_isError(n)) fail(fmt::format("zstd data does not decompress: {}", ZSTD_getErrorName(n)));
    if (n != size) fail(fmt::format("zstd data decompresses to {} bytes, the chunk says {}", n, size));
    return out;
  }
  if (compression == "lz4") {
    LZ4F_dctx* ctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION))) fail("lz4: no decompression context");
    std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> guard(ctx, &LZ4F_freeDecompressionContext);
    std::size_t src_pos = 0, dst_pos = 0;
    while (src_pos < in.size()) {
      std::size_t src_n = in.size() - src_pos, dst_n = out.size() - dst_pos;
      const auto r = LZ4F_decompress(ctx, out.data() + dst_pos, &dst_n, in.data() + src_pos, &src_n, nullptr);
      if (LZ4F_isError(r)) fail(fmt::format("lz4 data does not decompress: {}", LZ4F_getErrorName(r)));
      src_pos += src_n;
      dst_pos += dst_n;
      if (r == 0) break;  // end of frame
      if (src_n == 0 && dst_n == 0) fail("lz4 data is cut short or larger than the chunk says");
    }
    if (dst_pos != size) fail(fmt::format("lz4 data decompresses to {} bytes, the chunk says {}", dst_pos, size));
    return out;
  }
  return out;  // not reached: the compression was checked above
}

}  // namespace

const Channel* File::channel(const std::string& topic) const {
  for (const auto& c : channels)
    if (c.topic == topic) return &c;
  return nullptr;
}

const Schema* File::schema(std::uint16_t id) const {
  for (const auto& s : schemas)
    if (s.id == id) return &s;
  return nullptr;
}

std::vector<const Message*> File::messages_on(const std::string& topic) const {
  std::vector<const Message*> out;
  const auto* c = channel(topic);
  if (!c) return out;
  for (const auto& m : messages)
    if (m.channel_id == c->id) out.push_back(&m);
  return out;
}

File read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw error::FormatError({path, 0, 0, ""}, "cannot open the file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return read_bytes(ss.str(), path);
}

File read_file_checked(const std::string& b, const std::string& name, Recovery* recovery);

File read_bytes(const std::string& b, const std::string& name) { return read_file_checked(b, name, nullptr); }

File recover_bytes(const std::string& b, const std::string& name, Recovery& recovery) {
  recovery = Recovery{};
  recovery.bytes_total = b.size();
  auto f = read_file_checked(b, name, &recovery);
  if (recovery.complete) recovery.bytes_read = b.size();
  recovery.chunks = f.chunks.size();
  recovery.messages = f.messages.size();
  return f;
}

File recover_file(const std::string& path, Recovery& recovery) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw error::FormatError({path, 0, 0, ""}, "cannot open");
  std::ostringstream ss;
  ss << in.rdbuf();
  return recover_bytes(ss.str(), path, recovery);
}

File read_file_checked(const std::string& b, const std::string& name, Recovery* recovery) {
  File f;
  f.path = name;
  auto fail = [&](std::uint64_t off, const std::string& msg) { raise(name, off, msg); };
  constexpr std::size_t kM = sizeof kMagic;
  if (b.size() < kM || std::memcmp(b.data(), kMagic, kM) != 0) fail(0, "bad magic: not an MCAP file (expected \\x89MCAP0\\r\\n)");

  bool seen_header = false, seen_data_end = false, seen_footer = false;
  std::uint64_t data_end_offset = 0, footer_offset = 0;
  std::map<std::uint64_t, std::size_t> chunk_at;               // file offset -> index in f.chunks
  std::map<std::uint64_t, std::size_t> message_index_at;       // file offset -> index in f.message_indexes
  std::map<std::uint64_t, std::uint8_t> opcode_at;             // every record's opcode by offset
  std::map<std::uint64_t, std::uint16_t> last_chunk_messages;  // offsets in the last chunk -> channel
  std::set<std::uint16_t> schema_ids, channel_ids;
  std::vector<std::uint64_t> summary_record_offsets;

  std::size_t pos = kM;
  // Recovery: where the records stop being whole or sound, keep what came before and stop.
  auto stop = [&](std::uint64_t at, const std::string& why) {
    recovery->complete = false;
    recovery->bytes_read = at;
    recovery->stopped = fmt::format("offset {}: {}", at, why);
  };
  while (!seen_footer) {
    std::string cut;
    std::uint8_t op = 0;
    std::uint64_t len = 0;
    if (pos == b.size()) {
      cut = "the file ends here without a Footer: truncated (a recording that was not closed?)";
    } else if (b.size() - pos < 9) {
      cut = fmt::format("truncated record header ({} bytes left, a record needs 9)", b.size() - pos);
    } else {
      op = static_cast<std::uint8_t>(b[pos]);
      for (int k = 0; k < 8; ++k)
        len |= static_cast<std::uint64_t>(static_cast<unsigned char>(b[pos + 1 + static_cast<std::size_t>(k)])) << (8 * k);
      if (len > b.size() - pos - 9)
        cut = fmt::format("{} record of {} bytes runs past the end of the file ({} bytes): truncated or corrupt length", opcode_name(op),
                          len, b.size());
    }
    if (!cut.empty()) {
      if (recovery && seen_header) {
        stop(pos, cut);
        break;
      }
      fail(pos, cut);
    }
    const std::uint64_t off = pos;
    const auto kept = std::make_tuple(f.schemas.size(), f.channels.size(), f.messages.size(), f.chunks.size(), f.message_indexes.size());
    try {
      Cursor c(name, b.data() + pos + 9, static_cast<std::size_t>(len), off, opcode_name(op));
      pos += 9 + static_cast<std::size_t>(len);
      opcode_at[off] = op;
      if (!seen_header && op != static_cast<std::uint8_t>(Opcode::header))
        fail(off, fmt::format("the first record is a {}, not a Header", opcode_name(op)));
      const bool in_summary = seen_data_end;
      if (in_summary) summary_record_offsets.push_back(off);

      switch (static_cast<Opcode>(op)) {
        case Opcode::header:
          if (seen_header) fail(off, "a second Header");
          seen_header = true;
          f.header.profile = c.str("profile");
          f.header.library = c.str("library");
          break;
        case Opcode::schema: {
          auto s = parse_schema(c);
          if (s.id == 0) fail(off, "Schema with the reserved id 0");
          if (in_summary) {
            f.summary_schemas.push_back(std::move(s));
          } else {
            schema_ids.insert(s.id);
            f.schemas.push_back(std::move(s));
          }
          break;
        }
        case Opcode::channel: {
          auto ch = parse_channel(c);
          if (ch.schema_id != 0 && !schema_ids.count(ch.schema_id))
            fail(off, fmt::format("Channel '{}' refers to schema {}, not defined before it", ch.topic, ch.schema_id));
          if (in_summary) {
            f.summary_channels.push_back(std::move(ch));
          } else {
            channel_ids.insert(ch.id);
            f.channels.push_back(std::move(ch));
          }
          break;
        }
        case Opcode::message: {
          if (in_summary) fail(off, "a Message in the summary section");
          auto m = parse_message(c);
          if (!channel_ids.count(m.channel_id)) fail(off, fmt::format("Message on channel {}, not defined before it", m.channel_id));
          f.messages.push_back(std::move(m));
          break;
        }
        case Opcode::chunk: {
          if (in_summary) fail(off, "a Chunk in the summary section");
          ChunkInfo ci;
          ci.offset = off;
          ci.message_start_time_ns = c.u64("message_start_time");
          ci.message_end_time_ns = c.u64("message_end_time");
          ci.uncompressed_size = c.u64("uncompressed_size");
          ci.uncompressed_crc = c.u32("uncompressed_crc");
          ci.compression = c.str("compression");
          const auto records = c.bytes(c.u64("records_length"), "records");
          ci.compressed_size = records.size();
          const auto plain = decompress(name, off, ci.compression, records, ci.uncompressed_size);
          if (ci.uncompressed_crc != 0) {
            const auto crc = crc32(plain.data(), plain.size());
            if (crc != ci.uncompressed_crc)
              fail(off, fmt::format("Chunk: CRC mismatch of its records: stored {:#010x}, computed {:#010x}", ci.uncompressed_crc, crc));
          }
          // The chunk's records: schemas, channels and messages only.
          last_chunk_messages.clear();
          std::size_t q = 0;
          while (q < plain.size()) {
            const auto where = fmt::format("Chunk at offset {}, record at {} of its records", off, q);
            if (plain.size() - q < 9) fail(off, fmt::format("{}: truncated record header", where));
            const auto iop = static_cast<std::uint8_t>(plain[q]);
            std::uint64_t ilen = 0;
            for (int k = 0; k < 8; ++k)
              ilen |= static_cast<std::uint64_t>(static_cast<unsigned char>(plain[q + 1 + static_cast<std::size_t>(k)])) << (8 * k);
            if (ilen > plain.size() - q - 9)
              fail(off, fmt::format("{}: {} of {} bytes runs past the chunk's end", where, opcode_name(iop), ilen));
            Cursor ic(name, plain.data() + q + 9, static_cast<std::size_t>(ilen), off, where + " (" + opcode_name(iop) + ")");
            if (iop == static_cast<std::uint8_t>(Opcode::message)) {
              auto m = parse_message(ic);
              if (!channel_ids.count(m.channel_id))
                fail(off, fmt::format("{}: Message on channel {}, not defined before it", where, m.channel_id));
              if (m.log_time_ns < ci.message_start_time_ns || m.log_time_ns > ci.message_end_time_ns)
                fail(off, fmt::format("{}: Message log time {} outside the chunk's [{}, {}]", where, m.log_time_ns,
                                      ci.message_start_time_ns, ci.message_end_time_ns));
              last_chunk_messages[q] = m.channel_id;
              f.messages.push_back(std::move(m));
            } else if (iop == static_cast<std::uint8_t>(Opcode::schema)) {
              auto s = parse_schema(ic);
              schema_ids.insert(s.id);
              f.schemas.push_back(std::move(s));
            } else if (iop == static_cast<std::uint8_t>(Opcode::channel)) {
              auto ch = parse_channel(ic);
              if (ch.schema_id != 0 && !schema_ids.count(ch.schema_id))
                fail(off, fmt::format("{}: Channel '{}' refers to schema {}, not defined before it", where, ch.topic, ch.schema_id));
              channel_ids.insert(ch.id);
              f.channels.push_back(std::move(ch));
            } else if (iop >= static_cast<std::uint8_t>(Opcode::header) && iop <= static_cast<std::uint8_t>(Opcode::data_end)) {
              fail(off, fmt::format("{}: a {} record cannot be inside a chunk", where, opcode_name(iop)));
            }  // opcodes beyond the specification's are skipped, as the specification asks
            q += 9 + static_cast<std::size_t>(ilen);
          }
          chunk_at[off] = f.chunks.size();
          f.chunks.push_back(std::move(ci));
          break;
        }
        case Opcode::message_index: {
          if (in_summary) fail(off, "a MessageIndex in the summary section");
          MessageIndex mi;
          mi.offset = off;
          mi.channel_id = c.u16("channel_id");
          auto a = c.sub("records");
          while (!a.done()) {
            const auto t = a.u64("log_time");
            mi.entries.emplace_back(t, a.u64("offset"));
          }
          for (const auto& [t, o] : mi.entries) {
            const auto it = last_chunk_messages.find(o);
            if (it == last_chunk_messages.end() || it->second != mi.channel_id)
              fail(off, fmt::format("MessageIndex of channel {} points at offset {} of the chunk before it, not a message of that channel",
                                    mi.channel_id, o));
          }
          message_index_at[off] = f.message_indexes.size();
          f.message_indexes.push_back(std::move(mi));
          break;
        }
        case Opcode::chunk_index: {
          ChunkIndex ci;
          ci.message_start_time_ns = c.u64("message_start_time");
          ci.message_end_time_ns = c.u64("message_end_time");
          ci.chunk_start_offset = c.u64("chunk_start_offset");
          ci.chunk_length = c.u64("chunk_length");
          auto m = c.sub("message_index_offsets");
          while (!m.done()) {
            const auto id = m.u16("channel_id");
            ci.message_index_offsets[id] = m.u64("offset");
          }
          ci.message_index_length = c.u64("message_index_length");
          ci.compression = c.str("compression");
          ci.compressed_size = c.u64("compressed_size");
          ci.uncompressed_size = c.u64("uncompressed_size");
          const auto it = chunk_at.find(ci.chunk_start_offset);
          if (it == chunk_at.end()) fail(off, fmt::format("ChunkIndex points at offset {}, where no chunk starts", ci.chunk_start_offset));
          const auto& ch = f.chunks[it->second];
          if (ch.uncompressed_size != ci.uncompressed_size || ch.compressed_size != ci.compressed_size ||
              ch.compression != ci.compression || ch.message_start_time_ns != ci.message_start_time_ns ||
              ch.message_end_time_ns != ci.message_end_time_ns)
            fail(off, fmt::format("ChunkIndex disagrees with the chunk at offset {} (sizes, compression or times)", ci.chunk_start_offset));
          for (const auto& [id, o] : ci.message_index_offsets) {
            const auto mi = message_index_at.find(o);
            if (mi == message_index_at.end() || f.message_indexes[mi->second].channel_id != id)
              fail(off, fmt::format("ChunkIndex: the message index of channel {} is not at offset {}", id, o));
          }
          f.chunk_indexes.push_back(std::move(ci));
          break;
        }
        case Opcode::statistics: {
          Statistics s;
          s.message_count = c.u64("message_count");
          s.schema_count = c.u16("schema_count");
          s.channel_count = c.u32("channel_count");
          s.attachment_count = c.u32("attachment_count");
          s.metadata_count = c.u32("metadata_count");
          s.chunk_count = c.u32("chunk_count");
          s.message_start_time_ns = c.u64("message_start_time");
          s.message_end_time_ns = c.u64("message_end_time");
          auto m = c.sub("channel_message_counts");
          while (!m.done()) {
            const auto id = m.u16("channel_id");
            s.channel_message_counts[id] = m.u64("count");
          }
          f.statistics = std::move(s);
          break;
        }
        case Opcode::summary_offset: {
          SummaryOffset so;
          so.group_opcode = c.u8("group_opcode");
          so.group_start = c.u64("group_start");
          so.group_length = c.u64("group_length");
          f.summary_offsets.push_back(so);
          break;
        }
        case Opcode::data_end: {
          if (seen_data_end) fail(off, "a second DataEnd");
          f.data_section_crc = c.u32("data_section_crc");
          if (f.data_section_crc != 0) {
            const auto crc = crc32(b.data(), static_cast<std::size_t>(off));
            if (crc != f.data_section_crc)
              fail(off,
                   fmt::format("DataEnd: CRC mismatch of the data section: stored {:#010x}, computed {:#010x}", f.data_section_crc, crc));
          }
          seen_data_end = true;
          data_end_offset = off;
          break;
        }
        case Opcode::footer: {
          f.footer.summary_start = c.u64("summary_start");
          f.footer.summary_offset_start = c.u64("summary_offset_start");
          f.footer.summary_crc = c.u32("summary_crc");
          seen_footer = true;
          footer_offset = off;
          if (!summary_record_offsets.empty()) summary_record_offsets.pop_back();  // the footer itself
          break;
        }
        default: break;  // attachments, metadata and unknown opcodes: skipped
      }
    } catch (const error::FormatError& e) {
      if (!recovery || !seen_header || (op == static_cast<std::uint8_t>(Opcode::header))) throw;
      // A whole record that fails its checks: nothing of it, nor after it, is kept.
      f.schemas.resize(std::get<0>(kept));
      f.channels.resize(std::get<1>(kept));
      f.messages.resize(std::get<2>(kept));
      f.chunks.resize(std::get<3>(kept));
      f.message_indexes.resize(std::get<4>(kept));
      recovery->complete = false;
      recovery->bytes_read = off;
      recovery->stopped = e.message();  // "offset N: what", N within this record
      break;
    }
  }
  if (recovery && !recovery->complete) return f;  // no summary to check: the file was cut before it
  // The summary: a recovery keeps every message read so far when its checks fail.
  try {
    if (b.size() - pos != kM || std::memcmp(b.data() + pos, kMagic, kM) != 0)
      fail(pos, b.size() - pos < kM ? std::string("truncated: the closing magic is missing")
                                    : std::string("bad closing magic after the Footer"));
    if (!seen_data_end) fail(footer_offset, "Footer without a DataEnd record before it");

    // The footer's pointers and the summary CRC.
    const auto& ft = f.footer;
    if (ft.summary_start != 0) {
      if (ft.summary_start <= data_end_offset || ft.summary_start > footer_offset || !opcode_at.count(ft.summary_start))
        fail(footer_offset, fmt::format("Footer: summary_start {} is not a record after DataEnd", ft.summary_start));
      if (!summary_record_offsets.empty() && summary_record_offsets.front() != ft.summary_start)
        fail(footer_offset, fmt::format("Footer: summary_start {} is not where the summary begins ({})", ft.summary_start,
                                        summary_record_offsets.front()));
      if (ft.summary_crc != 0) {
        const auto n = static_cast<std::size_t>(footer_offset + 1 + 8 + 8 + 8 - ft.summary_start);
        const auto crc = crc32(b.data() + ft.summary_start, n);
        if (crc != ft.summary_crc)
          fail(footer_offset, fmt::format("Footer: CRC mismatch of the summary: stored {:#010x}, computed {:#010x}", ft.summary_crc, crc));
      }
    }
    if (ft.summary_offset_start != 0) {
      if (ft.summary_offset_start > footer_offset || (ft.summary_offset_start < footer_offset && !opcode_at.count(ft.summary_offset_start)))
        fail(footer_offset, fmt::format("Footer: summary_offset_start {} is not a record of the summary", ft.summary_offset_start));
    }
    for (const auto& so : f.summary_offsets) {
      const auto it = opcode_at.find(so.group_start);
      if (it == opcode_at.end() || it->second != so.group_opcode || so.group_start < ft.summary_start ||
          so.group_start + so.group_length > footer_offset)
        fail(ft.summary_offset_start, fmt::format("SummaryOffset for {} records points at [{}, +{}), not such a group",
                                                  opcode_name(so.group_opcode), so.group_start, so.group_length));
    }
    // The summary's copies agree with the data section; the statistics with the messages.
    for (const auto& s : f.summary_schemas) {
      const auto* d = f.schema(s.id);
      if (!d || d->name != s.name || d->encoding != s.encoding || d->data != s.data)
        fail(ft.summary_start, fmt::format("summary Schema {} ('{}') differs from the data section's", s.id, s.name));
    }
    for (const auto& ch : f.summary_channels) {
      const auto it = std::find_if(f.channels.begin(), f.channels.end(), [&](const Channel& d) { return d.id == ch.id; });
      if (it == f.channels.end() || it->topic != ch.topic || it->schema_id != ch.schema_id || it->message_encoding != ch.message_encoding)
        fail(ft.summary_start, fmt::format("summary Channel {} ('{}') differs from the data section's", ch.id, ch.topic));
    }
    if (f.statistics) {
      const auto& s = *f.statistics;
      std::map<std::uint16_t, std::uint64_t> counts;
      for (const auto& m : f.messages) ++counts[m.channel_id];
      if (s.message_count != f.messages.size())
        fail(ft.summary_start,
             fmt::format("Statistics: message_count {} but the file holds {} messages", s.message_count, f.messages.size()));
      for (const auto& [id, n] : counts) {
        const auto it = s.channel_message_counts.find(id);
        if (it == s.channel_message_counts.end() || it->second != n)
          fail(ft.summary_start, fmt::format("Statistics: channel {} holds {} messages, the statistics say {}", id, n,
                                             it == s.channel_message_counts.end() ? 0 : it->second));
      }
      if (s.chunk_count != f.chunks.size())
        fail(ft.summary_start, fmt::format("Statistics: chunk_count {} but the file holds {} chunks", s.chunk_count, f.chunks.size()));
    }
  } catch (const error::FormatError& e) {
    if (!recovery) throw;
    recovery->complete = false;
    recovery->bytes_read = pos;
    recovery->stopped = e.message();
  }
  return f;
}

}  // namespace hil::mcap
