#pragma once

// Cascades for tests that run everywhere (no data files): small hand-made ones, and random ones
// with the shapes of OpenCV's (Haar stumps and trees, tilted and three-rectangle features, LBP).

#include <algorithm>
#include <cstdint>
#include <random>

#include "epipole/vision/cascade_model.hpp"

namespace epipole::test {

struct RandomCascadeShape {
  vision::CascadeFeatureType type = vision::CascadeFeatureType::haar;
  int window_width = 24;
  int window_height = 24;
  int stages = 6;
  int first_stage_weaks = 3;  // stage s has first_stage_weaks + 2 s weak classifiers
  int max_nodes = 1;          // > 1: trees of 1..max_nodes nodes
  bool tilted = false;        // Haar: about a third of the features tilted
  // Haar: weights like -1.3 and 2.6 instead of OpenCV's -1, 2, 3 and 9 (the kernels form
  // integer weights' values in integers, other weights' in floats).
  bool fractional_weights = false;
  // Haar: one in three two-rectangle features a rectangle and its first half, as OpenCV's edge
  // features are (the corners they share make them the kernels' six-corner stumps).
  bool edge_features = false;
  // Stage thresholds: a random window passes a stage about this often.
  double pass_rate = 0.75;
};

// Leaves with varied exponents (as trained cascades have), thresholds around the values the
// features take on natural and random images, so that windows go deep and stop anywhere.
inline vision::CascadeData random_cascade(const RandomCascadeShape& shape, std::uint32_t seed) {
  std::mt19937 rng(seed);
  const auto uniform = [&rng](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  const auto pick = [&rng](int lo, int hi) {  // [lo, hi]
    return std::uniform_int_distribution<int>(lo, hi)(rng);
  };
  vision::CascadeData d;
  d.feature_type = shape.type;
  d.window_width = shape.window_width;
  d.window_height = shape.window_height;
  const bool lbp = shape.type == vision::CascadeFeatureType::lbp;
  const int w = shape.window_width;
  const int h = shape.window_height;
  int feature_count = 0;
  const auto add_feature = [&] {
    if (lbp) {
      const int bw = pick(1, std::max(1, w / 3));
      const int bh = pick(1, std::max(1, h / 3));
      d.lbp_features.push_back({pick(0, w - 3 * bw), pick(0, h - 3 * bh), bw, bh});
    } else {
      vision::HaarFeature f;
      f.tilted = shape.tilted && pick(0, 2) == 0;
      f.rect_count = pick(0, 3) == 0 ? 3 : 2;
      const bool half = shape.edge_features && f.rect_count == 2 && pick(0, 2) == 0;
      for (int r = 0; r < f.rect_count; ++r) {
        vision::HaarRect& rect = f.rects[r];
        if (f.tilted) {
          // Top corner (x, y), sides w down-right and h down-left: x - h >= 0, x + w <= W,
          // y + w + h <= H.
          rect.width = pick(1, std::max(1, std::min(w, h) / 2 - 1));
          rect.height = pick(1, std::max(1, std::min(w - rect.width, h - rect.width) - 1));
          rect.x = pick(rect.height, w - rect.width);
          rect.y = pick(0, h - rect.width - rect.height);
        } else {
          rect.width = pick(1, w);
          rect.height = pick(1, h);
          rect.x = pick(0, w - rect.width);
          rect.y = pick(0, h - rect.height);
        }
        if (half && r == 1) {
          // The first or the second half of the width or the height: the two rectangles
          // share two corners.
          const bool across = pick(0, 1) == 0;
          const bool second = pick(0, 1) == 0;
          rect = f.rects[0];
          const int cut = (across ? rect.width : rect.height) / 2;
          if (second && across) {  // along the width: right for upright, down-right for tilted
            rect.x += cut;
            if (f.tilted) rect.y += cut;
          } else if (second) {  // along the height: down for upright, down-left for tilted
            rect.y += cut;
            if (f.tilted) rect.x -= cut;
          }
          (across ? rect.width : rect.height) -= cut;
          rect.weight = 2.0f;
          continue;
        }
        if (shape.fractional_weights) {
          rect.weight = static_cast<float>(r == 0 ? -uniform(0.5, 1.5) : uniform(0.5, 3.5));
        } else {
          rect.weight = r == 0 ? -1.0f : static_cast<float>(pick(1, 3));
        }
      }
      d.haar_features.push_back(f);
    }
    return feature_count++;
  };
  // Leaves like 0.83, -0.61 and, one in five, tiny ones like 1.7e-4 (exponents down to -13),
  // as trained cascades have.
  const auto leaf = [&] {
    const double magnitude =
        pick(0, 4) == 0 ? std::ldexp(uniform(0.5, 1.0), pick(-13, -3)) : uniform(0.2, 1.0);
    return static_cast<float>(pick(0, 1) == 0 ? magnitude : -magnitude);
  };
  for (int s = 0; s < shape.stages; ++s) {
    const int weaks = shape.first_stage_weaks + 2 * s;
    // The stage passes when the leaves it took are at least a fraction q of the way from the
    // worst to the best sum: about pass_rate of random windows for q = 1 - pass_rate, varied a
    // little from stage to stage.
    double worst = 0.0;
    double range = 0.0;
    for (int k = 0; k < weaks; ++k) {
      const int nodes = pick(1, shape.max_nodes);
      d.node_counts.push_back(nodes);
      // A chain: node i's left child is leaf -i, its right the next node (the last: leaf -n).
      for (int i = 0; i < nodes; ++i) {
        vision::CascadeNode node;
        node.feature = add_feature();
        node.left = -i;
        node.right = i + 1 < nodes ? i + 1 : -nodes;
        if (!lbp) node.threshold = static_cast<float>(uniform(-0.3, 0.3) * (pick(0, 3) + 1) / 4);
        d.nodes.push_back(node);
        if (lbp) {
          for (int word = 0; word < vision::CascadeData::kLbpSubsetWords; ++word) {
            d.subsets.push_back(static_cast<std::uint32_t>(rng()) ^
                                static_cast<std::uint32_t>(rng() << 7));
          }
        }
      }
      double low = 1e9;
      double high = -1e9;
      for (int i = 0; i <= nodes; ++i) {
        const float v = leaf();
        d.leaves.push_back(v);
        low = std::min(low, static_cast<double>(v));
        high = std::max(high, static_cast<double>(v));
      }
      worst += low;
      range += high - low;
    }
    const double q = (1.0 - shape.pass_rate) * (0.6 + 0.2 * ((s * 7) % 5));
    d.stages.push_back({weaks, static_cast<float>(worst + q * range)});
  }
  return d;
}

}  // namespace epipole::test
