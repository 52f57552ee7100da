#pragma once

// Little-endian bytes of untrusted or portable data: the serial protocol, the compiled cascade
// format.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>

namespace epipole {

// Little-endian writing into a fixed buffer. Writing past the end sets !ok() and writes nothing
// more; the caller checks ok() once at the end.
class ByteWriter {
 public:
  explicit ByteWriter(std::span<std::uint8_t> out) : out_(out) {}
  void u8(std::uint8_t v) { put(v, 1); }
  void u16(std::uint16_t v) { put(v, 2); }
  void u32(std::uint32_t v) { put(v, 4); }
  void u64(std::uint64_t v) { put(v, 8); }
  void i16(std::int16_t v) { put(static_cast<std::uint16_t>(v), 2); }
  void i32(std::int32_t v) { put(static_cast<std::uint32_t>(v), 4); }
  void f32(float v) { put(std::bit_cast<std::uint32_t>(v), 4); }
  bool ok() const { return ok_; }
  std::size_t size() const { return size_; }

 private:
  void put(std::uint64_t v, std::size_t bytes) {
    if (!ok_ || out_.size() - size_ < bytes) {
      ok_ = false;
      return;
    }
    for (std::size_t i = 0; i < bytes; ++i) out_[size_++] = static_cast<std::uint8_t>(v >> (8 * i));
  }
  std::span<std::uint8_t> out_;
  std::size_t size_ = 0;
  bool ok_ = true;
};

// Little-endian reading from untrusted bytes: reading past the end returns 0 and sets !ok().
class ByteReader {
 public:
  explicit ByteReader(std::span<const std::uint8_t> in) : in_(in) {}
  std::uint8_t u8() { return static_cast<std::uint8_t>(get(1)); }
  std::uint16_t u16() { return static_cast<std::uint16_t>(get(2)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(get(4)); }
  std::uint64_t u64() { return get(8); }
  std::int16_t i16() { return static_cast<std::int16_t>(static_cast<std::uint16_t>(get(2))); }
  std::int32_t i32() { return static_cast<std::int32_t>(static_cast<std::uint32_t>(get(4))); }
  float f32() { return std::bit_cast<float>(static_cast<std::uint32_t>(get(4))); }
  bool ok() const { return ok_; }
  std::size_t remaining() const { return in_.size() - position_; }

 private:
  std::uint64_t get(std::size_t bytes) {
    if (!ok_ || remaining() < bytes) {
      ok_ = false;
      return 0;
    }
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < bytes; ++i) v |= std::uint64_t{in_[position_++]} << (8 * i);
    return v;
  }
  std::span<const std::uint8_t> in_;
  std::size_t position_ = 0;
  bool ok_ = true;
};

}  // namespace epipole
