#include "epipole/core/mcap_reader.hpp"

#include <zlib.h>
#include <zstd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <vector>

#include "epipole/core/error.hpp"
#include "mcap_format.hpp"

namespace epipole::mcap {

namespace {

// A chunk that says it holds more than this is refused rather than allocated (the writers chunk
// a few MiB), and so is any record read that is larger than a chunk could be.
constexpr std::uint64_t kLargestChunk = 256ull << 20;
constexpr std::uint64_t kLargestRecord = kLargestChunk + (1u << 20);

// Where the bytes come from: the records are read in order, each wholly, or skipped.
class Source {
 public:
  virtual ~Source() = default;
  virtual std::uint64_t offset() const = 0;
  virtual std::uint64_t remaining() const = 0;
  // The next n bytes (n <= remaining()), valid until the next call.
  virtual std::span<const std::uint8_t> read(std::size_t n) = 0;
  virtual void skip(std::uint64_t n) = 0;
};

class MemorySource final : public Source {
 public:
  explicit MemorySource(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  std::uint64_t offset() const override { return at_; }
  std::uint64_t remaining() const override { return bytes_.size() - at_; }
  std::span<const std::uint8_t> read(std::size_t n) override {
    const std::span<const std::uint8_t> s = bytes_.subspan(at_, n);
    at_ += n;
    return s;
  }
  void skip(std::uint64_t n) override { at_ += static_cast<std::size_t>(n); }

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t at_ = 0;
};

class FileSource final : public Source {
 public:
  explicit FileSource(const std::filesystem::path& file) : name_(file.string()) {
    file_.reset(std::fopen(file.c_str(), "rbe"));
    if (!file_) throw Error(cat(name_, ": cannot open: ", std::strerror(errno)));
    std::error_code ec;
    size_ = std::filesystem::file_size(file, ec);
    if (ec) throw Error(cat(name_, ": cannot read its size: ", ec.message()));
  }
  std::uint64_t offset() const override { return at_; }
  std::uint64_t remaining() const override { return size_ - at_; }
  std::span<const std::uint8_t> read(std::size_t n) override {
    buffer_.resize(n);
    if (std::fread(buffer_.data(), 1, n, file_.get()) != n) {
      throw Error(cat(name_, ": cannot read at offset ", at_, ": ",
                      std::feof(file_.get()) ? "it ends early (was it cut while read?)"
                                             : std::strerror(errno)));
    }
    at_ += n;
    return buffer_;
  }
  void skip(std::uint64_t n) override {
    at_ += n;
    if (::fseeko(file_.get(), static_cast<off_t>(at_), SEEK_SET) != 0) {
      throw Error(cat(name_, ": cannot seek to offset ", at_, ": ", std::strerror(errno)));
    }
  }

 private:
  struct Close {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::string name_;
  std::unique_ptr<std::FILE, Close> file_;
  std::uint64_t size_ = 0;
  std::uint64_t at_ = 0;
  std::vector<std::uint8_t> buffer_;
};

// A record's fields, little endian, each checked against what is left of the record.
class Fields {
 public:
  Fields(std::span<const std::uint8_t> bytes, const std::string& where)
      : bytes_(bytes), where_(where) {}
  template <typename T>
  T get(const char* what) {
    T v;
    std::memcpy(&v, take(sizeof(T), what).data(), sizeof(T));
    return v;
  }
  std::uint8_t u8(const char* what) { return get<std::uint8_t>(what); }
  std::uint16_t u16(const char* what) { return get<std::uint16_t>(what); }
  std::uint32_t u32(const char* what) { return get<std::uint32_t>(what); }
  std::uint64_t u64(const char* what) { return get<std::uint64_t>(what); }
  std::string_view string(const char* what) {
    const std::span<const std::uint8_t> s = take(u32(what), what);
    return {reinterpret_cast<const char*>(s.data()), s.size()};
  }
  std::span<const std::uint8_t> bytes32(const char* what) { return take(u32(what), what); }
  std::span<const std::uint8_t> bytes64(const char* what) { return take(u64(what), what); }
  std::span<const std::uint8_t> rest() { return take(bytes_.size() - at_, "the rest"); }
  std::size_t at() const { return at_; }

 private:
  std::span<const std::uint8_t> take(std::uint64_t n, const char* what) {
    if (n > bytes_.size() - at_) {
      throw Error(cat(where_, ": its ", what, " runs past the end of the record"));
    }
    const std::span<const std::uint8_t> s = bytes_.subspan(at_, static_cast<std::size_t>(n));
    at_ += static_cast<std::size_t>(n);
    return s;
  }
  std::span<const std::uint8_t> bytes_;
  std::size_t at_ = 0;
  const std::string& where_;
};

std::uint32_t crc_of(std::span<const std::uint8_t> bytes) {
  return static_cast<std::uint32_t>(crc32_z(0, bytes.data(), bytes.size()));
}

class Scanner {
 public:
  Scanner(Source& source, std::string_view name, const Visitor& visit)
      : source_(source), name_(name), visit_(visit) {}

  ScanResult scan() {
    if (source_.remaining() < sizeof kMagic ||
        std::memcmp(source_.read(sizeof kMagic).data(), kMagic, sizeof kMagic) != 0) {
      throw Error(cat(name_, ": not an MCAP file (it does not start with MCAP's magic)"));
    }
    bool first = true;
    while (source_.remaining() >= 9) {
      const std::uint64_t at = source_.offset();
      const std::span<const std::uint8_t> head = source_.read(9);
      const std::uint8_t op = head[0];
      std::uint64_t length = 0;
      std::memcpy(&length, head.data() + 1, 8);
      if (first && op != kHeader) throw Error(cat(name_, ": the first record is not a Header"));
      first = false;
      if (length > source_.remaining()) return result_;  // cut short within this record
      where_ = cat(name_, ": record 0x", hex(op), " at offset ", at);
      if (op == kDataEnd || op == kFooter) {
        result_.complete = true;
        return result_;
      }
      if (!wanted(op)) {
        source_.skip(length);
        continue;
      }
      if (length > kLargestRecord) {
        throw Error(
            cat(where_, ": a record of ", length, " bytes (at most ", kLargestRecord, " read)"));
      }
      record(op, source_.read(static_cast<std::size_t>(length)), false);
    }
    return result_;  // cut short between records
  }

 private:
  static std::string hex(std::uint8_t op) {
    constexpr char kDigits[] = "0123456789abcdef";
    return {kDigits[op >> 4], kDigits[op & 15]};
  }

  bool wants_messages() const { return bool(visit_.schema || visit_.channel || visit_.message); }
  bool wanted(std::uint8_t op) const {
    switch (op) {
      case kHeader:
      case kSchema:
      case kChannel:
        return true;  // messages need their channels known, whoever visits them
      case kMessage:
      case kChunk:
        return wants_messages();
      case kAttachment:
        return bool(visit_.attachment);
      default:
        return false;
    }
  }

  void record(std::uint8_t op, std::span<const std::uint8_t> bytes, bool in_chunk) {
    Fields f(bytes, where_);
    switch (op) {
      case kHeader:
        result_.profile = f.string("profile");
        break;
      case kSchema:
        schema(f);
        break;
      case kChannel:
        channel(f);
        break;
      case kMessage:
        message(f);
        break;
      case kChunk:
        if (in_chunk) throw Error(cat(where_, ": a chunk inside a chunk"));
        chunk(f);
        break;
      case kAttachment:
        if (!in_chunk) attachment(f, bytes);
        break;
      default:
        break;  // indexes, metadata: not needed to read the messages
    }
  }

  void schema(Fields& f) {
    const std::uint16_t id = f.u16("id");
    Schema s;
    s.name = f.string("name");
    s.encoding = f.string("encoding");
    const std::span<const std::uint8_t> data = f.bytes32("data");
    s.data.assign(reinterpret_cast<const char*>(data.data()), data.size());
    if (id == 0) return;  // reserved for none: ignored, as the specification asks
    schemas_[id] = true;
    if (visit_.schema) visit_.schema(id, s);
  }

  void channel(Fields& f) {
    const std::uint16_t id = f.u16("id");
    Channel c;
    c.schema_id = f.u16("schema id");
    c.topic = f.string("topic");
    c.message_encoding = f.string("message encoding");
    const std::span<const std::uint8_t> metadata = f.bytes32("metadata");
    Fields map(metadata, where_);
    while (map.at() < metadata.size()) {
      const std::string_view key = map.string("metadata key");
      c.metadata.emplace_back(key, map.string("metadata value"));
    }
    if (c.schema_id != 0 && !schemas_.contains(c.schema_id)) {
      throw Error(cat(where_, ": channel ", id, " (", c.topic, ") names schema ", c.schema_id,
                      ", which is not declared before it"));
    }
    channels_[id] = true;
    if (visit_.channel) visit_.channel(id, c);
  }

  void message(Fields& f) {
    Message m;
    m.channel = f.u16("channel id");
    m.sequence = f.u32("sequence");
    m.log_time = f.u64("log time");
    m.publish_time = f.u64("publish time");
    m.data = f.rest();
    if (!channels_.contains(m.channel)) {
      throw Error(
          cat(where_, ": a message on channel ", m.channel, ", which is not declared before it"));
    }
    ++result_.messages;
    if (visit_.message) visit_.message(m);
  }

  void attachment(Fields& f, std::span<const std::uint8_t> bytes) {
    Attachment a;
    a.log_time = f.u64("log time");
    f.u64("create time");
    a.name = f.string("name");
    a.media_type = f.string("media type");
    a.data = f.bytes64("data");
    const std::size_t covered = f.at();
    const std::uint32_t crc = f.u32("crc");
    if (crc != 0 && crc != crc_of(bytes.first(covered))) {
      throw Error(cat(where_, ": attachment ", a.name, ": its CRC does not match its bytes"));
    }
    visit_.attachment(a);
  }

  void chunk(Fields& f) {
    f.u64("start time");
    f.u64("end time");
    const std::uint64_t size = f.u64("uncompressed size");
    const std::uint32_t crc = f.u32("uncompressed crc");
    const std::string_view compression = f.string("compression");
    const std::span<const std::uint8_t> records = f.bytes64("records");
    if (size > kLargestChunk) {
      throw Error(cat(where_, ": a chunk of ", size, " bytes uncompressed (at most ", kLargestChunk,
                      " read)"));
    }
    std::span<const std::uint8_t> plain = records;
    if (compression == "zstd") {
      const unsigned long long declared = ZSTD_getFrameContentSize(records.data(), records.size());
      if (declared == ZSTD_CONTENTSIZE_ERROR ||
          (declared != ZSTD_CONTENTSIZE_UNKNOWN && declared != size)) {
        throw Error(cat(where_, ": a chunk whose zstd frame does not hold its ", size, " bytes"));
      }
      chunk_.resize(static_cast<std::size_t>(size));
      const std::size_t n =
          ZSTD_decompress(chunk_.data(), chunk_.size(), records.data(), records.size());
      if (ZSTD_isError(n) || n != size) {
        throw Error(cat(where_, ": a chunk that does not decompress to its ", size, " bytes",
                        ZSTD_isError(n) ? cat(" (zstd: ", ZSTD_getErrorName(n), ")") : ""));
      }
      plain = chunk_;
    } else if (!compression.empty()) {
      throw Error(cat(where_, ": a chunk compressed with '", compression,
                      "', which this reader does not read (zstd, or none)"));
    } else if (records.size() != size) {
      throw Error(cat(where_, ": an uncompressed chunk of ", records.size(), " bytes says ", size));
    }
    if (crc != 0 && crc != crc_of(plain)) {
      throw Error(cat(where_, ": a chunk whose CRC does not match its records"));
    }
    const std::string chunk_where = where_;
    Fields inner(plain, chunk_where);
    while (inner.at() < plain.size()) {
      const std::uint8_t op = inner.u8("record's opcode");
      const std::span<const std::uint8_t> bytes = inner.bytes64("record");
      where_ = cat(chunk_where, ", its record 0x", hex(op));
      record(op, bytes, true);
    }
    where_ = chunk_where;
  }

  Source& source_;
  std::string name_;
  const Visitor& visit_;
  std::string where_;
  std::map<std::uint16_t, bool> schemas_, channels_;
  std::vector<std::uint8_t> chunk_;
  ScanResult result_;
};

}  // namespace

ScanResult scan(std::span<const std::uint8_t> bytes, std::string_view name, const Visitor& visit) {
  MemorySource source(bytes);
  return Scanner(source, name, visit).scan();
}

ScanResult scan_file(const std::filesystem::path& file, const Visitor& visit) {
  FileSource source(file);
  return Scanner(source, file.string(), visit).scan();
}

bool is_mcap_file(const std::filesystem::path& file) {
  std::uint8_t magic[sizeof kMagic] = {};
  std::FILE* f = std::fopen(file.c_str(), "rbe");
  if (f == nullptr) return false;
  const bool read = std::fread(magic, 1, sizeof magic, f) == sizeof magic;
  std::fclose(f);
  return read && std::memcmp(magic, kMagic, sizeof kMagic) == 0;
}

std::optional<std::string> read_attachment(const std::filesystem::path& file,
                                           std::string_view name) {
  std::optional<std::string> found;
  Visitor visit;
  visit.attachment = [&](const Attachment& a) {
    if (!found && a.name == name) {
      found.emplace(reinterpret_cast<const char*>(a.data.data()), a.data.size());
    }
  };
  scan_file(file, visit);
  return found;
}

}  // namespace epipole::mcap
