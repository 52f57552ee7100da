#pragma once

// Durations summarised the way a frame loop is judged: the median, the 99th percentile (nearest
// rank) and the mean, in milliseconds.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numeric>
#include <vector>

namespace epipole::tools {

struct TimingSummary {
  double p50_ms = 0;
  double p99_ms = 0;
  double mean_ms = 0;
};

inline TimingSummary summarize(std::vector<double> ms) {
  if (ms.empty()) return {};
  std::sort(ms.begin(), ms.end());
  const auto rank = [&](double p) {
    const auto k = static_cast<std::size_t>(std::ceil(p * static_cast<double>(ms.size())));
    return ms[std::clamp<std::size_t>(k, 1, ms.size()) - 1];
  };
  return {rank(0.50), rank(0.99),
          std::accumulate(ms.begin(), ms.end(), 0.0) / static_cast<double>(ms.size())};
}

}  // namespace epipole::tools
