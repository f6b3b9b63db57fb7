#include "findmug/mrf/layout_prior.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "findmug/common/error.hpp"
#include "findmug/common/numbers.hpp"
#include <iomanip>

namespace findmug {

namespace {

constexpr const char* kMagic = "findmug-layout-prior";
constexpr int kPairsPerTable = kNumLabels * (kNumLabels - 1);

// Counts are whole numbers when counted, any number >= 0 when edited.
std::string formatCount(double v) {
  std::ostringstream out;
  out << std::setprecision(17) << v;
  return out.str();
}

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) {
    const auto b = field.find_first_not_of(" \t\r");
    const auto e = field.find_last_not_of(" \t\r");
    fields.push_back(b == std::string::npos ? "" : field.substr(b, e - b + 1));
  }
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

int labelIndex(const std::string& name) {
  for (int i = 0; i < kNumLabels; ++i)
    if (kLabelNames[static_cast<std::size_t>(i)] == name) return i;
  return -1;
}

// One table's costs: minus the pointwise mutual information of the smoothed
// boundary distribution, scaled to [0, 1].
MrfPairTable tableCosts(const LayoutPairCounts& counts, double smoothing, const char* name) {
  double total = 0;
  for (int a = 0; a < kNumLabels; ++a)
    for (int b = 0; b < kNumLabels; ++b)
      if (a != b) total += counts[a * kNumLabels + b] + smoothing;
  if (!(total > 0))
    throw Error(std::string("layout prior: the ") + name +
                " table has no count and no smoothing");
  std::array<double, kNumLabels * kNumLabels> p{};
  std::array<double, kNumLabels> row{}, col{};
  for (int a = 0; a < kNumLabels; ++a)
    for (int b = 0; b < kNumLabels; ++b) {
      if (a == b) continue;
      const double v = (counts[a * kNumLabels + b] + smoothing) / total;
      p[a * kNumLabels + b] = v;
      row[a] += v;
      col[b] += v;
    }
  std::array<double, kNumLabels * kNumLabels> cost{};
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int a = 0; a < kNumLabels; ++a)
    for (int b = 0; b < kNumLabels; ++b) {
      const double v = p[a * kNumLabels + b];
      if (a == b || !(v > 0)) continue;  // a pair never seen without smoothing: set below
      const double c = -std::log(v / (row[a] * col[b]));
      cost[a * kNumLabels + b] = c;
      lo = std::min(lo, c);
      hi = std::max(hi, c);
    }
  MrfPairTable out{};
  for (int a = 0; a < kNumLabels; ++a)
    for (int b = 0; b < kNumLabels; ++b) {
      if (a == b) continue;
      const std::size_t k = static_cast<std::size_t>(a * kNumLabels + b);
      // Unseen (smoothing 0) is the most unlikely pair.
      out[k] = !(p[k] > 0) ? 1.0f
               : hi > lo   ? static_cast<float>((cost[k] - lo) / (hi - lo))
                           : 0.0f;
    }
  return out;
}

}  // namespace

LayoutCounts parseLayoutCounts(const std::string& text, const std::string& source) {
  LayoutCounts counts;
  std::array<std::array<bool, kNumLabels * kNumLabels>, 2> seen{};
  bool magic = false, smoothing = false, offset = false, frames = false;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  auto fail = [&](const std::string& what) -> void {
    throw Error(source + ": line " + std::to_string(line_no) + ": " + what);
  };
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos || line[0] == '#') continue;
    const std::vector<std::string> f = splitCsv(line);
    if (!magic) {
      if (f.size() != 2 || f[0] != kMagic || f[1] != "1")
        fail("expected '" + std::string(kMagic) + ",1' (a label-layout prior, version 1)");
      magic = true;
      continue;
    }
    if (f[0] == "smoothing" || f[0] == "offset_px" || f[0] == "frames") {
      if (f.size() != 2) fail("expected '" + f[0] + ",VALUE'");
      if (f[0] == "smoothing") {
        const auto v = parseNumber(f[1]);
        if (!v || !std::isfinite(*v) || *v < 0) fail("smoothing '" + f[1] + "' is not a number >= 0");
        counts.smoothing = *v;
        smoothing = true;
      } else {
        const auto v = parseInteger(f[1]);
        if (!v || *v < 0 || *v > std::numeric_limits<int>::max())
          fail(f[0] + " '" + f[1] + "' is not an integer >= 0");
        (f[0] == "frames" ? frames : offset) = true;
        if (f[0] == "frames")
          counts.frames = static_cast<long>(*v);
        else
          counts.offset_px = static_cast<int>(*v);
      }
      continue;
    }
    if (f[0] != "vertical" && f[0] != "horizontal")
      fail("unknown row '" + f[0] + "' (expected smoothing, offset_px, frames, vertical or horizontal)");
    if (f.size() != 4) fail("expected '" + f[0] + ",LABEL,LABEL,COUNT'");
    const int a = labelIndex(f[1]), b = labelIndex(f[2]);
    if (a < 0) fail("unknown label '" + f[1] + "'");
    if (b < 0) fail("unknown label '" + f[2] + "'");
    if (a == b) fail("a pair of the same label (" + f[1] + ") is no boundary");
    const auto v = parseNumber(f[3]);
    if (!v || !std::isfinite(*v) || *v < 0) fail("count '" + f[3] + "' is not a number >= 0");
    const int t = f[0] == "vertical" ? 0 : 1;
    const std::size_t k = static_cast<std::size_t>(a * kNumLabels + b);
    if (seen[t][k]) fail(f[0] + " pair " + f[1] + "," + f[2] + " listed twice");
    seen[t][k] = true;
    (t == 0 ? counts.vertical : counts.horizontal)[k] = *v;
  }
  if (!magic) throw Error(source + ": empty (expected a label-layout prior)");
  if (!smoothing || !offset || !frames)
    throw Error(source + ": line " + std::to_string(line_no) + ": missing " +
                (!smoothing ? "smoothing" : !offset ? "offset_px" : "frames") + " row");
  for (int t = 0; t < 2; ++t)
    for (int a = 0; a < kNumLabels; ++a)
      for (int b = 0; b < kNumLabels; ++b)
        if (a != b && !seen[t][static_cast<std::size_t>(a * kNumLabels + b)])
          throw Error(source + ": line " + std::to_string(line_no) + ": missing " +
                      (t == 0 ? "vertical" : "horizontal") + " pair " +
                      std::string(kLabelNames[a]) + "," + std::string(kLabelNames[b]) +
                      " (every table lists its " + std::to_string(kPairsPerTable) + " pairs)");
  return counts;
}

LayoutCounts loadLayoutCounts(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open the layout prior (mrf.layout_prior_path)");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw Error(path + ": read failed");
  return parseLayoutCounts(text.str(), path);
}

std::string formatLayoutCounts(const LayoutCounts& counts,
                               const std::vector<std::string>& comment) {
  std::ostringstream out;
  for (const std::string& c : comment) out << "# " << c << "\n";
  out << kMagic << ",1\n";
  out << "smoothing," << formatCount(counts.smoothing) << "\n";
  out << "offset_px," << counts.offset_px << "\n";
  out << "frames," << counts.frames << "\n";
  for (int t = 0; t < 2; ++t) {
    const LayoutPairCounts& table = t == 0 ? counts.vertical : counts.horizontal;
    for (int a = 0; a < kNumLabels; ++a)
      for (int b = 0; b < kNumLabels; ++b)
        if (a != b)
          out << (t == 0 ? "vertical," : "horizontal,") << kLabelNames[a] << "," << kLabelNames[b]
              << "," << formatCount(table[a * kNumLabels + b]) << "\n";
  }
  return out.str();
}

LayoutPrior layoutPriorFromCounts(const LayoutCounts& counts) {
  if (!(std::isfinite(counts.smoothing) && counts.smoothing >= 0))
    throw Error("layout prior: smoothing " + std::to_string(counts.smoothing) +
                " (expected a number >= 0)");
  for (const LayoutPairCounts* t : {&counts.vertical, &counts.horizontal})
    for (double v : *t)
      if (!(std::isfinite(v) && v >= 0))
        throw Error("layout prior: count " + std::to_string(v) + " (expected a number >= 0)");
  LayoutPrior prior;
  prior.vertical = tableCosts(counts.vertical, counts.smoothing, "vertical");
  prior.horizontal = tableCosts(counts.horizontal, counts.smoothing, "horizontal");
  return prior;
}

LayoutPrior loadLayoutPrior(const std::string& path) {
  const LayoutCounts counts = loadLayoutCounts(path);
  try {
    return layoutPriorFromCounts(counts);
  } catch (const Error& e) {
    throw Error(path + ": " + e.what());
  }
}

void patchHeightsInto(const std::vector<FeatureVector>& features, std::vector<float>& heights) {
  constexpr std::size_t kHeight = 3;
  static_assert(kFeatureNames[kHeight] == "centroid_height");
  heights.resize(features.size());
  for (std::size_t i = 0; i < features.size(); ++i) heights[i] = features[i][kHeight];
}

void segmentImageHeightsInto(const std::vector<int>& pixel_segment, int width,
                             std::size_t segments, std::vector<float>& heights) {
  if (width < 1 || pixel_segment.size() % static_cast<std::size_t>(width) != 0)
    throw Error("layout prior: " + std::to_string(pixel_segment.size()) +
                " pixels do not fill rows of " + std::to_string(width));
  std::vector<double> row_sum(segments, 0.0), count(segments, 0.0);
  for (std::size_t p = 0; p < pixel_segment.size(); ++p) {
    const int s = pixel_segment[p];
    if (s < 0) continue;
    if (static_cast<std::size_t>(s) >= segments)
      throw Error("layout prior: pixel " + std::to_string(p) + " in segment " + std::to_string(s) +
                  " of " + std::to_string(segments));
    row_sum[static_cast<std::size_t>(s)] += static_cast<double>(p / static_cast<std::size_t>(width));
    count[static_cast<std::size_t>(s)] += 1;
  }
  heights.resize(segments);
  for (std::size_t i = 0; i < segments; ++i)
    heights[i] = count[i] > 0 ? static_cast<float>(-row_sum[i] / count[i])
                              : std::numeric_limits<float>::quiet_NaN();
}

float layoutHeightsInto(const MrfParams& params, const LayoutGeometry& geometry,
                        std::vector<float>& heights) {
  if (!geometry.features) throw Error("layout prior: no patch features");
  if (params.layout_direction == LayoutDirection::Image) {
    if (!geometry.pixel_segment) throw Error("layout prior: no segmentation for image rows");
    segmentImageHeightsInto(*geometry.pixel_segment, geometry.width, geometry.features->size(),
                            heights);
    return params.layout_image_threshold_px;
  }
  patchHeightsInto(*geometry.features, heights);
  return params.layout_height_threshold;
}

void layoutPairFactorsInto(const LayoutPrior& prior, float weight, float height_threshold,
                           const std::vector<float>& heights,
                           const std::vector<std::pair<int, int>>& edges, MrfPairFactors& out) {
  if (!(std::isfinite(weight) && weight >= 0))
    throw Error("layout prior: weight " + std::to_string(weight) + " (expected >= 0)");
  if (!(std::isfinite(height_threshold) && height_threshold >= 0))
    throw Error("layout prior: height threshold " + std::to_string(height_threshold) +
                " (expected >= 0)");
  enum : std::uint8_t { kFirstAbove = 0, kSecondAbove = 1, kBeside = 2, kPotts = 3 };
  out.tables.resize(4);
  for (int a = 0; a < kNumLabels; ++a)
    for (int b = 0; b < kNumLabels; ++b) {
      const std::size_t k = static_cast<std::size_t>(a * kNumLabels + b);
      const std::size_t kt = static_cast<std::size_t>(b * kNumLabels + a);
      const bool differ = a != b;
      out.tables[kFirstAbove][k] = differ ? 1.0f + weight * prior.vertical[k] : 0.0f;
      // The first node is the lower one: its label is the table's column.
      out.tables[kSecondAbove][k] = differ ? 1.0f + weight * prior.vertical[kt] : 0.0f;
      out.tables[kBeside][k] = differ ? 1.0f + weight * prior.horizontal[k] : 0.0f;
      out.tables[kPotts][k] = differ ? 1.0f : 0.0f;
    }
  out.table_of_edge.resize(edges.size());
  const auto n = static_cast<long long>(heights.size());
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const auto [a, b] = edges[k];
    if (a < 0 || b < 0 || a >= n || b >= n)
      throw Error("layout prior: edge " + std::to_string(k) + " (" + std::to_string(a) + ", " +
                  std::to_string(b) + ") outside " + std::to_string(n) + " patches");
    const float ha = heights[static_cast<std::size_t>(a)];
    const float hb = heights[static_cast<std::size_t>(b)];
    if (!(std::isfinite(ha) && std::isfinite(hb)))
      out.table_of_edge[k] = kPotts;
    else if (std::abs(ha - hb) > height_threshold)
      out.table_of_edge[k] = ha > hb ? kFirstAbove : kSecondAbove;
    else
      out.table_of_edge[k] = kBeside;
  }
}

}  // namespace findmug
