// The MCAP reader: what the writer wrote comes back whole (schemas, channels, messages in order,
// attachments); a file cut anywhere gives every record before the cut; what is malformed is an
// error naming the file and where, never a crash or a wrong message.
#include "epipole/core/mcap_reader.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <vector>

#include "epipole/core/temporary_folder.hpp"
#include "error_of.hpp"

namespace epipole::mcap {
namespace {

struct Read {
  std::vector<std::pair<std::uint16_t, Schema>> schemas;
  std::vector<std::pair<std::uint16_t, Channel>> channels;
  struct Kept {
    std::uint16_t channel;
    std::uint32_t sequence;
    std::uint64_t log_time, publish_time;
    std::vector<std::uint8_t> data;
  };
  std::vector<Kept> messages;
  std::vector<std::pair<std::string, std::string>> attachments;  // name, data
  ScanResult result;
};

Visitor keeping(Read& r) {
  Visitor v;
  v.schema = [&](std::uint16_t id, const Schema& s) { r.schemas.emplace_back(id, s); };
  v.channel = [&](std::uint16_t id, const Channel& c) { r.channels.emplace_back(id, c); };
  v.message = [&](const Message& m) {
    r.messages.push_back({m.channel, m.sequence, m.log_time, m.publish_time,
                          std::vector<std::uint8_t>(m.data.begin(), m.data.end())});
  };
  v.attachment = [&](const Attachment& a) {
    r.attachments.emplace_back(std::string(a.name), std::string(a.data.begin(), a.data.end()));
  };
  return v;
}

Read read_bytes(const std::vector<std::uint8_t>& bytes) {
  Read r;
  r.result = scan(bytes, "test.mcap", keeping(r));
  return r;
}

std::vector<std::uint8_t> file_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The message i of the written files: its channel, and bytes of a length and content of its own.
std::uint16_t channel_of(int i) {
  return static_cast<std::uint16_t>(i % 3);
}
std::vector<std::uint8_t> data_of(int i) {
  std::vector<std::uint8_t> d(static_cast<std::size_t>(100 + (i * 37) % 900));
  for (std::size_t k = 0; k < d.size(); ++k) d[k] = static_cast<std::uint8_t>(i * 7 + k * k);
  return d;
}

constexpr int kMessages = 120;

// A file of three channels over two schemas, chunks of about 8 KiB, an attachment in between.
std::filesystem::path write_file(const std::filesystem::path& folder) {
  Writer w({{"pkg/msg/A", "ros2msg", "uint8[] data\n"}, {"pkg/msg/B", "ros2msg", "int32 x\n"}},
           {{1, "/a", "cdr", {{"offered_qos_profiles", "- history: 3\n"}}},
            {2, "/b", "cdr", {}},
            {1, "/c", "cdr", {{"k", "v"}, {"k2", ""}}}},
           8 * 1024, 4 * 1024);
  const std::filesystem::path file = folder / "test.mcap";
  w.open(file, "test");
  for (int i = 0; i < kMessages; ++i) {
    const std::vector<std::uint8_t> d = data_of(i);
    std::vector<std::uint8_t>& out =
        w.begin_message(channel_of(i), static_cast<std::uint32_t>(i),
                        1'000'000'000ull + static_cast<std::uint64_t>(i) * 1000, 7);
    out.insert(out.end(), d.begin(), d.end());
    w.end_message();
    if (i == 50) {
      const std::string yaml = "calibration: yes\n";
      w.attach("calibration.yaml", "application/yaml",
               {reinterpret_cast<const std::uint8_t*>(yaml.data()), yaml.size()}, 5);
    }
  }
  w.close();
  return file;
}

TEST(McapReader, ReadsBackWhatTheWriterWrote) {
  const TemporaryFolder dir("epipole-test");
  const std::filesystem::path file = write_file(dir.path());
  Read r;
  r.result = scan_file(file, keeping(r));
  EXPECT_TRUE(r.result.complete);
  EXPECT_EQ(r.result.profile, "ros2");
  ASSERT_EQ(r.schemas.size(), 2u);
  EXPECT_EQ(r.schemas[1].first, 2);
  EXPECT_EQ(r.schemas[1].second.name, "pkg/msg/B");
  EXPECT_EQ(r.schemas[1].second.data, "int32 x\n");
  ASSERT_EQ(r.channels.size(), 3u);
  EXPECT_EQ(r.channels[2].first, 2);
  EXPECT_EQ(r.channels[2].second.topic, "/c");
  EXPECT_EQ(r.channels[2].second.schema_id, 1);
  EXPECT_EQ(r.channels[2].second.metadata,
            (std::vector<std::pair<std::string, std::string>>{{"k", "v"}, {"k2", ""}}));
  EXPECT_EQ(r.channels[0].second.metadata.at(0).second, "- history: 3\n");
  ASSERT_EQ(r.messages.size(), static_cast<std::size_t>(kMessages));
  EXPECT_EQ(r.result.messages, static_cast<std::uint64_t>(kMessages));
  for (int i = 0; i < kMessages; ++i) {
    const Read::Kept& m = r.messages[static_cast<std::size_t>(i)];
    EXPECT_EQ(m.channel, channel_of(i));
    EXPECT_EQ(m.sequence, static_cast<std::uint32_t>(i));
    EXPECT_EQ(m.log_time, 1'000'000'000ull + static_cast<std::uint64_t>(i) * 1000);
    EXPECT_EQ(m.publish_time, 7u);
    EXPECT_EQ(m.data, data_of(i)) << "message " << i;
  }
  ASSERT_EQ(r.attachments.size(), 1u);
  EXPECT_EQ(r.attachments[0].second, "calibration: yes\n");
  EXPECT_EQ(read_attachment(file, "calibration.yaml"), "calibration: yes\n");
  EXPECT_EQ(read_attachment(file, "other"), std::nullopt);
  EXPECT_TRUE(is_mcap_file(file));
  EXPECT_FALSE(is_mcap_file(dir.path() / "missing.mcap"));
  // In memory, the same.
  const Read m = read_bytes(file_bytes(file));
  EXPECT_EQ(m.messages.size(), r.messages.size());
  EXPECT_EQ(m.attachments, r.attachments);
}

// Power lost while recording: wherever the file ends, what was written whole before is read and
// nothing else, and the scan says the file is not complete.
TEST(McapReader, AFileCutAnywhereGivesEveryWholeRecordBeforeTheCut) {
  const TemporaryFolder dir("epipole-test");
  const std::vector<std::uint8_t> whole = file_bytes(write_file(dir.path()));
  std::size_t before = 0;
  std::set<std::size_t> counts;  // of messages, over the cuts
  int cuts = 0;
  for (std::size_t length = 8; length < whole.size(); length += 211) {
    const std::vector<std::uint8_t> cut(whole.begin(),
                                        whole.begin() + static_cast<std::ptrdiff_t>(length));
    Read r;
    ASSERT_EQ(test::error_of([&] { r = read_bytes(cut); }), "") << "cut at " << length;
    ++cuts;
    if (length < whole.size() / 2) {
      EXPECT_FALSE(r.result.complete) << length;
    }
    EXPECT_GE(r.messages.size(), before) << "a longer file gives no fewer messages";
    before = r.messages.size();
    counts.insert(before);
    for (std::size_t i = 0; i < r.messages.size(); ++i) {
      ASSERT_EQ(r.messages[i].data, data_of(static_cast<int>(i))) << "cut at " << length;
    }
  }
  EXPECT_GT(cuts, 20);
  EXPECT_GT(counts.size(), 4u) << "the chunks come whole, one after another";
}

// Record by record, as a malformed file would have them.
class Bytes {
 public:
  template <typename T>
  Bytes& put(T v) {
    char raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof(T));
    b.append(raw, sizeof(T));
    return *this;
  }
  Bytes& string(const std::string& s) {
    put(static_cast<std::uint32_t>(s.size()));
    b += s;
    return *this;
  }
  Bytes& record(std::uint8_t op, const Bytes& content) {
    put(op).put(static_cast<std::uint64_t>(content.b.size()));
    b += content.b;
    return *this;
  }
  // With MCAP's magic first.
  std::vector<std::uint8_t> file() const {
    const std::string bytes = std::string("\x89MCAP0\r\n", 8) + b;
    return {bytes.begin(), bytes.end()};
  }
  std::string b;
};

Bytes with_header() {
  Bytes f;
  f.record(0x01, Bytes().string("ros2").string("test"));
  return f;
}

std::string scan_error(const std::vector<std::uint8_t>& bytes) {
  return test::error_of([&] { read_bytes(bytes); });
}

TEST(McapReader, MalformedFilesAreErrorsThatSayWhere) {
  EXPECT_NE(scan_error({'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd'})
                .find("test.mcap: not an MCAP file"),
            std::string::npos);
  EXPECT_NE(scan_error({}).find("not an MCAP file"), std::string::npos);
  // A message on a channel never declared.
  Bytes message = with_header();
  message.record(
      0x05,
      (Bytes().put<std::uint16_t>(4).put<std::uint32_t>(0).put<std::uint64_t>(1).put<std::uint64_t>(
          1)));
  EXPECT_NE(scan_error(message.file()).find("channel 4, which is not declared"), std::string::npos)
      << scan_error(message.file());
  // A channel whose schema is not declared.
  Bytes channel = with_header();
  channel.record(0x04, (Bytes()
                            .put<std::uint16_t>(0)
                            .put<std::uint16_t>(9)
                            .string("/t")
                            .string("cdr")
                            .put<std::uint32_t>(0)));
  EXPECT_NE(scan_error(channel.file()).find("names schema 9"), std::string::npos);
  // A string that says it is longer than its record.
  Bytes overrun = with_header();
  overrun.record(0x03,
                 (Bytes().put<std::uint16_t>(1).put<std::uint32_t>(1000).put<std::uint8_t>('x')));
  const std::string error = scan_error(overrun.file());
  EXPECT_NE(error.find("test.mcap: record 0x03 at offset 33"), std::string::npos) << error;
  EXPECT_NE(error.find("runs past the end of the record"), std::string::npos) << error;
  // A compression it does not read.
  Bytes lz4 = with_header();
  lz4.record(0x06, (Bytes()
                        .put<std::uint64_t>(0)
                        .put<std::uint64_t>(0)
                        .put<std::uint64_t>(4)
                        .put<std::uint32_t>(0)
                        .string("lz4")
                        .put<std::uint64_t>(4)
                        .put<std::uint32_t>(0)));
  EXPECT_NE(scan_error(lz4.file()).find("compressed with 'lz4'"), std::string::npos);
  // A chunk that says it is enormous.
  Bytes huge = with_header();
  huge.record(0x06, (Bytes()
                         .put<std::uint64_t>(0)
                         .put<std::uint64_t>(0)
                         .put<std::uint64_t>(1ull << 40)
                         .put<std::uint32_t>(0)
                         .string("zstd")
                         .put<std::uint64_t>(0)));
  EXPECT_NE(scan_error(huge.file()).find("bytes uncompressed"), std::string::npos);
  // No header first.
  Bytes headless;
  headless.record(0x0F, Bytes().put<std::uint32_t>(0));
  EXPECT_NE(scan_error(headless.file()).find("first record is not a Header"), std::string::npos);
}

// A byte changed in a compressed chunk: the CRC (or zstd itself) says so; nothing wrong is read.
TEST(McapReader, ADamagedChunkIsAnError) {
  const TemporaryFolder dir("epipole-test");
  const std::vector<std::uint8_t> whole = file_bytes(write_file(dir.path()));
  int errors = 0;
  for (std::size_t at = 600; at < whole.size() - 2000; at += 1499) {
    std::vector<std::uint8_t> damaged = whole;
    damaged[at] ^= 0x5a;
    Read r;
    const std::string error = test::error_of([&] { r = read_bytes(damaged); });
    if (!error.empty()) {
      ++errors;
      EXPECT_NE(error.find("test.mcap: record 0x"), std::string::npos) << error;
      continue;
    }
    // Undetected only where the byte is in no message: an index, a chunk's times; or in a
    // record's length, which then reads as the file's end. What is read is right.
    for (std::size_t i = 0; i < r.messages.size(); ++i) {
      EXPECT_EQ(r.messages[i].data, data_of(static_cast<int>(i))) << "damage at " << at;
    }
  }
  EXPECT_GT(errors, 0);
}

}  // namespace
}  // namespace epipole::mcap
