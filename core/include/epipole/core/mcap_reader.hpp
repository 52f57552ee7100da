#pragma once

// Reading MCAP files (mcap.dev/spec, version 0) as the format's scanning readers do: the data
// section from the start, in the order it was written, each chunk decompressed (zstd, or none)
// and its CRC checked. The summary is not needed, so a recording cut short (power lost) gives
// every whole record written before the cut. What is malformed (a record that overruns the one
// holding it, a message on a channel never declared, a CRC that does not match, a compression it
// cannot read) throws Error naming the file and the offset.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "epipole/core/mcap_writer.hpp"

namespace epipole::mcap {

struct Message {
  std::uint16_t channel = 0;  // a channel declared before it
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0, publish_time = 0;  // ns since the epoch
  std::span<const std::uint8_t> data;            // valid during the call only
};

struct Attachment {
  std::string_view name, media_type;
  std::uint64_t log_time = 0;
  std::span<const std::uint8_t> data;  // valid during the call only
};

// What a scan calls for each record of interest; any may be left empty.
struct Visitor {
  std::function<void(std::uint16_t id, const Schema&)> schema;
  std::function<void(std::uint16_t id, const Channel&)> channel;
  std::function<void(const Message&)> message;
  std::function<void(const Attachment&)> attachment;
};

struct ScanResult {
  std::string profile;    // the header's ("ros2")
  bool complete = false;  // the data section ended (DataEnd); false: the file was cut short
  std::uint64_t messages = 0;
};

// Scans bytes in memory; `name` is what errors call them.
ScanResult scan(std::span<const std::uint8_t> bytes, std::string_view name, const Visitor& visit);
// Scans a file, a record at a time (a chunk's records are held decompressed while visited).
ScanResult scan_file(const std::filesystem::path& file, const Visitor& visit);

// Whether the file starts with MCAP's magic (false when it cannot be read).
bool is_mcap_file(const std::filesystem::path& file);

// The data of the first attachment named `name`, if the file has one.
std::optional<std::string> read_attachment(const std::filesystem::path& file,
                                           std::string_view name);

}  // namespace epipole::mcap
