#pragma once

// The live view's page for any browser, on the WebSocket's port (docs/live-view.md):
//
//   GET /                  the page (self-contained: nothing is fetched from elsewhere)
//   GET /api/health        the latest health message as JSON
//   GET /api/frame.json    the latest pictured pair: its number, corners, detections with depth
//   GET /api/left.jpg      its rectified left image
//   GET /api/disparity.jpg its disparity in colour (disparity_colours.hpp)
//   GET /api/colours.json  the disparity's colours, for the legend
//
// Pictures are made on the view's thread, at most `picture_hz` a second and only while a page
// asks for them (a request in the last 5 s); requests are answered from the latest ones on
// civetweb's threads. A picture asked for as ?frame=N of a pair no longer the latest gets 409
// (the page then asks again, so its corners are drawn on their own image). Other paths get 404,
// other methods 405 (HEAD too: this server answers GET only).

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "delivery/pair_copy.hpp"
#include "epipole/firmware/protocol/messages.hpp"
#include "view/jpeg_encoder.hpp"

struct mg_connection;

namespace epipole::firmware::view {

struct PageSettings {
  double picture_hz = 5;  // pictures a second at most
  int quality = 80;       // JPEG quality, 1..100
};

class ViewPages {
 public:
  ViewPages(const BoardConfig& board, PageSettings settings);

  // The view's thread: whether pictures are wanted now (steady clock, ns), then the pair's.
  bool due(std::int64_t now) const;
  void picture(const outputs::PairCopy& pair, std::int64_t now);
  void health(const protocol::Health& health);

  // civetweb's request handler: answers every request to the server's port but the WebSocket's.
  int serve(mg_connection* conn);

  std::size_t working_set_bytes() const;

 private:
  int send(mg_connection* conn, const char* type, const std::vector<std::uint8_t>& bytes,
           const char* what);

  const BoardConfig& board_;
  PageSettings settings_;
  JpegEncoder encoder_;
  std::vector<std::uint8_t> rgb_;  // the disparity in colour, before it is encoded
  std::atomic<std::int64_t> asked_{-1'000'000'000'000};     // when a page last asked (steady ns)
  std::atomic<std::int64_t> pictured_{0};                   // when the last pictures were made
  std::vector<std::uint8_t> left_spare_, disparity_spare_;  // the next pictures, made unlocked
  std::vector<std::uint8_t> health_spare_;                  // the next health, made unlocked
  mutable std::mutex mutex_;  // the latest pictures and texts, for the request handlers
  std::vector<std::uint8_t> left_jpeg_, disparity_jpeg_, frame_json_, health_json_;
  std::int64_t frame_ = -1;  // the pair they show
};

}  // namespace epipole::firmware::view
