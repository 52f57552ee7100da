#pragma once

// A Foxglove WebSocket server (the protocol Foxglove and Lichtblick connect with, subprotocols
// foxglove.websocket.v1 and foxglove.sdk.v1; docs/live-view.md) over civetweb: it advertises
// channels of ROS 2 messages (`cdr`, with `ros2msg` schemas), takes subscribe and unsubscribe,
// and sends each subscribed message as binary Message Data. Read-only: what a client would
// publish, set or call is refused with a status message.
//
// Each client has a slot, allocated at start-up for at most `max_clients`: per channel the
// freshest message not yet sent, and a thread of its own that sends them in the order they
// came. publish() copies into the slots of the clients subscribed and returns; a client that
// reads slowly gets messages replaced before they were sent, counted as dropped, and never makes
// the publisher wait for it. A client that takes nothing for 10 s while a message is being
// written to it is cut off (nothing more is sent) and closed.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "epipole/firmware/journal.hpp"

struct mg_context;
struct mg_connection;

namespace epipole::firmware::view {

struct Channel {
  std::string topic;        // "/epipole/left/image_rect"
  std::string schema_name;  // "sensor_msgs/msg/Image"
  std::string schema;       // its ros2msg definition
  std::size_t largest = 0;  // the largest message it sends (bytes of CDR)
  bool latched = false;     // its last message is sent to each new subscriber (/tf_static)
};

struct ServerSettings {
  std::string bind = "127.0.0.1";  // the address it listens on
  int port = 8765;                 // 0: a free port the system picks (tests)
  int max_clients = 4;             // more are refused at the handshake
  std::string name;                // serverInfo's name
};

struct ServerCounters {
  std::uint64_t clients = 0;   // connected, in all
  std::uint64_t refused = 0;   // over max_clients, or without a Foxglove subprotocol
  std::uint64_t sent = 0;      // messages sent
  std::uint64_t dropped = 0;   // replaced by a fresher one before they were sent
  std::uint64_t rejected = 0;  // client requests refused (malformed, unknown, not allowed)
};

class FoxgloveServer {
 public:
  FoxgloveServer(ServerSettings settings, std::vector<Channel> channels);
  ~FoxgloveServer();
  FoxgloveServer(const FoxgloveServer&) = delete;
  FoxgloveServer& operator=(const FoxgloveServer&) = delete;

  // Every HTTP request but the WebSocket's goes to `handler` (on civetweb's threads; it returns
  // the status it sent). Set before start().
  void serve_http(std::function<int(mg_connection*)> handler) { http_ = std::move(handler); }
  // Listens; throws Error naming the address when it cannot.
  void start();
  // Closes every client and stops listening.
  void stop();
  int port() const { return port_; }

  // Whether any client is subscribed to `channel` (else its message need not be made).
  bool subscribed(std::uint16_t channel) const {
    return subscribers_[channel].load(std::memory_order_relaxed) > 0 || channels_[channel].latched;
  }
  // The message to every client subscribed to `channel` (time: ns since the epoch).
  void publish(std::uint16_t channel, std::uint64_t time_ns, std::span<const std::uint8_t> data);

  ServerCounters counters() const;
  std::size_t working_set_bytes() const;

  // civetweb's callbacks (foxglove_server.cpp).
  struct Client;
  int on_connect(const mg_connection* conn);
  void on_ready(mg_connection* conn);
  int on_data(mg_connection* conn, int bits, const char* data, std::size_t length);
  void on_close(const mg_connection* conn);

 private:
  void send_loop(Client& client);
  void handle_request(Client& client, mg_connection* conn, std::string_view text);
  void subscribe(Client& client, mg_connection* conn, std::int64_t id, std::int64_t channel);
  void unsubscribe(Client& client, mg_connection* conn, std::int64_t id);
  void queue(Client& client, std::uint16_t channel, std::int64_t subscription,
             std::uint64_t time_ns, std::span<const std::uint8_t> data);
  void status(mg_connection* conn, int level, const std::string& message);

  ServerSettings settings_;
  std::vector<Channel> channels_;
  std::function<int(mg_connection*)> http_;
  std::unique_ptr<std::atomic<int>[]> subscribers_;  // per channel
  std::vector<std::unique_ptr<Client>> clients_;
  std::mutex latched_mutex_;
  std::vector<std::vector<std::uint8_t>> latched_;  // per channel: its last message, if latched
  std::vector<std::uint64_t> latched_time_;
  mg_context* context_ = nullptr;
  int port_ = 0;
  std::string session_;
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> connected_{0}, refused_{0}, rejected_{0};
  std::mutex journal_mutex_;
  JournalLimit refusals_said_{60'000'000'000};
};

}  // namespace epipole::firmware::view
