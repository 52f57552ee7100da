#include "epipole/tools/cascade_xml.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <pugixml.hpp>
#include <string>
#include <vector>

#include "epipole/core/error.hpp"

namespace epipole::tools {

namespace {

using vision::CascadeData;
using vision::CascadeFeatureType;

// Errors name the source and the line of the element they are about.
class XmlContext {
 public:
  XmlContext(std::string_view text, std::string_view source) : text_(text), source_(source) {}

  template <typename... Parts>
  [[noreturn]] void fail(const pugi::xml_node& node, Parts&&... parts) const {
    throw Error(
        cat(source_, ": line ", line(node.offset_debug()), ": ", std::forward<Parts>(parts)...));
  }
  std::string_view source() const { return source_; }
  int line(std::ptrdiff_t offset) const {
    if (offset < 0) return 0;
    const auto end = std::min(static_cast<std::size_t>(offset), text_.size());
    return 1 + static_cast<int>(std::count(text_.begin(), text_.begin() + end, '\n'));
  }

 private:
  std::string_view text_;
  std::string_view source_;
};

// The character data of an element (all its text pieces; comments between them are skipped).
std::string element_text(const pugi::xml_node& node) {
  std::string text;
  for (const pugi::xml_node child : node.children()) {
    if (child.type() == pugi::node_pcdata || child.type() == pugi::node_cdata) {
      text += child.value();
      text += ' ';
    }
  }
  return text;
}

// Whitespace-separated numbers of an element, as OpenCV's FileStorage reads them.
class Numbers {
 public:
  Numbers(const XmlContext& context, const pugi::xml_node& node, std::string_view what)
      : context_(context), node_(node), what_(what), text_(element_text(node)) {}

  bool done() {
    skip_space();
    return position_ >= text_.size();
  }
  std::size_t count() {
    std::size_t n = 0;
    const std::size_t start = position_;
    while (!done()) {
      token();
      ++n;
    }
    position_ = start;
    return n;
  }
  double real() {
    std::string_view t = token();
    if (!t.empty() && t.front() == '+') t.remove_prefix(1);
    double v = 0.0;
    const auto [end, error] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (error != std::errc() || end != t.data() + t.size()) {
      context_.fail(node_, what_, ": '", t, "' is not a number");
    }
    return v;
  }
  float real32() {
    const double v = real();
    if (std::isfinite(v) && std::abs(v) > static_cast<double>(std::numeric_limits<float>::max())) {
      context_.fail(node_, what_, ": ", v, " is out of the range of float");
    }
    return static_cast<float>(v);
  }
  long long integer() {
    std::string_view t = token();
    if (!t.empty() && t.front() == '+') t.remove_prefix(1);
    long long v = 0;
    const auto [end, error] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (error != std::errc() || end != t.data() + t.size()) {
      context_.fail(node_, what_, ": '", t, "' is not an integer");
    }
    return v;
  }
  int int32(long long low = std::numeric_limits<int>::min(),
            long long high = std::numeric_limits<int>::max()) {
    const long long v = integer();
    if (v < low || v > high) {
      context_.fail(node_, what_, ": ", v, " is out of range [", low, ", ", high, "]");
    }
    return static_cast<int>(v);
  }

 private:
  void skip_space() {
    while (position_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[position_]))) {
      ++position_;
    }
  }
  std::string_view token() {
    if (done()) context_.fail(node_, what_, ": more numbers expected");
    const std::size_t start = position_;
    while (position_ < text_.size() &&
           !std::isspace(static_cast<unsigned char>(text_[position_]))) {
      ++position_;
    }
    return std::string_view(text_).substr(start, position_ - start);
  }

  const XmlContext& context_;
  pugi::xml_node node_;
  std::string_view what_;
  std::string text_;
  std::size_t position_ = 0;
};

pugi::xml_node required_child(const XmlContext& context, const pugi::xml_node& node,
                              const char* name) {
  const pugi::xml_node child = node.child(name);
  if (!child) context.fail(node, "<", node.name(), "> has no <", name, ">");
  return child;
}

std::string trimmed_text(const pugi::xml_node& node) {
  std::string text = element_text(node);
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(" \t\r\n") - first + 1);
}

// A single number in an element, e.g. <width>24</width>.
int single_int(const XmlContext& context, const pugi::xml_node& node, long long low,
               long long high) {
  Numbers numbers(context, node, node.name());
  const int v = numbers.int32(low, high);
  if (!numbers.done()) context.fail(node, "<", node.name(), "> holds more than one number");
  return v;
}

std::vector<pugi::xml_node> elements(const pugi::xml_node& node) {
  std::vector<pugi::xml_node> out;
  for (const pugi::xml_node child : node.children()) {
    if (child.type() == pugi::node_element) out.push_back(child);
  }
  return out;
}

void read_stages(const XmlContext& context, const pugi::xml_node& stages_node, bool lbp,
                 CascadeData& d) {
  // Each node of internalNodes: left, right, feature, then the threshold (Haar) or the 8
  // words of the category subset (LBP), as OpenCV's nodeStep.
  const std::size_t node_step = lbp ? 3 + CascadeData::kLbpSubsetWords : 4;
  const std::vector<pugi::xml_node> stages = elements(stages_node);
  if (stages.empty()) context.fail(stages_node, "<stages> is empty");
  for (std::size_t s = 0; s < stages.size(); ++s) {
    const pugi::xml_node stage = stages[s];
    Numbers threshold(context, required_child(context, stage, "stageThreshold"), "stageThreshold");
    vision::CascadeStage out;
    out.threshold = threshold.real32() - 1e-5f;  // OpenCV's THRESHOLD_EPS, in float
    const pugi::xml_node weak_node = required_child(context, stage, "weakClassifiers");
    const std::vector<pugi::xml_node> weaks = elements(weak_node);
    if (weaks.empty()) context.fail(weak_node, "stage ", s, " has no weak classifiers");
    out.weak_count = static_cast<int>(weaks.size());
    d.stages.push_back(out);
    for (const pugi::xml_node weak : weaks) {
      const pugi::xml_node internal = required_child(context, weak, "internalNodes");
      const pugi::xml_node leaf_node = required_child(context, weak, "leafValues");
      Numbers nodes(context, internal, "internalNodes");
      const std::size_t values = nodes.count();
      if (values == 0 || values % node_step != 0) {
        context.fail(
            internal, "internalNodes holds ", values, " numbers, not a multiple of ", node_step,
            " (", lbp ? "left, right, feature, 8 subset words" : "left, right, feature, threshold",
            " per node)");
      }
      const std::size_t node_count = values / node_step;
      Numbers leaves(context, leaf_node, "leafValues");
      const std::size_t leaf_count = leaves.count();
      if (leaf_count != node_count + 1) {
        context.fail(leaf_node, "leaf count mismatch: ", leaf_count, " leafValues for ", node_count,
                     " node", node_count == 1 ? "" : "s", " (", node_count + 1, " expected)");
      }
      d.node_counts.push_back(static_cast<int>(node_count));
      for (std::size_t n = 0; n < node_count; ++n) {
        vision::CascadeNode node;
        node.left = nodes.int32();
        node.right = nodes.int32();
        node.feature = nodes.int32(0);
        if (lbp) {
          for (int k = 0; k < CascadeData::kLbpSubsetWords; ++k) {
            d.subsets.push_back(static_cast<std::uint32_t>(nodes.int32()));
          }
        } else {
          node.threshold = nodes.real32();
        }
        d.nodes.push_back(node);
      }
      for (std::size_t k = 0; k < leaf_count; ++k) d.leaves.push_back(leaves.real32());
    }
  }
}

void read_haar_features(const XmlContext& context, const pugi::xml_node& features, CascadeData& d) {
  for (const pugi::xml_node feature : elements(features)) {
    vision::HaarFeature f;
    const pugi::xml_node rects = required_child(context, feature, "rects");
    for (const pugi::xml_node rect : elements(rects)) {
      if (f.rect_count == 3) context.fail(rect, "a Haar feature has at most 3 rectangles");
      Numbers numbers(context, rect, "rectangle");
      vision::HaarRect& r = f.rects[f.rect_count++];
      r.x = numbers.int32(-32768, 32767);
      r.y = numbers.int32(-32768, 32767);
      r.width = numbers.int32(-32768, 32767);
      r.height = numbers.int32(-32768, 32767);
      r.weight = numbers.real32();
      if (!numbers.done()) context.fail(rect, "a rectangle is x y width height weight");
    }
    if (f.rect_count == 0) context.fail(rects, "a Haar feature without rectangles");
    if (const pugi::xml_node tilted = feature.child("tilted")) {
      f.tilted = single_int(context, tilted, 0, 1) != 0;
    }
    d.haar_features.push_back(f);
  }
}

void read_lbp_features(const XmlContext& context, const pugi::xml_node& features, CascadeData& d) {
  for (const pugi::xml_node feature : elements(features)) {
    const pugi::xml_node rect = required_child(context, feature, "rect");
    Numbers numbers(context, rect, "rect");
    vision::LbpFeature f;
    f.x = numbers.int32(-32768, 32767);
    f.y = numbers.int32(-32768, 32767);
    f.block_width = numbers.int32(-32768, 32767);
    f.block_height = numbers.int32(-32768, 32767);
    if (!numbers.done()) context.fail(rect, "an LBP rect is x y block-width block-height");
    d.lbp_features.push_back(f);
  }
}

}  // namespace

vision::CascadeModel parse_cascade_xml(std::string_view text, std::string_view source) {
  const XmlContext context(text, source);
  pugi::xml_document document;
  const pugi::xml_parse_result parsed =
      document.load_buffer(text.data(), text.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!parsed) {
    throw Error(cat(source, ": line ", context.line(parsed.offset), ": malformed XML (",
                    parsed.description(), ")"));
  }
  const pugi::xml_node storage = document.child("opencv_storage");
  if (!storage) throw Error(cat(source, ": not an OpenCV file (no <opencv_storage>)"));
  const pugi::xml_node cascade =
      storage.find_child([](const pugi::xml_node& n) { return n.type() == pugi::node_element; });
  if (!cascade) context.fail(storage, "<opencv_storage> is empty");
  if (std::string_view(cascade.attribute("type_id").value()) == "opencv-haar-classifier") {
    context.fail(cascade,
                 "the old OpenCV Haar format (opencv-haar-classifier) is not supported; use a "
                 "cascade in the traincascade format");
  }
  const std::string stage_type = trimmed_text(required_child(context, cascade, "stageType"));
  if (stage_type != "BOOST") {
    context.fail(cascade.child("stageType"), "stage type '", stage_type,
                 "' is not supported (BOOST expected)");
  }
  const pugi::xml_node type_node = required_child(context, cascade, "featureType");
  const std::string feature_type = trimmed_text(type_node);
  CascadeData d;
  if (feature_type == "HAAR") {
    d.feature_type = CascadeFeatureType::haar;
  } else if (feature_type == "LBP") {
    d.feature_type = CascadeFeatureType::lbp;
  } else if (feature_type == "HOG") {
    context.fail(type_node, "HOG cascades are not supported (OpenCV 3 and later dropped them)");
  } else {
    context.fail(type_node, "unknown feature type '", feature_type, "' (HAAR or LBP expected)");
  }
  const bool lbp = d.feature_type == CascadeFeatureType::lbp;
  d.window_width = single_int(context, required_child(context, cascade, "width"), 1,
                              vision::CascadeModel::kMaxWindowSize);
  d.window_height = single_int(context, required_child(context, cascade, "height"), 1,
                               vision::CascadeModel::kMaxWindowSize);
  const pugi::xml_node params = required_child(context, cascade, "featureParams");
  const pugi::xml_node categories_node = required_child(context, params, "maxCatCount");
  const int categories = single_int(context, categories_node, 0, 1 << 20);
  if (categories != (lbp ? 256 : 0)) {
    context.fail(categories_node, "maxCatCount ", categories, " for a ", feature_type, " cascade (",
                 lbp ? 256 : 0, " expected)");
  }
  read_stages(context, required_child(context, cascade, "stages"), lbp, d);
  const pugi::xml_node features = required_child(context, cascade, "features");
  if (lbp) {
    read_lbp_features(context, features, d);
  } else {
    read_haar_features(context, features, d);
  }
  return vision::CascadeModel(std::move(d), source);
}

vision::CascadeModel load_cascade(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(cat(file.string(), ": cannot open"));
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
  if (in.bad()) throw Error(cat(file.string(), ": read error"));
  const std::string name = file.string();
  if (bytes.size() >= 4 && std::string_view(bytes.data(), 4) == "EPCC") {
    return vision::CascadeModel::from_binary(
        std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), name);
  }
  return parse_cascade_xml(std::string_view(bytes.data(), bytes.size()), name);
}

}  // namespace epipole::tools
