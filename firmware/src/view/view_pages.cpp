#include "view/view_pages.hpp"

#include <civetweb.h>

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string_view>

#include "epipole/core/resident.hpp"
#include "epipole/firmware/protocol/fields.hpp"
#include "steady_time.hpp"
#include "view/disparity_colours.hpp"
#include "view_page.hpp"

namespace epipole::firmware::view {

namespace {

using nlohmann::json;

// A page asked within this long: pictures are made.
constexpr std::int64_t kWatchedNs = 5'000'000'000;

// Health's fields as a JSON object of numbers, named as on the serial link (epipole link
// --json), appended to a buffer reserved ahead (nothing is allocated once a second).
struct HealthJson {
  std::vector<std::uint8_t>& out;
  void text(std::string_view s) { out.insert(out.end(), s.begin(), s.end()); }
  template <typename T>
  void operator()(const char* name, const T& value) {
    text(out.size() > 1 ? ",\"" : "\"");
    text(name);
    text("\":");
    char number[24];
    const auto [end, ec] = std::to_chars(number, number + sizeof number, +value);
    text({number, ec == std::errc() ? static_cast<std::size_t>(end - number) : 0});
  }
  template <typename... A>
  void list(A&&...) {}  // health has no lists
};

void store(std::vector<std::uint8_t>& to, std::string_view text) {
  to.assign(text.begin(), text.end());
}

}  // namespace

ViewPages::ViewPages(const BoardConfig& board, PageSettings settings)
    : board_(board),
      settings_(settings),
      encoder_(board.width(), board.height()),
      rgb_(static_cast<std::size_t>(board.width()) * board.height() * 3) {
  for (std::vector<std::uint8_t>* picture :
       {&left_jpeg_, &disparity_jpeg_, &left_spare_, &disparity_spare_}) {
    reserve_resident(*picture, encoder_.working_set_bytes());
  }
  reserve_resident(health_json_, 4096);
  reserve_resident(health_spare_, 4096);
}

std::size_t ViewPages::working_set_bytes() const {
  return encoder_.working_set_bytes() + rgb_.capacity() + left_jpeg_.capacity() +
         disparity_jpeg_.capacity() + left_spare_.capacity() + disparity_spare_.capacity();
}

bool ViewPages::due(std::int64_t now) const {
  return now - asked_.load(std::memory_order_relaxed) < kWatchedNs &&
         now - pictured_.load(std::memory_order_relaxed) >=
             static_cast<std::int64_t>(1e9 / settings_.picture_hz);
}

void ViewPages::picture(const outputs::PairCopy& pair, std::int64_t now) {
  pictured_.store(now, std::memory_order_relaxed);
  json frame = {{"frame", pair.frame},
                {"board", board_.name},
                {"width", board_.width()},
                {"height", board_.height()},
                {"max_disparity", board_.stereo.max_disparity},
                {"picture_hz", settings_.picture_hz},
                {"valid_disparity_permille", pair.valid_disparity_permille},
                {"corners", json::array()},
                {"detections", json::array()}};
  for (const vision::Corner& c : pair.corners) frame["corners"].push_back({c.x, c.y});
  for (std::size_t i = 0; i < pair.detections.size(); ++i) {
    const vision::Detection& d = pair.detections[i];
    const bool known = i < pair.detection_depths.size() && pair.detection_depths[i].valid;
    frame["detections"].push_back(
        {{"x", d.x},
         {"y", d.y},
         {"width", d.width},
         {"height", d.height},
         {"depth_m",
          known ? json(std::round(pair.detection_depths[i].depth * 1000) / 1000) : json(nullptr)}});
  }
  const std::string frame_text = frame.dump();
  left_spare_.clear();
  disparity_spare_.clear();
  if (pair.has_rectified) {
    const std::span<const std::uint8_t> jpeg = encoder_.gray(pair.left.view(), settings_.quality);
    left_spare_.assign(jpeg.begin(), jpeg.end());
  }
  if (pair.has_disparity) {
    const std::size_t stride = static_cast<std::size_t>(board_.width()) * 3;
    colour_disparity(pair.disparity.view(), board_.stereo.max_disparity, rgb_.data(), stride);
    const std::span<const std::uint8_t> jpeg =
        encoder_.rgb(rgb_.data(), board_.width(), board_.height(), stride, settings_.quality);
    disparity_spare_.assign(jpeg.begin(), jpeg.end());
  }
  const std::lock_guard lock(mutex_);
  left_jpeg_.swap(left_spare_);
  disparity_jpeg_.swap(disparity_spare_);
  store(frame_json_, frame_text);
  frame_ = pair.frame;
}

void ViewPages::health(const protocol::Health& health) {
  health_spare_.clear();
  HealthJson fields{health_spare_};
  fields.text("{");
  protocol::fields(fields, health);
  fields.text("}");
  const std::lock_guard lock(mutex_);
  health_json_.swap(health_spare_);
}

int ViewPages::send(mg_connection* conn, const char* type, const std::vector<std::uint8_t>& bytes,
                    const char* what) {
  const char* query = mg_get_request_info(conn)->query_string;
  std::vector<std::uint8_t> copy;  // sent without the lock: a slow browser holds nothing up
  std::int64_t latest = -1;
  {
    const std::lock_guard lock(mutex_);
    copy = bytes;
    latest = frame_;
  }
  if (copy.empty()) {
    mg_send_http_error(conn, 503, "no %s yet: the firmware has not made one", what);
    return 503;
  }
  if (query != nullptr && std::string_view(query).starts_with("frame=") &&
      std::atoll(query + 6) != latest) {
    mg_send_http_error(conn, 409, "pair %s is gone: %lld is the latest", query + 6,
                       static_cast<long long>(latest));
    return 409;
  }
  mg_send_http_ok(conn, type, static_cast<long long>(copy.size()));
  mg_write(conn, copy.data(), copy.size());
  return 200;
}

int ViewPages::serve(mg_connection* conn) {
  const mg_request_info* request = mg_get_request_info(conn);
  const std::string_view method = request->request_method;
  if (method == "HEAD") {  // no body, not even an error's
    mg_response_header_start(conn, 405);
    mg_response_header_add(conn, "Allow", "GET", -1);
    mg_response_header_send(conn);
    return 405;
  }
  if (method != "GET") {
    mg_send_http_error(conn, 405, "this server only answers GET: it is read-only");
    return 405;
  }
  const std::string_view path = request->local_uri != nullptr ? request->local_uri : "";
  if (path == "/api/frame.json" || path == "/api/left.jpg" || path == "/api/disparity.jpg") {
    asked_.store(detail::steady_now(), std::memory_order_relaxed);
  }
  if (path == "/" || path == "/index.html") {
    mg_send_http_ok(conn, "text/html; charset=utf-8", static_cast<long long>(kViewPage.size()));
    mg_write(conn, kViewPage.data(), kViewPage.size());
    return 200;
  }
  if (path == "/api/health") return send(conn, "application/json", health_json_, "health message");
  if (path == "/api/frame.json") return send(conn, "application/json", frame_json_, "pair");
  if (path == "/api/left.jpg") return send(conn, "image/jpeg", left_jpeg_, "left image");
  if (path == "/api/disparity.jpg") return send(conn, "image/jpeg", disparity_jpeg_, "disparity");
  if (path == "/api/colours.json") {
    json colours = json::array();
    for (const Rgb& c : disparity_colours()) colours.push_back({c[0], c[1], c[2]});
    const std::string text = colours.dump();
    mg_send_http_ok(conn, "application/json", static_cast<long long>(text.size()));
    mg_write(conn, text.data(), text.size());
    return 200;
  }
  mg_send_http_error(conn, 404, "no such page: the view serves / and /api/ (docs/live-view.md)");
  return 404;
}

}  // namespace epipole::firmware::view
