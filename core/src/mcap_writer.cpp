#include "epipole/core/mcap_writer.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <limits>

#include "epipole/core/error.hpp"
#include "epipole/core/resident.hpp"
#include "mcap_format.hpp"

namespace epipole::mcap {

namespace {

// Little-endian fields appended to a buffer.
class Out {
 public:
  explicit Out(std::vector<std::uint8_t>& bytes) : b_(bytes) {}
  template <typename T>
  void put(T v) {
    std::uint8_t raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof(T));
    b_.insert(b_.end(), raw, raw + sizeof(T));
  }
  void u8(std::uint8_t v) { put(v); }
  void u16(std::uint16_t v) { put(v); }
  void u32(std::uint32_t v) { put(v); }
  void u64(std::uint64_t v) { put(v); }
  void string(std::string_view s) {
    u32(static_cast<std::uint32_t>(s.size()));
    b_.insert(b_.end(), s.begin(), s.end());
  }
  void bytes32(std::span<const std::uint8_t> d) {
    u32(static_cast<std::uint32_t>(d.size()));
    b_.insert(b_.end(), d.begin(), d.end());
  }
  // A record: its opcode and length, patched by end().
  std::size_t begin(Op op) {
    u8(op);
    const std::size_t at = b_.size();
    u64(0);
    return at;
  }
  void end(std::size_t at) {
    const std::uint64_t length = b_.size() - at - 8;
    std::memcpy(b_.data() + at, &length, 8);
  }
  // A u32 byte length patched once what it measures is written.
  std::size_t begin_length() {
    const std::size_t at = b_.size();
    u32(0);
    return at;
  }
  void end_length(std::size_t at) {
    const auto length = static_cast<std::uint32_t>(b_.size() - at - 4);
    std::memcpy(b_.data() + at, &length, 4);
  }
  std::size_t size() const { return b_.size(); }

 private:
  std::vector<std::uint8_t>& b_;
};

std::uint32_t crc_of(std::span<const std::uint8_t> bytes, std::uint32_t crc = 0) {
  return static_cast<std::uint32_t>(crc32(crc, bytes.data(), static_cast<uInt>(bytes.size())));
}

void write_schema(Out& out, std::uint16_t id, const Schema& s) {
  const std::size_t r = out.begin(kSchema);
  out.u16(id);
  out.string(s.name);
  out.string(s.encoding);
  out.bytes32({reinterpret_cast<const std::uint8_t*>(s.data.data()), s.data.size()});
  out.end(r);
}

void write_channel(Out& out, std::uint16_t id, const Channel& c) {
  const std::size_t r = out.begin(kChannel);
  out.u16(id);
  out.u16(c.schema_id);
  out.string(c.topic);
  out.string(c.message_encoding);
  const std::size_t map = out.begin_length();
  for (const auto& [key, value] : c.metadata) {
    out.string(key);
    out.string(value);
  }
  out.end_length(map);
  out.end(r);
}

void write_statistics(Out& out, std::uint64_t messages, std::size_t schemas, std::size_t channels,
                      std::size_t attachments, std::size_t chunks, std::uint64_t first_time,
                      std::uint64_t last_time, const std::vector<std::uint64_t>& counts) {
  const std::size_t r = out.begin(kStatistics);
  out.u64(messages);
  out.u16(static_cast<std::uint16_t>(schemas));
  out.u32(static_cast<std::uint32_t>(channels));
  out.u32(static_cast<std::uint32_t>(attachments));
  out.u32(0);  // metadata
  out.u32(static_cast<std::uint32_t>(chunks));
  out.u64(first_time);
  out.u64(last_time);
  const std::size_t map = out.begin_length();
  for (std::uint16_t c = 0; c < counts.size(); ++c) {
    out.u16(c);
    out.u64(counts[c]);
  }
  out.end_length(map);
  out.end(r);
}

// (`auto`: the writer's own record of the chunk or attachment.)
void write_chunk_index(Out& out, const auto& ci) {
  const std::size_t r = out.begin(kChunkIndex);
  out.u64(ci.start_time);
  out.u64(ci.end_time);
  out.u64(ci.offset);
  out.u64(ci.length);
  const std::size_t map = out.begin_length();
  for (std::size_t i = 0; i < ci.indexed_channels; ++i) {
    const auto& [channel, offset] = ci.index_offsets[i];
    out.u16(channel);
    out.u64(offset);
  }
  out.end_length(map);
  out.u64(ci.index_length);
  out.string("zstd");
  out.u64(ci.compressed);
  out.u64(ci.uncompressed);
  out.end(r);
}

void write_attachment_index(Out& out, const auto& a) {
  const std::size_t r = out.begin(kAttachmentIndex);
  out.u64(a.offset);
  out.u64(a.length);
  out.u64(a.log_time);
  out.u64(a.log_time);  // create time
  out.u64(a.data_size);
  out.string(a.name);
  out.string(a.media_type);
  out.end(r);
}

}  // namespace

Writer::Writer(std::vector<Schema> schemas, std::vector<Channel> channels, std::size_t chunk_bytes,
               std::size_t largest_message, int zstd_level)
    : schemas_(std::move(schemas)),
      channels_(std::move(channels)),
      chunk_bytes_(chunk_bytes),
      level_(zstd_level),
      zstd_(ZSTD_createCCtx()),
      message_counts_(channels_.size(), 0) {
  require(zstd_ != nullptr, "mcap: cannot make a zstd context");
  require(channels_.size() <= kMaxChannels, "mcap: more than ", kMaxChannels, " channels");
  reserve_resident(chunks_, kMaxChunks);
  reserve_resident(chunk_, chunk_bytes + largest_message + 1024);
  reserve_resident(compressed_, ZSTD_compressBound(chunk_.capacity()));
  reserve_resident(index_, 4096);
  // A chunk's record and its indexes.
  reserve_resident(scratch_, compressed_.capacity() + 64 * 1024);
}

Writer::~Writer() {
  if (fd_ >= 0) ::close(fd_);
  ZSTD_freeCCtx(static_cast<ZSTD_CCtx*>(zstd_));
}

void Writer::emit(const std::vector<std::uint8_t>& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = n < 0 ? std::strerror(errno) : "nothing written";
      abandon();
      throw Error(cat(file_.string(), ": cannot write (", why, "): the file ends before it"));
    }
    done += static_cast<std::size_t>(n);
  }
  written_ += bytes.size();
}

// A file that cannot be written is left as it is (its chunks before the failure readable) and
// the writer starts afresh: the next message opens nothing by itself, its owner opens a file.
void Writer::abandon() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  chunk_.clear();
  index_.clear();
}

void Writer::open(const std::filesystem::path& file, std::string_view library) {
  if (fd_ >= 0) close();
  fd_ = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd_ < 0) throw Error(cat(file.string(), ": cannot create: ", std::strerror(errno)));
  file_ = file;
  written_ = 0;
  chunk_.clear();
  index_.clear();
  chunks_.clear();
  attachments_.clear();
  std::fill(message_counts_.begin(), message_counts_.end(), 0);
  first_time_ = last_time_ = 0;
  messages_ = 0;
  scratch_.clear();
  scratch_.insert(scratch_.end(), std::begin(kMagic), std::end(kMagic));
  Out out(scratch_);
  const std::size_t h = out.begin(kHeader);
  out.string("ros2");
  out.string(library);
  out.end(h);
  for (std::size_t i = 0; i < schemas_.size(); ++i) {
    write_schema(out, static_cast<std::uint16_t>(i + 1), schemas_[i]);
  }
  for (std::size_t i = 0; i < channels_.size(); ++i) {
    write_channel(out, static_cast<std::uint16_t>(i), channels_[i]);
  }
  emit(scratch_);
}

std::vector<std::uint8_t>& Writer::begin_message(std::uint16_t channel, std::uint32_t sequence,
                                                 std::uint64_t log_time,
                                                 std::uint64_t publish_time) {
  require(channel < channels_.size(), "mcap: no channel ", channel);
  require(fd_ >= 0, "mcap: a message with no file open");
  if (index_.empty()) chunk_start_ = chunk_end_ = log_time;
  chunk_start_ = std::min(chunk_start_, log_time);
  chunk_end_ = std::max(chunk_end_, log_time);
  if (messages_ == 0) first_time_ = last_time_ = log_time;
  ++messages_;
  first_time_ = std::min(first_time_, log_time);
  last_time_ = std::max(last_time_, log_time);
  ++message_counts_[channel];
  index_.push_back({channel, log_time, chunk_.size()});
  Out out(chunk_);
  message_at_ = out.begin(kMessage);
  out.u16(channel);
  out.u32(sequence);
  out.u64(log_time);
  out.u64(publish_time);
  return chunk_;
}

void Writer::end_message() {
  Out(chunk_).end(message_at_);
  if (chunk_.size() >= chunk_bytes_ || index_.size() == index_.capacity()) write_chunk();
}

void Writer::write_chunk() {
  if (index_.empty()) return;
  auto* context = static_cast<ZSTD_CCtx*>(zstd_);
  compressed_.resize(compressed_.capacity());
  const std::size_t size = ZSTD_compressCCtx(context, compressed_.data(), compressed_.size(),
                                             chunk_.data(), chunk_.size(), level_);
  if (ZSTD_isError(size)) {
    abandon();
    throw Error(cat(file_.string(), ": zstd: ", ZSTD_getErrorName(size)));
  }
  compressed_.resize(size);
  ChunkIndex ci{};
  ci.start_time = chunk_start_;
  ci.end_time = chunk_end_;
  ci.offset = written_;
  ci.compressed = size;
  ci.uncompressed = chunk_.size();
  scratch_.clear();
  Out out(scratch_);
  const std::size_t r = out.begin(kChunk);
  out.u64(chunk_start_);
  out.u64(chunk_end_);
  out.u64(chunk_.size());
  out.u32(crc_of(chunk_));
  out.string("zstd");
  out.u64(size);
  scratch_.insert(scratch_.end(), compressed_.begin(), compressed_.end());
  out.end(r);
  ci.length = scratch_.size();
  // The message indexes, a record per channel with messages in the chunk.
  const std::uint64_t index_start = written_ + scratch_.size();
  for (std::uint16_t channel = 0; channel < channels_.size(); ++channel) {
    const bool any = std::any_of(index_.begin(), index_.end(),
                                 [&](const IndexEntry& e) { return e.channel == channel; });
    if (!any) continue;
    ci.index_offsets[ci.indexed_channels++] = {channel, written_ + scratch_.size()};
    const std::size_t m = out.begin(kMessageIndex);
    out.u16(channel);
    const std::size_t entries = out.begin_length();
    for (const IndexEntry& e : index_) {
      if (e.channel != channel) continue;
      out.u64(e.log_time);
      out.u64(e.offset);
    }
    out.end_length(entries);
    out.end(m);
  }
  ci.index_length = written_ + scratch_.size() - index_start;
  emit(scratch_);
  chunks_.push_back(ci);
  chunk_.clear();
  index_.clear();
}

void Writer::attach(std::string_view name, std::string_view media_type,
                    std::span<const std::uint8_t> data, std::uint64_t log_time) {
  write_chunk();  // records stay in file order
  scratch_.clear();
  Out out(scratch_);
  const std::size_t r = out.begin(kAttachment);
  out.u64(log_time);
  out.u64(log_time);  // create time
  out.string(name);
  out.string(media_type);
  out.u64(data.size());
  scratch_.insert(scratch_.end(), data.begin(), data.end());
  out.u32(crc_of({scratch_.data() + r + 8, scratch_.size() - r - 8}));
  out.end(r);
  attachments_.push_back({written_, scratch_.size(), log_time, data.size(), std::string(name),
                          std::string(media_type)});
  emit(scratch_);
}

void Writer::write_summary() {
  scratch_.clear();
  Out out(scratch_);
  const std::size_t de = out.begin(kDataEnd);
  out.u32(0);  // no CRC of the data section
  out.end(de);
  emit(scratch_);
  const std::uint64_t summary_start = written_;
  scratch_.clear();
  struct Group {
    Op op;
    std::uint64_t start, length;
  };
  std::vector<Group> groups;
  const auto group = [&](Op op, auto write) {
    const std::size_t start = scratch_.size();
    write();
    if (scratch_.size() > start) {
      groups.push_back({op, summary_start + start, scratch_.size() - start});
    }
  };
  group(kSchema, [&] {
    for (std::size_t i = 0; i < schemas_.size(); ++i) {
      write_schema(out, static_cast<std::uint16_t>(i + 1), schemas_[i]);
    }
  });
  group(kChannel, [&] {
    for (std::size_t i = 0; i < channels_.size(); ++i) {
      write_channel(out, static_cast<std::uint16_t>(i), channels_[i]);
    }
  });
  group(kStatistics, [&] {
    write_statistics(out, messages_, schemas_.size(), channels_.size(), attachments_.size(),
                     chunks_.size(), first_time_, last_time_, message_counts_);
  });
  group(kChunkIndex, [&] {
    for (const ChunkIndex& ci : chunks_) write_chunk_index(out, ci);
  });
  group(kAttachmentIndex, [&] {
    for (const AttachmentIndex& a : attachments_) write_attachment_index(out, a);
  });
  const std::uint64_t offsets_start = summary_start + scratch_.size();
  for (const Group& g : groups) {
    const std::size_t r = out.begin(kSummaryOffset);
    out.u8(g.op);
    out.u64(g.start);
    out.u64(g.length);
    out.end(r);
  }
  // The footer; its CRC covers the summary, the offsets and the footer up to the CRC itself.
  out.u8(kFooter);
  out.u64(8 + 8 + 4);
  out.u64(summary_start);
  out.u64(offsets_start);
  out.u32(crc_of(scratch_));
  scratch_.insert(scratch_.end(), std::begin(kMagic), std::end(kMagic));
  emit(scratch_);
}

void Writer::close() {
  if (fd_ < 0) return;
  write_chunk();  // each abandons the file when it fails
  write_summary();
  if (::fsync(fd_) != 0) {
    const std::string why = std::strerror(errno);
    abandon();
    throw Error(cat(file_.string(), ": cannot sync: ", why));
  }
  abandon();  // closed; nothing left of it
}

}  // namespace epipole::mcap
