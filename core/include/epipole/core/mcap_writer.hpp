#pragma once

// MCAP files (mcap.dev/spec, version 0): what Foxglove, Lichtblick and `ros2 bag` open. Written
// as the format's own writers do: the magic, a Header, the Schemas and Channels, then the
// messages in zstd-compressed Chunks, each followed by its MessageIndex records, then DataEnd
// and the summary (the Schemas and Channels again, Statistics, the ChunkIndexes and
// AttachmentIndexes, each group found through a SummaryOffset) and the Footer with the
// summary's CRC. A file cut short (power lost) keeps every chunk written before: readers that
// scan the data section read them.

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace epipole::mcap {

// A channel's id is its index among the writer's channels.
struct Channel {
  std::uint16_t schema_id = 0;  // 1 + the schema's index among the writer's schemas
  std::string topic;
  std::string message_encoding;  // "cdr"
  std::vector<std::pair<std::string, std::string>> metadata;
};

struct Schema {
  std::string name;      // "sensor_msgs/msg/Image"
  std::string encoding;  // "ros2msg"
  std::string data;      // the definition
};

// One file at a time: open(), messages, close(). Its buffers are allocated by the constructor
// (a chunk of `chunk_bytes` plus the largest message, its compressed copy, the index of
// kMaxChunks chunks), so a message that fits allocates nothing; a file of more chunks grows the
// index (its owner starts a new file before: chunks_left()). A
// write that fails throws Error naming the file, which is then left as it is (every chunk written
// before it readable) and closed: the owner opens another.
class Writer {
 public:
  static constexpr std::size_t kMaxChannels = 32;
  static constexpr std::size_t kMaxChunks = 1024;  // a file's chunks the index holds
  Writer(std::vector<Schema> schemas, std::vector<Channel> channels, std::size_t chunk_bytes,
         std::size_t largest_message, int zstd_level = 1);
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  // Creates `file` (never over an existing one) and writes the header, schemas and channels.
  void open(const std::filesystem::path& file, std::string_view library);
  bool is_open() const { return fd_ >= 0; }
  // A message on `channel` (an index into the constructor's channels): its bytes are appended to
  // the buffer begin_message() returns, then end_message() closes it. Times in ns since the epoch.
  std::vector<std::uint8_t>& begin_message(std::uint16_t channel, std::uint32_t sequence,
                                           std::uint64_t log_time, std::uint64_t publish_time);
  void end_message();
  // A file beside the messages (the calibration), written in the data section at once.
  void attach(std::string_view name, std::string_view media_type,
              std::span<const std::uint8_t> data, std::uint64_t log_time);
  // Writes the last chunk, the summary and the footer, syncs and closes the file.
  void close();
  // The chunks the open file can take before its index would grow.
  std::size_t chunks_left() const {
    return chunks_.size() < kMaxChunks ? kMaxChunks - chunks_.size() : 0;
  }
  // What the file holds so far (written, and the open chunk uncompressed).
  std::uint64_t bytes() const { return written_ + chunk_.size(); }
  const std::filesystem::path& file() const { return file_; }
  // Its buffers (the chunk and its compressed copy, the records outside chunks, the index).
  std::size_t working_set_bytes() const {
    return chunk_.capacity() + compressed_.capacity() + scratch_.capacity() +
           index_.capacity() * sizeof(IndexEntry) + chunks_.capacity() * sizeof(ChunkIndex);
  }

 private:
  struct IndexEntry {
    std::uint16_t channel;
    std::uint64_t log_time;
    std::uint64_t offset;  // in the chunk's records, uncompressed
  };
  struct ChunkIndex {
    std::uint64_t start_time, end_time, offset, length, index_length, compressed, uncompressed;
    std::array<std::pair<std::uint16_t, std::uint64_t>, kMaxChannels> index_offsets;
    std::size_t indexed_channels;
  };
  struct AttachmentIndex {
    std::uint64_t offset, length, log_time, data_size;
    std::string name, media_type;
  };
  void write_chunk();
  void write_summary();
  void emit(const std::vector<std::uint8_t>& bytes);
  void abandon();

  std::vector<Schema> schemas_;
  std::vector<Channel> channels_;
  std::size_t chunk_bytes_;
  int level_;
  void* zstd_ = nullptr;  // ZSTD_CCtx
  int fd_ = -1;
  std::filesystem::path file_;
  std::uint64_t written_ = 0;
  std::vector<std::uint8_t> chunk_;       // the open chunk's records
  std::vector<std::uint8_t> compressed_;  // its compressed copy
  std::vector<std::uint8_t> scratch_;     // records written outside chunks
  std::vector<IndexEntry> index_;         // the open chunk's messages
  std::size_t message_at_ = 0;            // where the open message's record starts in chunk_
  std::uint64_t chunk_start_ = 0, chunk_end_ = 0;
  std::vector<ChunkIndex> chunks_;
  std::vector<AttachmentIndex> attachments_;
  std::vector<std::uint64_t> message_counts_;  // by channel
  std::uint64_t messages_ = 0;
  std::uint64_t first_time_ = 0, last_time_ = 0;
};

}  // namespace epipole::mcap
