#pragma once

// CDR as ROS 2 messages travel in (XCDR1, little endian): the 4-byte encapsulation header, then
// each field aligned to its own size (8-byte ones to 8) counted from after the header; strings
// as a u32 length that counts their terminating NUL, then the bytes and the NUL; sequences as a
// u32 count, then the elements; fixed arrays as their elements alone.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string_view>
#include <vector>

namespace epipole::cdr {

// Appends to a byte buffer the caller owns (reserved ahead: appending within its capacity never
// allocates).
class CdrWriter {
 public:
  // Writes the encapsulation header at the buffer's end; alignment counts from after it.
  explicit CdrWriter(std::vector<std::uint8_t>& out) : out_(out) {
    const std::uint8_t header[4] = {0x00, 0x01, 0x00, 0x00};  // CDR_LE, no options
    out_.insert(out_.end(), header, header + 4);
    origin_ = out_.size();
  }

  void u8(std::uint8_t v) { out_.push_back(v); }
  void boolean(bool v) { u8(v ? 1 : 0); }
  void u32(std::uint32_t v) { put(v); }
  void i32(std::int32_t v) { put(v); }
  void f32(float v) { put(v); }
  void f64(double v) { put(v); }
  void string(std::string_view s) {
    u32(static_cast<std::uint32_t>(s.size() + 1));
    out_.insert(out_.end(), s.begin(), s.end());
    out_.push_back(0);
  }
  void f64s(std::span<const double> values) {  // a fixed array
    for (const double v : values) f64(v);
  }
  // A sequence of bytes whose content the caller writes at the returned pointer (count bytes).
  std::uint8_t* byte_sequence(std::size_t count) {
    u32(static_cast<std::uint32_t>(count));
    const std::size_t at = out_.size();
    out_.resize(at + count);
    return out_.data() + at;
  }
  void align(std::size_t n) {
    while ((out_.size() - origin_) % n != 0) out_.push_back(0);
  }

 private:
  template <typename T>
  void put(T v) {
    align(sizeof(T));
    std::uint8_t bytes[sizeof(T)];
    std::memcpy(bytes, &v, sizeof(T));  // the targets are little endian, as the header says
    out_.insert(out_.end(), bytes, bytes + sizeof(T));
  }

  std::vector<std::uint8_t>& out_;
  std::size_t origin_ = 0;
};

}  // namespace epipole::cdr
