#pragma once

// A Foxglove WebSocket client small enough to run inside a test under qemu (no Node.js there):
// it connects to the live view on the loopback interface with the protocol's subprotocol,
// subscribes to every channel it advertises, then reads and discards what comes, in a thread of
// its own and with buffers taken before (nothing allocated while it reads). The independent
// client that checks the values is tests/clients/foxglove-view.mjs; this one only takes.
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "loopback.hpp"

namespace epipole::test {

class FoxgloveSocket {
 public:
  // Connects and subscribes; ok() says whether it did.
  explicit FoxgloveSocket(int port) : buffer_(1 << 20) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    const sockaddr_in a = loopback(port);
    if (::connect(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) return;
    const std::string request =
        "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
        "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n\r\n";
    if (!send_all(request.data(), request.size())) return;
    std::string head;
    char c = 0;
    while (head.find("\r\n\r\n") == std::string::npos && ::recv(fd_, &c, 1, 0) == 1) head += c;
    if (head.rfind("HTTP/1.1 101", 0) != 0) return;
    // serverInfo, then advertise: subscribe to every channel it names.
    std::size_t channels = 0;
    for (int frame = 0; frame < 2; ++frame) {
      const std::string text = read_text();
      for (std::size_t at = 0; (at = text.find("\"topic\"", at)) != std::string::npos; ++at) {
        if (frame == 1) ++channels;
      }
    }
    if (channels == 0) return;
    std::string subscribe = R"({"op":"subscribe","subscriptions":[)";
    for (std::size_t i = 0; i < channels; ++i) {
      subscribe += (i ? "," : "") + std::string(R"({"id":)") + std::to_string(i) +
                   R"(,"channelId":)" + std::to_string(i) + "}";
    }
    subscribe += "]}";
    if (!send_text(subscribe)) return;
    channels_ = channels;
    reader_ = std::thread([this] {
      while (!stop_ && read_frame()) ++frames_;
    });
  }
  ~FoxgloveSocket() {
    stop_ = true;
    ::shutdown(fd_, SHUT_RDWR);
    if (reader_.joinable()) reader_.join();
    ::close(fd_);
  }
  FoxgloveSocket(const FoxgloveSocket&) = delete;
  FoxgloveSocket& operator=(const FoxgloveSocket&) = delete;

  bool ok() const { return channels_ > 0; }
  std::uint64_t frames() const { return frames_; }  // binary and text, after subscribing

 private:
  bool send_all(const void* data, std::size_t size) {
    const auto* p = static_cast<const char*>(data);
    while (size > 0) {
      const ssize_t n = ::send(fd_, p, size, MSG_NOSIGNAL);
      if (n <= 0) return false;
      p += n;
      size -= static_cast<std::size_t>(n);
    }
    return true;
  }
  bool recv_all(void* data, std::size_t size) {
    auto* p = static_cast<char*>(data);
    while (size > 0) {
      const ssize_t n = ::recv(fd_, p, size, 0);
      if (n <= 0) return false;
      p += n;
      size -= static_cast<std::size_t>(n);
    }
    return true;
  }
  // A client's frame: masked (RFC 6455), here with a zero mask.
  bool send_text(const std::string& text) {
    std::vector<std::uint8_t> frame = {0x81};
    if (text.size() < 126) {
      frame.push_back(static_cast<std::uint8_t>(0x80 | text.size()));
    } else {
      frame.push_back(0x80 | 126);
      frame.push_back(static_cast<std::uint8_t>(text.size() >> 8));
      frame.push_back(static_cast<std::uint8_t>(text.size()));
    }
    frame.insert(frame.end(), {0, 0, 0, 0});
    frame.insert(frame.end(), text.begin(), text.end());
    return send_all(frame.data(), frame.size());
  }
  // One frame's payload length (its header read), or -1.
  long long frame_length() {
    std::array<std::uint8_t, 2> head{};
    if (!recv_all(head.data(), 2)) return -1;
    opcode_ = head[0] & 0x0f;
    std::uint64_t length = head[1] & 0x7f;
    if (length >= 126) {
      std::array<std::uint8_t, 8> ext{};
      const std::size_t n = length == 126 ? 2 : 8;
      if (!recv_all(ext.data(), n)) return -1;
      length = 0;
      for (std::size_t i = 0; i < n; ++i) length = (length << 8) | ext[i];
    }
    return static_cast<long long>(length);
  }
  std::string read_text() {
    const long long n = frame_length();
    if (n < 0 || static_cast<std::size_t>(n) > buffer_.size()) return "";
    if (!recv_all(buffer_.data(), static_cast<std::size_t>(n))) return "";
    return {reinterpret_cast<const char*>(buffer_.data()), static_cast<std::size_t>(n)};
  }
  // Reads one frame into the buffer, in pieces when it is larger.
  // Answers a ping as every WebSocket client does (the server closes a client that leaves its
  // pings unanswered).
  bool read_frame() {
    long long left = frame_length();
    const long long length = left;
    while (left > 0) {
      const std::size_t piece =
          std::min<std::size_t>(buffer_.size(), static_cast<std::size_t>(left));
      if (!recv_all(buffer_.data(), piece)) return false;
      left -= static_cast<long long>(piece);
    }
    if (left == 0 && opcode_ == 0x9 && length < 126) {
      std::array<std::uint8_t, 6 + 125> pong{0x8a, static_cast<std::uint8_t>(0x80 | length)};
      std::memcpy(pong.data() + 6, buffer_.data(), static_cast<std::size_t>(length));
      return send_all(pong.data(), 6 + static_cast<std::size_t>(length));  // a zero mask
    }
    return left == 0;
  }

  int fd_ = -1;
  int opcode_ = 0;  // of the frame being read
  std::vector<std::uint8_t> buffer_;
  std::size_t channels_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> frames_{0};
  std::thread reader_;
};

}  // namespace epipole::test
