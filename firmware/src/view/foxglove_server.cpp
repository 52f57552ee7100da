#include "view/foxglove_server.hpp"

#include <civetweb.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <nlohmann/json.hpp>

#include "epipole/core/error.hpp"
#include "epipole/core/resident.hpp"
#include "epipole/firmware/journal.hpp"
#include "epipole/firmware/thread_roles.hpp"
#include "steady_time.hpp"
#include "system_time.hpp"

namespace epipole::firmware::view {

namespace {

using nlohmann::json;

constexpr const char* kSubprotocols[] = {"foxglove.websocket.v1", "foxglove.sdk.v1"};
constexpr std::uint8_t kMessageData = 0x01;
constexpr std::size_t kFrameHeader = 1 + 4 + 8;  // opcode, subscription id, time
constexpr std::size_t kLargestRequest = 64 * 1024;

FoxgloveServer& server_of(const mg_connection* conn) {
  return *static_cast<FoxgloveServer*>(mg_get_user_data(mg_get_context(conn)));
}

void write_text(mg_connection* conn, const std::string& text) {
  mg_lock_connection(conn);
  mg_websocket_write(conn, MG_WEBSOCKET_OPCODE_TEXT, text.data(), text.size());
  mg_unlock_connection(conn);
}

}  // namespace

struct FoxgloveServer::Client {
  struct Pending {
    std::vector<std::uint8_t> frame;  // the Message Data frame, whole
    std::uint64_t order = 0;
    bool due = false;
  };
  std::mutex mutex;
  std::condition_variable wake;
  bool taken = false;             // a connection holds this slot (from its handshake)
  mg_connection* conn = nullptr;  // once it is ready
  bool writing = false;           // the sender writes to conn: a close waits for it
  bool broken = false;            // a write did not finish: nothing more is sent, it is closed
  bool stop = false;
  std::vector<std::int64_t> subscription;  // per channel: the client's id for it, -1 none
  std::vector<Pending> pending;            // per channel
  std::vector<std::uint8_t> sending;
  std::uint64_t order = 0;
  std::atomic<std::uint64_t> sent{0}, dropped{0};  // read without the lock (health)
  std::thread sender;
};

FoxgloveServer::FoxgloveServer(ServerSettings settings, std::vector<Channel> channels)
    : settings_(std::move(settings)),
      channels_(std::move(channels)),
      subscribers_(std::make_unique<std::atomic<int>[]>(channels_.size())),
      latched_(channels_.size()),
      latched_time_(channels_.size(), 0) {
  require(channels_.size() < 65535, "view: too many channels");
  std::size_t largest = 0;
  for (const Channel& c : channels_) largest = std::max(largest, c.largest);
  for (int i = 0; i < settings_.max_clients; ++i) {
    auto client = std::make_unique<Client>();
    client->subscription.assign(channels_.size(), -1);
    client->pending.resize(channels_.size());
    for (std::size_t c = 0; c < channels_.size(); ++c) {
      reserve_resident(client->pending[c].frame, kFrameHeader + channels_[c].largest);
    }
    reserve_resident(client->sending, kFrameHeader + largest);
    clients_.push_back(std::move(client));
  }
  for (std::size_t c = 0; c < channels_.size(); ++c) {
    if (channels_[c].latched) reserve_resident(latched_[c], channels_[c].largest);
  }
}

FoxgloveServer::~FoxgloveServer() {
  stop();
}

std::size_t FoxgloveServer::working_set_bytes() const {
  std::size_t bytes = 0;
  for (const auto& client : clients_) {
    bytes += client->sending.capacity();
    for (const Client::Pending& p : client->pending) bytes += p.frame.capacity();
  }
  for (const auto& l : latched_) bytes += l.capacity();
  return bytes;
}

void FoxgloveServer::start() {
  mg_init_library(0);
  session_ = std::to_string(detail::system_now_ns());
  const std::string ports = settings_.bind + ":" + std::to_string(settings_.port);
  // A thread per connected client, and some for the page and connections opened but idle.
  const std::string threads = std::to_string(settings_.max_clients + 6);
  // Clients that only listen (Foxglove after subscribing) are kept: pinged when quiet, not timed
  // out. A write a client does not take within request_timeout_ms gives up (the client is then
  // closed), as does a connection that sends no request.
  const char* options[] = {"listening_ports",
                           ports.c_str(),
                           "num_threads",
                           threads.c_str(),
                           "enable_websocket_ping_pong",
                           "yes",
                           "websocket_timeout_ms",
                           "10000",
                           "request_timeout_ms",
                           "10000",
                           nullptr};
  mg_callbacks callbacks{};
  mg_init_data init{&callbacks, this, options};
  std::array<char, 256> error_text{};
  unsigned code = 0;
  mg_error_data error{&code, error_text.data(), error_text.size()};
  context_ = mg_start2(&init, &error);
  if (context_ == nullptr) {
    throw Error(cat("outputs.view: cannot listen on ", ports, ": ", error_text.data(),
                    " (another program on that port? outputs.view.port chooses another)"));
  }
  mg_server_port port{};
  port_ = mg_get_server_ports(context_, 1, &port) == 1 ? port.port : settings_.port;
  for (const auto& client : clients_) {
    client->sender = std::thread([this, c = client.get()] {
      enter_thread_role_or_say(ThreadRole::output);
      send_loop(*c);
    });
  }
  if (http_) {
    mg_set_request_handler(
        context_, "/",
        [](mg_connection* conn, void* self) {
          return static_cast<FoxgloveServer*>(self)->http_(conn);
        },
        this);
  }
  static mg_websocket_subprotocols subprotocols{
      2, const_cast<const char**>(static_cast<const char* const*>(kSubprotocols))};
  mg_set_websocket_handler_with_subprotocols(
      context_, "/", &subprotocols,
      [](const mg_connection* conn, void*) { return server_of(conn).on_connect(conn); },
      [](mg_connection* conn, void*) { server_of(conn).on_ready(conn); },
      [](mg_connection* conn, int bits, char* data, std::size_t length, void*) {
        return server_of(conn).on_data(conn, bits, data, length);
      },
      [](const mg_connection* conn, void*) { server_of(conn).on_close(conn); }, nullptr);
}

void FoxgloveServer::stop() {
  if (context_ == nullptr) return;
  stopping_ = true;
  mg_stop(context_);  // closes every connection (on_close for each), joins its threads
  context_ = nullptr;
  for (const auto& client : clients_) {
    {
      const std::lock_guard lock(client->mutex);
      client->stop = true;
    }
    client->wake.notify_all();
    if (client->sender.joinable()) client->sender.join();
  }
}

int FoxgloveServer::on_connect(const mg_connection* conn) {
  const mg_request_info* request = mg_get_request_info(conn);
  if (stopping_ || request->acceptedWebSocketSubprotocol == nullptr) {
    ++refused_;
    return 1;  // not a Foxglove client: no subprotocol of ours
  }
  // A key of any other length than the 24 characters of RFC 6455 fails civetweb's handshake
  // after this: refused here, before it takes a slot that no close would give back.
  const char* key = mg_get_header(conn, "Sec-WebSocket-Key");
  if (key == nullptr || std::strlen(key) != 24) {
    ++refused_;
    return 1;
  }
  for (const auto& client : clients_) {
    const std::lock_guard lock(client->mutex);
    if (client->taken) continue;
    client->taken = true;
    mg_set_user_connection_data(conn, client.get());
    return 0;
  }
  ++refused_;
  const std::lock_guard lock(journal_mutex_);
  if (refusals_said_.allow(detail::steady_now())) {
    const unsigned long long more = refusals_said_.left_out();
    journal(Priority::warning, "output view: a client from %s refused: %d clients already%s",
            request->remote_addr, settings_.max_clients,
            more > 0 ? cat(" (", more, " more refused since the last line)").c_str() : "");
  }
  return 1;
}

void FoxgloveServer::on_ready(mg_connection* conn) {
  auto* client = static_cast<Client*>(mg_get_user_connection_data(conn));
  if (client == nullptr) return;
  ++connected_;
  json info = {{"op", "serverInfo"},
               {"name", settings_.name},
               {"capabilities", json::array()},
               {"sessionId", session_}};
  write_text(conn, info.dump());
  json advertise = {{"op", "advertise"}, {"channels", json::array()}};
  for (std::size_t c = 0; c < channels_.size(); ++c) {
    advertise["channels"].push_back({{"id", c},
                                     {"topic", channels_[c].topic},
                                     {"encoding", "cdr"},
                                     {"schemaName", channels_[c].schema_name},
                                     {"schema", channels_[c].schema},
                                     {"schemaEncoding", "ros2msg"}});
  }
  write_text(conn, advertise.dump());
  {
    const std::lock_guard lock(client->mutex);
    client->conn = conn;
  }
}

int FoxgloveServer::on_data(mg_connection* conn, int bits, const char* data, std::size_t length) {
  auto* client = static_cast<Client*>(mg_get_user_connection_data(conn));
  const int opcode = bits & 0x0f;
  if (client == nullptr || opcode == MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE) return 0;
  {
    const std::lock_guard lock(client->mutex);
    if (client->broken) return 0;  // its stream was cut within a frame: closed
  }
  // (civetweb answers pings itself.)
  if (opcode == MG_WEBSOCKET_OPCODE_PING || opcode == MG_WEBSOCKET_OPCODE_PONG) return 1;
  if (opcode == MG_WEBSOCKET_OPCODE_CONTINUATION || (bits & 0x80) == 0) {
    ++rejected_;
    status(conn, 2, "a request in fragments: requests are read whole (one frame each)");
    return 1;
  }
  if (opcode != MG_WEBSOCKET_OPCODE_TEXT) {
    ++rejected_;
    status(conn, 2, "this server is read-only: it takes no client messages");
    return 1;
  }
  if (length > kLargestRequest) {
    ++rejected_;
    status(conn, 2, cat("a request of ", length, " bytes (at most ", kLargestRequest, ")"));
    return 1;
  }
  handle_request(*client, conn, {data, length});
  return 1;
}

void FoxgloveServer::on_close(const mg_connection* conn) {
  auto* client = static_cast<Client*>(mg_get_user_connection_data(conn));
  if (client == nullptr) return;
  std::unique_lock lock(client->mutex);
  client->wake.wait(lock, [&] { return !client->writing; });
  for (std::size_t c = 0; c < channels_.size(); ++c) {
    if (client->subscription[c] >= 0) --subscribers_[c];
    client->subscription[c] = -1;
    client->pending[c].due = false;
  }
  client->conn = nullptr;
  client->taken = false;
  client->broken = false;
}

void FoxgloveServer::status(mg_connection* conn, int level, const std::string& message) {
  write_text(conn, json{{"op", "status"}, {"level", level}, {"message", message}}.dump());
}

void FoxgloveServer::handle_request(Client& client, mg_connection* conn, std::string_view text) {
  const json request = json::parse(text, nullptr, false);
  const auto refuse = [&](const std::string& why) {
    ++rejected_;
    status(conn, 2, why);
  };
  if (!request.is_object() || !request.contains("op") || !request["op"].is_string()) {
    return refuse("a request that is not a JSON object with an 'op'");
  }
  const std::string op = request["op"].get<std::string>();
  const auto number = [](const json& j, const char* key) -> std::int64_t {
    const auto it = j.find(key);
    return it != j.end() && it->is_number_integer() ? it->get<std::int64_t>() : -1;
  };
  if (op == "subscribe" && request.contains("subscriptions") &&
      request["subscriptions"].is_array()) {
    for (const json& s : request["subscriptions"]) {
      if (!s.is_object()) return refuse("subscribe: a subscription that is not an object");
      subscribe(client, conn, number(s, "id"), number(s, "channelId"));
    }
  } else if (op == "unsubscribe" && request.contains("subscriptionIds") &&
             request["subscriptionIds"].is_array()) {
    for (const json& id : request["subscriptionIds"]) {
      unsubscribe(client, conn, id.is_number_integer() ? id.get<std::int64_t>() : -1);
    }
  } else if (op == "subscribe" || op == "unsubscribe") {
    refuse(op + ": its list is missing");
  } else {
    refuse("'" + op + "' is not served: this server is read-only (subscribe and unsubscribe)");
  }
}

void FoxgloveServer::subscribe(Client& client, mg_connection* conn, std::int64_t id,
                               std::int64_t channel) {
  if (id < 0 || id > 0xffffffffLL || channel < 0 ||
      channel >= static_cast<std::int64_t>(channels_.size())) {
    ++rejected_;
    return status(conn, 2, cat("subscribe: no channel ", channel, " (or id ", id, " is bad)"));
  }
  const auto c = static_cast<std::size_t>(channel);
  bool taken = false;
  {
    const std::lock_guard lock(client.mutex);
    taken = client.subscription[c] >= 0 ||
            std::find(client.subscription.begin(), client.subscription.end(), id) !=
                client.subscription.end();
    if (!taken) {
      client.subscription[c] = id;
      ++subscribers_[c];
    }
  }
  if (taken) {
    ++rejected_;
    return status(conn, 1, cat("subscribe: id ", id, " or channel ", channel, " in use"));
  }
  if (channels_[c].latched) {
    const std::lock_guard latched(latched_mutex_);
    if (!latched_[c].empty()) {
      const std::lock_guard lock(client.mutex);
      queue(client, static_cast<std::uint16_t>(c), id, latched_time_[c], latched_[c]);
    }
  }
}

void FoxgloveServer::unsubscribe(Client& client, mg_connection* conn, std::int64_t id) {
  {
    const std::lock_guard lock(client.mutex);
    const auto it = std::find(client.subscription.begin(), client.subscription.end(), id);
    if (id >= 0 && it != client.subscription.end()) {
      const auto c = static_cast<std::size_t>(it - client.subscription.begin());
      *it = -1;
      --subscribers_[c];
      client.pending[c].due = false;
      return;
    }
  }
  ++rejected_;
  status(conn, 1, cat("unsubscribe: no subscription ", id));
}

// (The client's mutex held.)
void FoxgloveServer::queue(Client& client, std::uint16_t channel, std::int64_t subscription,
                           std::uint64_t time_ns, std::span<const std::uint8_t> data) {
  Client::Pending& p = client.pending[channel];
  if (client.broken) return;
  if (p.due) ++client.dropped;
  p.frame.resize(kFrameHeader + data.size());
  p.frame[0] = kMessageData;
  const auto id = static_cast<std::uint32_t>(subscription);
  std::memcpy(p.frame.data() + 1, &id, 4);
  std::memcpy(p.frame.data() + 5, &time_ns, 8);
  std::memcpy(p.frame.data() + kFrameHeader, data.data(), data.size());
  p.order = ++client.order;
  p.due = true;
  client.wake.notify_all();
}

void FoxgloveServer::publish(std::uint16_t channel, std::uint64_t time_ns,
                             std::span<const std::uint8_t> data) {
  if (channels_[channel].latched) {
    const std::lock_guard lock(latched_mutex_);
    latched_[channel].assign(data.begin(), data.end());
    latched_time_[channel] = time_ns;
  }
  if (subscribers_[channel].load(std::memory_order_relaxed) == 0) return;
  for (const auto& client : clients_) {
    const std::lock_guard lock(client->mutex);
    if (client->conn == nullptr || client->subscription[channel] < 0) continue;
    queue(*client, channel, client->subscription[channel], time_ns, data);
  }
}

void FoxgloveServer::send_loop(Client& client) {
  std::unique_lock lock(client.mutex);
  const auto next = [&]() -> Client::Pending* {
    Client::Pending* first = nullptr;
    for (Client::Pending& p : client.pending) {
      if (p.due && (first == nullptr || p.order < first->order)) first = &p;
    }
    return first;
  };
  for (;;) {
    client.wake.wait(
        lock, [&] { return client.stop || (client.conn != nullptr && !client.broken && next()); });
    if (client.stop) return;
    Client::Pending* p = next();
    client.sending.assign(p->frame.begin(), p->frame.end());
    p->due = false;
    mg_connection* conn = client.conn;
    client.writing = true;
    lock.unlock();
    mg_lock_connection(conn);
    const int written = mg_websocket_write(conn, MG_WEBSOCKET_OPCODE_BINARY,
                                           reinterpret_cast<const char*>(client.sending.data()),
                                           client.sending.size());
    mg_unlock_connection(conn);
    lock.lock();
    client.writing = false;
    if (written == static_cast<int>(client.sending.size())) {
      ++client.sent;
    } else {
      // Cut off within a frame (a client that stopped reading, past the write timeout): what
      // would follow could not be read. Nothing more goes to it; it is closed at its next word.
      client.broken = true;
      for (Client::Pending& pending : client.pending) pending.due = false;
    }
    client.wake.notify_all();
  }
}

ServerCounters FoxgloveServer::counters() const {
  ServerCounters c;
  c.clients = connected_;
  c.refused = refused_;
  c.rejected = rejected_;
  for (const auto& client : clients_) {
    c.sent += client->sent.load(std::memory_order_relaxed);
    c.dropped += client->dropped.load(std::memory_order_relaxed);
  }
  return c;
}

}  // namespace epipole::firmware::view
