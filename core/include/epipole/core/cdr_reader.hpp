#pragma once

// Reading CDR as ROS 2 messages travel in (XCDR1, little endian; cdr_writer.hpp says how it is
// laid out). Every field is checked against the bytes left: a message that ends early, or says it
// is big endian, throws Error naming `what` the message is.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>

#include "epipole/core/error.hpp"

namespace epipole::cdr {

class CdrReader {
 public:
  CdrReader(std::span<const std::uint8_t> bytes, std::string_view what)
      : bytes_(bytes), what_(what) {
    require(bytes.size() >= 4, what_, ": shorter than CDR's encapsulation header");
    require(bytes[0] == 0x00 && bytes[1] == 0x01, what_,
            ": not little-endian CDR (its encapsulation is ", int(bytes[0]), ", ", int(bytes[1]),
            ")");
    at_ = 4;
  }

  std::uint8_t u8() { return get<std::uint8_t>("a byte"); }
  bool boolean() { return u8() != 0; }
  std::uint32_t u32() { return get<std::uint32_t>("a 32-bit field"); }
  std::int32_t i32() { return get<std::int32_t>("a 32-bit field"); }
  float f32() { return get<float>("a float"); }
  double f64() { return get<double>("a double"); }
  // A string: its length counts the terminating NUL, which is not returned.
  std::string_view string() {
    const std::uint32_t n = u32();
    require(n >= 1, what_, ": a string without its terminating NUL");
    const std::span<const std::uint8_t> s = take(n, "a string");
    return {reinterpret_cast<const char*>(s.data()), n - 1};
  }
  // A sequence of bytes.
  std::span<const std::uint8_t> byte_sequence() { return take(u32(), "a sequence of bytes"); }
  void align(std::size_t n) {
    const std::size_t pad = (n - (at_ - 4) % n) % n;
    take(pad, "padding");
  }

 private:
  template <typename T>
  T get(const char* field) {
    align(sizeof(T));
    T v;
    std::memcpy(&v, take(sizeof(T), field).data(), sizeof(T));  // the targets are little endian
    return v;
  }
  std::span<const std::uint8_t> take(std::size_t n, const char* field) {
    require(n <= bytes_.size() - at_, what_, ": ends inside ", field, " (", n, " bytes at ", at_,
            " of ", bytes_.size(), ")");
    const std::span<const std::uint8_t> s = bytes_.subspan(at_, n);
    at_ += n;
    return s;
  }

  std::span<const std::uint8_t> bytes_;
  std::string what_;
  std::size_t at_ = 0;
};

}  // namespace epipole::cdr
