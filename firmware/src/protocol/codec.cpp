#include "epipole/firmware/protocol/codec.hpp"

#include <array>
#include <type_traits>
#include <utility>
#include <variant>

#include "epipole/core/bytes.hpp"
#include "epipole/core/crc32.hpp"
#include "epipole/core/error.hpp"
#include "epipole/firmware/protocol/fields.hpp"

namespace epipole::protocol {

namespace {

struct Writer {
  ByteWriter out;
  template <class T>
  void operator()(const char*, const T& value) {
    if constexpr (std::is_enum_v<T>) {
      out.u8(static_cast<std::uint8_t>(value));
    } else if constexpr (std::is_same_v<T, std::int32_t>) {
      out.i32(value);
    } else if constexpr (std::is_same_v<T, std::int16_t>) {
      out.u16(static_cast<std::uint16_t>(value));  // two's complement
    } else if constexpr (sizeof(T) == 1) {
      out.u8(value);
    } else if constexpr (sizeof(T) == 2) {
      out.u16(value);
    } else if constexpr (sizeof(T) == 4) {
      out.u32(value);
    } else {
      out.u64(value);
    }
  }
  template <class Items, class Each>
  void list(const char*, std::uint8_t count, int limit, const Items& items, Each each) {
    require(count <= limit, "protocol: a message holds at most ", limit, " items, not ",
            int{count});
    out.u8(count);
    for (int i = 0; i < count; ++i) each(*this, items[i]);
  }
  bool ok() const { return out.ok(); }
};

struct Reader {
  ByteReader in;
  bool valid = true;
  template <class T>
  void operator()(const char*, T& value) {
    if constexpr (std::is_enum_v<T>) {
      static_assert(sizeof(T) == 1, "a message's enums are one byte");
      const std::uint8_t raw = in.u8();
      valid = valid && raw <= static_cast<std::uint8_t>(last_value(T{}));
      value = static_cast<T>(raw);
    } else if constexpr (std::is_same_v<T, std::int32_t>) {
      value = in.i32();
    } else if constexpr (std::is_same_v<T, std::int16_t>) {
      value = static_cast<std::int16_t>(in.u16());
    } else if constexpr (sizeof(T) == 1) {
      value = in.u8();
    } else if constexpr (sizeof(T) == 2) {
      value = in.u16();
    } else if constexpr (sizeof(T) == 4) {
      value = in.u32();
    } else {
      value = in.u64();
    }
  }
  template <class Items, class Each>
  void list(const char*, std::uint8_t& count, int limit, Items& items, Each each) {
    count = in.u8();
    valid = valid && count <= limit;
    for (int i = 0; i < count && ok(); ++i) each(*this, items[i]);
  }
  bool ok() const { return valid && in.ok(); }
};

// What the fields alone cannot say: a grid's cells fill whole rows.
template <class M>
bool well_formed(const M&) {
  return true;
}
bool well_formed(const DepthGrid& grid) {
  return grid.columns >= 1 && grid.count % grid.columns == 0;
}

template <class M>
std::optional<Message> read_as(std::span<const std::uint8_t> body) {
  Reader reader{ByteReader(body)};
  M message{};
  fields(reader, message);
  if (!reader.ok() || reader.in.remaining() != 0 || !well_formed(message)) return std::nullopt;
  return Message(message);
}

// Calls f(std::type_identity<M>{}) for each message type M of the Message variant, until one
// call returns true; whether one did.
template <class F>
bool any_message_type(F&& f) {
  return [&]<std::size_t... I>(std::index_sequence<I...>) {
    return (f(std::type_identity<std::variant_alternative_t<I, Message>>{}) || ...);
  }
  (std::make_index_sequence<std::variant_size_v<Message>>{});
}

constexpr bool types_are_distinct() {
  return []<std::size_t... I>(std::index_sequence<I...>) {
    const std::array<MessageType, sizeof...(I)> types{
        std::variant_alternative_t<I, Message>::kType...};
    for (std::size_t i = 0; i < types.size(); ++i) {
      for (std::size_t j = i + 1; j < types.size(); ++j) {
        if (types[i] == types[j]) return false;
      }
    }
    return true;
  }
  (std::make_index_sequence<std::variant_size_v<Message>>{});
}
static_assert(types_are_distinct(), "two messages have the same type byte");

bool is_known(std::uint8_t type) {
  return any_message_type(
      [&](auto t) { return decltype(t)::type::kType == static_cast<MessageType>(type); });
}

}  // namespace

MessageType type_of(const Message& message) {
  return std::visit([](const auto& m) { return std::decay_t<decltype(m)>::kType; }, message);
}

const char* name_of(MessageType type) {
  const char* name = "unknown";
  any_message_type([&](auto t) {
    using M = typename decltype(t)::type;
    if (M::kType != type) return false;
    name = M::kName;
    return true;
  });
  return name;
}

std::optional<Message> decode_body(MessageType type, std::span<const std::uint8_t> body) {
  std::optional<Message> message;
  any_message_type([&](auto t) {
    using M = typename decltype(t)::type;
    if (M::kType != type) return false;
    message = read_as<M>(body);
    return true;
  });
  return message;
}

std::size_t encode_frame(const Message& message, std::uint16_t sequence,
                         std::span<std::uint8_t> out) {
  std::array<std::uint8_t, kMaxPayloadSize> payload{};
  Writer writer{ByteWriter(payload)};
  writer.out.u8(kVersion);
  writer.out.u8(static_cast<std::uint8_t>(type_of(message)));
  writer.out.u16(sequence);
  std::visit([&writer](const auto& m) { fields(writer, m); }, message);
  require(std::visit([](const auto& m) { return well_formed(m); }, message),
          "protocol: a depth grid whose cells do not fill whole rows");
  require(writer.ok() && writer.out.size() + kCrcSize <= payload.size(),
          "protocol: message body larger than ", kMaxBodySize, " bytes");
  const std::size_t covered = writer.out.size();
  writer.out.u32(crc32(std::span(payload.data(), covered)));
  const auto encoded = cobs_encode(std::span(payload.data(), writer.out.size()), out);
  require(encoded.has_value() && *encoded < out.size(), "protocol: frame buffer of ", out.size(),
          " bytes is too small");
  out[*encoded] = 0;
  return *encoded + 1;
}

std::optional<DecodedMessage> FrameDecoder::push(std::uint8_t byte) {
  if (byte != 0) {
    if (size_ < encoded_.size()) {
      encoded_[size_++] = byte;
    } else {
      overflowed_ = true;
    }
    return std::nullopt;
  }
  std::optional<DecodedMessage> result = finish_frame();
  size_ = 0;
  overflowed_ = false;
  return result;
}

std::optional<DecodedMessage> FrameDecoder::finish_frame() {
  if (overflowed_) {
    ++stats_.too_long;
    return std::nullopt;
  }
  if (size_ == 0) {
    ++stats_.empty;
    return std::nullopt;
  }
  const auto decoded = cobs_decode(std::span(encoded_.data(), size_), payload_);
  if (!decoded) {
    ++stats_.bad_cobs;
    return std::nullopt;
  }
  const std::size_t n = *decoded;
  if (n < kHeaderSize + kCrcSize) {
    ++stats_.bad_body;
    return std::nullopt;
  }
  ByteReader crc_reader(std::span(payload_.data() + n - kCrcSize, kCrcSize));
  if (crc_reader.u32() != crc32(std::span(payload_.data(), n - kCrcSize))) {
    ++stats_.bad_crc;
    return std::nullopt;
  }
  if (payload_[0] != kVersion) {
    ++stats_.bad_version;
    return std::nullopt;
  }
  if (!is_known(payload_[1])) {
    ++stats_.unknown_type;
    return std::nullopt;
  }
  const auto type = static_cast<MessageType>(payload_[1]);
  const auto sequence = static_cast<std::uint16_t>(payload_[2] | payload_[3] << 8);
  std::optional<Message> message =
      decode_body(type, std::span(payload_.data() + kHeaderSize, n - kHeaderSize - kCrcSize));
  if (!message) {
    ++stats_.bad_body;
    return std::nullopt;
  }
  // Sequence numbers: 0 out of turn (not the last one sent again), or a large step back, is a
  // sender that restarted; a small step back is a replay when that number was delivered, and a
  // frame late past a newer one when it was not; a step forward of more than one means frames
  // were lost on the way (until they come late).
  if (have_sequence_) {
    const auto step =
        static_cast<std::int16_t>(static_cast<std::uint16_t>(sequence - last_sequence_));
    const bool restarted = (sequence == 0 && step != 1 && step != 0) || step <= -kReplayWindow;
    if (restarted) {
      ++stats_.resyncs;
      delivered_ = 0;
    } else if (step <= 0) {
      const std::uint64_t bit = std::uint64_t{1} << -step;
      if ((delivered_ & bit) == 0) {  // late, not repeated: counted lost when it was skipped
        delivered_ |= bit;
        if (stats_.lost > 0) --stats_.lost;
        ++stats_.frames;
        return DecodedMessage{sequence, std::move(*message)};
      }
      ++stats_.replays;
      if (!deliver_replays_) return std::nullopt;
      ++stats_.frames;
      return DecodedMessage{sequence, std::move(*message), true};
    } else {
      stats_.lost += static_cast<std::uint64_t>(step - 1);
      delivered_ = step >= 64 ? 0 : delivered_ << step;
    }
  }
  have_sequence_ = true;
  last_sequence_ = sequence;
  delivered_ |= 1;
  ++stats_.frames;
  return DecodedMessage{sequence, std::move(*message)};
}

void FrameDecoder::reset() {
  size_ = 0;
  overflowed_ = false;
  have_sequence_ = false;
  delivered_ = 0;
}

}  // namespace epipole::protocol
