// Randomized decision forest: training, prediction and the binary model file.
//
// Training follows Criminisi et al.: at every node a few random features and,
// per feature, a few random thresholds between the node's minimum and maximum
// of that feature are tried; the candidate with the highest weighted
// information gain (Shannon entropy of the weighted label histograms) wins.
// A node becomes a leaf at max_depth, when it is pure, or when no candidate
// leaves at least min_samples_leaf samples on each side.
//
// Reproducibility: tree t draws every random number from its own generator
// seeded with seed + t, and random numbers are turned into integers/reals by
// our own code (not std::*_distribution, whose output is implementation
// defined), so a seed gives a byte-identical model whatever the thread count.
//
// Model file (all little-endian):
//   char[8]  "FMUGFRST"
//   uint32   format version (kFormatVersion)
//   uint32   label count, then per label: uint32 length + bytes   (kLabelNames)
//   uint32   feature count, then per feature: uint32 length + bytes (kFeatureNames,
//            then in version 3 any extra columns: region/context features)
//   params   int32 num_trees, max_depth, min_samples_leaf, candidate_features,
//            candidate_thresholds; uint8 class_weighting; float64 bagging_fraction;
//            uint64 seed   (num_threads is not stored: it is not a property of
//            the model, and a seed must give the same file whatever it is)
//   uint32   extraction setting count (version 2), then per setting: key, value
//            as uint32 length + bytes (cloud.*, normals.*, overseg.* of training)
//   uint32   tree count; per tree: uint32 node count, then per node:
//            int32 feature; inner (feature >= 0): float32 threshold, int32 left, int32 right;
//            leaf (feature == -1): float32[kNumLabels] distribution
//   uint8    (version 3) 1 when an auto-context stage follows, else 0; the stage is
//            feature count + names, params, tree count + trees as above
//   uint64   FNV-1a 64 checksum of every byte before it
#include "findmug/forest.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <limits>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

#include "findmug/error.hpp"

namespace findmug {

namespace {

constexpr char kMagic[8] = {'F', 'M', 'U', 'G', 'F', 'R', 'S', 'T'};
constexpr std::uint32_t kFormatVersion = 3;
// Format 2: the 14 base features only, no context stage. Still read; such a
// model means features.regions = false and features.context = false.
constexpr std::uint32_t kOldestFormatVersion = 2;
constexpr std::uint32_t kMaxFeatures = 1024;
constexpr std::uint32_t kMaxSettings = 256;
constexpr int kMaxTrees = 10000;
// Tree size is bounded by the training samples (every leaf holds at least
// one), not by the depth; this limit only refuses absurd values.
constexpr int kMaxDepth = 64;
constexpr std::uint32_t kMaxNameLength = 256;
constexpr std::size_t kChecksumSize = 8;
// Smallest encodings of a node, used to bound counts before allocating.
constexpr std::size_t kInnerNodeBytes = 4 + 4 + 4 + 4;
constexpr std::size_t kLeafNodeBytes = 4 + 4 * kNumLabels;

static_assert(std::endian::native == std::endian::little || std::endian::native == std::endian::big,
              "mixed-endian platforms are not supported");

// ---------------------------------------------------------------------------
// Parameter and data validation

void validateParams(const ForestParams& p, const std::string& where) {
  auto fail = [&](const std::string& field, const std::string& value, const std::string& rule) {
    throw Error(where + ": forest parameter " + field + " = " + value + " is invalid (" + rule +
                ")");
  };
  if (p.num_trees < 1 || p.num_trees > kMaxTrees)
    fail("num_trees", std::to_string(p.num_trees), "expected 1.." + std::to_string(kMaxTrees));
  if (p.max_depth < 0 || p.max_depth > kMaxDepth)
    fail("max_depth", std::to_string(p.max_depth), "expected 0.." + std::to_string(kMaxDepth));
  if (p.min_samples_leaf < 1)
    fail("min_samples_leaf", std::to_string(p.min_samples_leaf), "expected >= 1");
  if (p.candidate_features < 1 || p.candidate_features > static_cast<int>(kMaxFeatures))
    fail("candidate_features", std::to_string(p.candidate_features),
         "expected 1.." + std::to_string(kMaxFeatures));
  if (p.candidate_thresholds < 1 || p.candidate_thresholds > 100000)
    fail("candidate_thresholds", std::to_string(p.candidate_thresholds), "expected 1..100000");
  if (!(p.bagging_fraction > 0.0 && p.bagging_fraction <= 1.0))
    fail("bagging_fraction", std::to_string(p.bagging_fraction), "expected in (0, 1]");
  if (p.num_threads < 0) fail("num_threads", std::to_string(p.num_threads), "expected >= 0");
}

void validateTrainingSet(const TrainingSet& data) {
  const std::size_t n = data.features.size();
  if (n == 0) throw Error("forest training: the training set is empty");
  if (n > std::numeric_limits<std::uint32_t>::max())
    throw Error("forest training: " + std::to_string(n) + " samples exceed the 2^32 - 1 limit");
  if (data.labels.size() != n)
    throw Error("forest training: " + std::to_string(n) + " feature vectors but " +
                std::to_string(data.labels.size()) + " labels");
  if (!data.weights.empty() && data.weights.size() != n)
    throw Error("forest training: " + std::to_string(n) + " feature vectors but " +
                std::to_string(data.weights.size()) + " weights");
  const std::size_t extra_dim = data.extra_names.size();
  if (kFeatureDim + extra_dim > kMaxFeatures)
    throw Error("forest training: " + std::to_string(kFeatureDim + extra_dim) +
                " features exceed the limit of " + std::to_string(kMaxFeatures));
  for (const auto& name : data.extra_names)
    if (name.empty() || name.size() > kMaxNameLength)
      throw Error("forest training: extra feature name '" + name + "' is empty or too long");
  if (data.extra.size() != n * extra_dim)
    throw Error("forest training: " + std::to_string(n) + " samples with " +
                std::to_string(extra_dim) + " extra features need " +
                std::to_string(n * extra_dim) + " extra values, got " +
                std::to_string(data.extra.size()));
  for (std::size_t i = 0; i < n; ++i) {
    if (data.labels[i] >= kNumLabels)
      throw Error("forest training: sample " + std::to_string(i) + " has label " +
                  std::to_string(data.labels[i]) + " (expected 0.." +
                  std::to_string(kNumLabels - 1) + "; void samples must be removed)");
    for (int f = 0; f < kFeatureDim; ++f) {
      if (!std::isfinite(data.features[i][f]))
        throw Error("forest training: sample " + std::to_string(i) + " feature " +
                    std::string(kFeatureNames[f]) + " is not finite");
    }
    for (std::size_t f = 0; f < extra_dim; ++f) {
      if (!std::isfinite(data.extra[i * extra_dim + f]))
        throw Error("forest training: sample " + std::to_string(i) + " feature " +
                    data.extra_names[f] + " is not finite");
    }
    if (!data.weights.empty() && !(std::isfinite(data.weights[i]) && data.weights[i] > 0.0f))
      throw Error("forest training: sample " + std::to_string(i) + " has weight " +
                  std::to_string(data.weights[i]) + " (expected finite and > 0)");
  }
}

// ---------------------------------------------------------------------------
// Deterministic random numbers (std::mt19937_64 is fully specified; the
// conversions below are ours so that every standard library agrees).

class TreeRng {
 public:
  explicit TreeRng(std::uint64_t seed) : engine_(seed) {}
  // Uniform integer in [0, n), n >= 1, without modulo bias (rejection).
  std::uint64_t below(std::uint64_t n) {
    const std::uint64_t limit =
        std::numeric_limits<std::uint64_t>::max() - std::numeric_limits<std::uint64_t>::max() % n;
    std::uint64_t x;
    do {
      x = engine_();
    } while (x >= limit);
    return x % n;
  }
  // Uniform real in [0, 1) with 53 random bits.
  double unit() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

 private:
  std::mt19937_64 engine_;
};

// ---------------------------------------------------------------------------
// Tree training

using Histogram = std::array<double, kNumLabels>;

double entropy(const Histogram& h, double total) {
  if (total <= 0.0) return 0.0;
  double e = 0.0;
  for (double c : h) {
    if (c > 0.0) {
      const double p = c / total;
      e -= p * std::log2(p);
    }
  }
  return e;
}

struct TrainingView {
  const std::vector<FeatureVector>& features;
  const std::vector<float>& extra;
  int extra_dim;
  const std::vector<std::uint8_t>& labels;
  std::vector<double> weights;  // per sample, including class weighting
  int dim() const { return kFeatureDim + extra_dim; }
  float value(std::uint32_t sample, int f) const {
    return f < kFeatureDim ? features[sample][f]
                           : extra[static_cast<std::size_t>(sample) * extra_dim + (f - kFeatureDim)];
  }
};

class TreeBuilder {
 public:
  TreeBuilder(const TrainingView& data, const ForestParams& params, std::uint64_t seed)
      : data_(data), params_(params), rng_(seed) {}

  RandomForest::Tree build() {
    const std::size_t n = data_.features.size();
    // Samples of this tree: all of them, or a bootstrap draw with replacement.
    std::vector<std::uint32_t> samples;
    if (params_.bagging_fraction >= 1.0) {
      samples.resize(n);
      for (std::size_t i = 0; i < n; ++i) samples[i] = static_cast<std::uint32_t>(i);
    } else {
      const auto m = std::max<std::size_t>(
          1, static_cast<std::size_t>(std::llround(params_.bagging_fraction * n)));
      samples.resize(m);
      for (auto& s : samples) s = static_cast<std::uint32_t>(rng_.below(n));
    }

    RandomForest::Tree tree;
    tree.emplace_back();
    // Explicit stack instead of recursion; children are appended, so a child's
    // index is always larger than its parent's (the loader relies on that).
    struct Pending {
      std::int32_t node;
      std::size_t begin, end;
      int depth;
    };
    std::vector<Pending> stack{{0, 0, samples.size(), 0}};
    while (!stack.empty()) {
      const Pending job = stack.back();
      stack.pop_back();
      Histogram hist{};
      for (std::size_t k = job.begin; k < job.end; ++k)
        hist[data_.labels[samples[k]]] += data_.weights[samples[k]];
      double total = 0.0;
      int classes_present = 0;
      for (double c : hist) {
        total += c;
        classes_present += c > 0.0;
      }

      Split split;
      const std::size_t count = job.end - job.begin;
      const bool can_split = job.depth < params_.max_depth && classes_present > 1 &&
                             count >= 2 * static_cast<std::size_t>(params_.min_samples_leaf);
      if (can_split) split = findSplit(samples, job.begin, job.end, hist, total);

      if (!split.valid) {
        RandomForest::Node& leaf = tree[job.node];
        leaf.feature = -1;
        for (int c = 0; c < kNumLabels; ++c)
          leaf.distribution[c] = static_cast<float>(hist[c] / total);
        continue;
      }
      // Partition in place: samples going left first.
      const auto mid_it = std::stable_partition(
          samples.begin() + static_cast<std::ptrdiff_t>(job.begin),
          samples.begin() + static_cast<std::ptrdiff_t>(job.end),
          [&](std::uint32_t s) { return data_.value(s, split.feature) < split.threshold; });
      const auto mid = static_cast<std::size_t>(mid_it - samples.begin());
      const auto left = static_cast<std::int32_t>(tree.size());
      const auto right = left + 1;
      tree.emplace_back();
      tree.emplace_back();
      RandomForest::Node& node = tree[job.node];
      node.feature = split.feature;
      node.threshold = split.threshold;
      node.left = left;
      node.right = right;
      // Right first so that the left subtree is built (and numbered) first.
      stack.push_back({right, mid, job.end, job.depth + 1});
      stack.push_back({left, job.begin, mid, job.depth + 1});
    }
    return tree;
  }

 private:
  struct Split {
    bool valid = false;
    int feature = -1;
    float threshold = 0.0f;
    double gain = 0.0;
  };

  Split findSplit(const std::vector<std::uint32_t>& samples, std::size_t begin, std::size_t end,
                  const Histogram& parent, double parent_total) {
    const double parent_entropy = entropy(parent, parent_total);
    const int num_thresholds = params_.candidate_thresholds;
    const auto min_leaf = static_cast<std::size_t>(params_.min_samples_leaf);

    // Distinct random features: a partial Fisher-Yates shuffle.
    const int dim = data_.dim();
    std::vector<int>& order = order_;
    order.resize(static_cast<std::size_t>(dim));
    for (int f = 0; f < dim; ++f) order[f] = f;
    for (int k = 0; k < params_.candidate_features; ++k) {
      const auto j = k + static_cast<int>(rng_.below(static_cast<std::uint64_t>(dim - k)));
      std::swap(order[k], order[j]);
    }

    Split best;
    thresholds_.resize(num_thresholds);
    bins_.assign(static_cast<std::size_t>(num_thresholds) + 1, Histogram{});
    bin_counts_.assign(static_cast<std::size_t>(num_thresholds) + 1, 0);
    for (int k = 0; k < params_.candidate_features; ++k) {
      const int feature = order[k];
      float lo = std::numeric_limits<float>::infinity();
      float hi = -lo;
      for (std::size_t s = begin; s < end; ++s) {
        const float v = data_.value(samples[s], feature);
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
      // Thresholds are drawn even for a constant feature so that the number of
      // random draws (and thus the rest of the tree) does not depend on it.
      for (auto& t : thresholds_) {
        const double u = rng_.unit();
        t = static_cast<float>(static_cast<double>(lo) + u * (static_cast<double>(hi) - lo));
        // "x < t" must send the minimum left and the maximum right.
        if (!(t > lo)) t = std::nextafter(lo, hi);
      }
      if (!(hi > lo)) continue;
      std::sort(thresholds_.begin(), thresholds_.end());

      // Bin b holds samples with thresholds[b-1] <= x < thresholds[b]; the
      // left side of threshold b is then bins 0..b. O(n log T + T L).
      std::fill(bins_.begin(), bins_.end(), Histogram{});
      std::fill(bin_counts_.begin(), bin_counts_.end(), 0);
      for (std::size_t s = begin; s < end; ++s) {
        const std::uint32_t sample = samples[s];
        const float v = data_.value(sample, feature);
        const auto bin = static_cast<std::size_t>(
            std::upper_bound(thresholds_.begin(), thresholds_.end(), v) - thresholds_.begin());
        bins_[bin][data_.labels[sample]] += data_.weights[sample];
        ++bin_counts_[bin];
      }
      Histogram left{};
      double left_total = 0.0;
      std::size_t left_count = 0;
      const std::size_t count = end - begin;
      for (int b = 0; b < num_thresholds; ++b) {
        for (int c = 0; c < kNumLabels; ++c) {
          left[c] += bins_[b][c];
          left_total += bins_[b][c];
        }
        left_count += bin_counts_[b];
        const std::size_t right_count = count - left_count;
        if (left_count < min_leaf || right_count < min_leaf) continue;
        Histogram right;
        double right_total = 0.0;
        for (int c = 0; c < kNumLabels; ++c) {
          right[c] = std::max(0.0, parent[c] - left[c]);
          right_total += right[c];
        }
        const double children =
            (left_total * entropy(left, left_total) + right_total * entropy(right, right_total)) /
            parent_total;
        const double gain = parent_entropy - children;
        // Strictly better only: ties keep the first candidate (deterministic).
        if (gain > best.gain + 1e-12) {
          best.valid = true;
          best.feature = feature;
          best.threshold = thresholds_[b];
          best.gain = gain;
        }
      }
    }
    return best;
  }

  const TrainingView& data_;
  const ForestParams& params_;
  TreeRng rng_;
  std::vector<int> order_;
  std::vector<float> thresholds_;
  std::vector<Histogram> bins_;
  std::vector<std::size_t> bin_counts_;
};

// ---------------------------------------------------------------------------
// Serialisation

std::uint64_t fnv1a64(const std::uint8_t* data, std::size_t size) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (std::size_t i = 0; i < size; ++i) {
    h ^= data[i];
    h *= 0x100000001b3ULL;
  }
  return h;
}

std::string idFromChecksum(std::uint64_t checksum) {
  std::ostringstream s;
  s << std::hex << std::setw(8) << std::setfill('0') << (checksum >> 32);
  return s.str();
}

class Writer {
 public:
  void bytes(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    buf_.insert(buf_.end(), b, b + n);
  }
  void u8(std::uint8_t v) { buf_.push_back(v); }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) buf_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) buf_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void f32(float v) { u32(std::bit_cast<std::uint32_t>(v)); }
  void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
  void str(std::string_view s) {
    u32(static_cast<std::uint32_t>(s.size()));
    bytes(s.data(), s.size());
  }
  std::vector<std::uint8_t>& buffer() { return buf_; }

 private:
  std::vector<std::uint8_t> buf_;
};

// Bounds-checked reader; `what` names the field for the error message.
class Reader {
 public:
  Reader(const std::vector<std::uint8_t>& buf, std::size_t end, const std::string& path)
      : buf_(buf), end_(end), path_(path) {}
  std::size_t offset() const { return pos_; }
  std::size_t remaining() const { return end_ - pos_; }
  void need(std::size_t n, const std::string& what) const {
    if (remaining() < n)
      throw Error(path_ + ": forest model is truncated: " + what + " needs " + std::to_string(n) +
                  " bytes at offset " + std::to_string(pos_) + " but only " +
                  std::to_string(remaining()) + " remain");
  }
  std::uint8_t u8(const std::string& what) {
    need(1, what);
    return buf_[pos_++];
  }
  std::uint32_t u32(const std::string& what) {
    need(4, what);
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(buf_[pos_ + i]) << (8 * i);
    pos_ += 4;
    return v;
  }
  std::uint64_t u64(const std::string& what) {
    need(8, what);
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(buf_[pos_ + i]) << (8 * i);
    pos_ += 8;
    return v;
  }
  std::int32_t i32(const std::string& what) { return static_cast<std::int32_t>(u32(what)); }
  float f32(const std::string& what) { return std::bit_cast<float>(u32(what)); }
  double f64(const std::string& what) { return std::bit_cast<double>(u64(what)); }
  std::string str(const std::string& what) {
    const std::uint32_t n = u32(what + " length");
    if (n > kMaxNameLength)
      throw Error(path_ + ": forest model has an absurd " + what + " length " + std::to_string(n) +
                  " at offset " + std::to_string(pos_ - 4));
    need(n, what);
    std::string s(reinterpret_cast<const char*>(buf_.data() + pos_), n);
    pos_ += n;
    return s;
  }

 private:
  const std::vector<std::uint8_t>& buf_;
  std::size_t end_;
  std::size_t pos_ = 0;
  const std::string& path_;
};

void writeParams(Writer& w, const ForestParams& params) {
  w.i32(params.num_trees);
  w.i32(params.max_depth);
  w.i32(params.min_samples_leaf);
  w.i32(params.candidate_features);
  w.i32(params.candidate_thresholds);
  w.u8(params.class_weighting ? 1 : 0);
  w.f64(params.bagging_fraction);
  w.u64(params.seed);
}

void writeFeatureNames(Writer& w, const std::vector<std::string>& names) {
  w.u32(static_cast<std::uint32_t>(names.size()));
  for (const auto& name : names) w.str(name);
}

void writeTrees(Writer& w, const std::vector<RandomForest::Tree>& trees) {
  w.u32(static_cast<std::uint32_t>(trees.size()));
  for (const auto& tree : trees) {
    w.u32(static_cast<std::uint32_t>(tree.size()));
    for (const auto& node : tree) {
      w.i32(node.feature);
      if (node.feature >= 0) {
        w.f32(node.threshold);
        w.i32(node.left);
        w.i32(node.right);
      } else {
        for (float p : node.distribution) w.f32(p);
      }
    }
  }
}

std::vector<std::uint8_t> serialize(const RandomForest& forest) {
  Writer w;
  w.bytes(kMagic, sizeof kMagic);
  w.u32(kFormatVersion);
  w.u32(kNumLabels);
  for (auto name : kLabelNames) w.str(name);
  writeFeatureNames(w, forest.featureNames());
  writeParams(w, forest.params());
  const auto& settings = forest.extractionSettings();
  w.u32(static_cast<std::uint32_t>(settings.size()));
  for (const auto& [key, value] : settings) {
    w.str(key);
    w.str(value);
  }
  writeTrees(w, forest.trees());
  const RandomForest* stage = forest.contextStage();
  w.u8(stage ? 1 : 0);
  if (stage) {
    writeFeatureNames(w, stage->featureNames());
    writeParams(w, stage->params());
    writeTrees(w, stage->trees());
  }
  auto& buf = w.buffer();
  w.u64(fnv1a64(buf.data(), buf.size()));
  return std::move(buf);
}

// Structural checks of one loaded tree: indices in range, every node except
// the root referenced exactly once and only from a node with a smaller index
// (so there are no cycles and every node is reachable), sane leaves.
void validateTree(const RandomForest::Tree& tree, std::size_t t, int dim,
                  const std::string& path) {
  const auto n = static_cast<std::int64_t>(tree.size());
  std::vector<std::uint8_t> referenced(tree.size(), 0);
  auto fail = [&](std::size_t node, const std::string& problem) {
    throw Error(path + ": forest model tree " + std::to_string(t) + " node " +
                std::to_string(node) + ": " + problem);
  };
  for (std::size_t i = 0; i < tree.size(); ++i) {
    const auto& node = tree[i];
    if (node.feature >= 0) {
      if (node.feature >= dim)
        fail(i, "feature index " + std::to_string(node.feature) + " out of range 0.." +
                    std::to_string(dim - 1));
      if (!std::isfinite(node.threshold)) fail(i, "threshold is not finite");
      for (std::int32_t child : {node.left, node.right}) {
        if (child <= 0 || child >= n)
          fail(i, "child index " + std::to_string(child) + " out of range 1.." +
                      std::to_string(n - 1));
        if (static_cast<std::size_t>(child) <= i)
          fail(i, "child index " + std::to_string(child) +
                      " does not follow its parent (cycle or bad order)");
        if (referenced[static_cast<std::size_t>(child)]++)
          fail(i, "node " + std::to_string(child) + " has more than one parent");
      }
    } else if (node.feature == -1) {
      double sum = 0.0;
      for (float p : node.distribution) {
        if (!std::isfinite(p) || p < 0.0f || p > 1.0f)
          fail(i, "leaf probability " + std::to_string(p) + " outside [0, 1]");
        sum += p;
      }
      if (std::abs(sum - 1.0) > 1e-3)
        fail(i, "leaf distribution sums to " + std::to_string(sum) + ", not 1");
    } else {
      fail(i, "feature index " + std::to_string(node.feature) + " is neither a feature nor -1");
    }
  }
  for (std::size_t i = 1; i < tree.size(); ++i)
    if (!referenced[i]) fail(i, "node is not reachable from the root");
}

}  // namespace

// ---------------------------------------------------------------------------

RandomForest RandomForest::train(const TrainingSet& data, const ForestParams& params,
                                 const Progress& progress) {
  validateParams(params, "forest training");
  validateTrainingSet(data);

  TrainingView view{data.features, data.extra, static_cast<int>(data.extra_names.size()),
                    data.labels, {}};
  if (params.candidate_features > view.dim())
    throw Error("forest training: forest parameter candidate_features = " +
                std::to_string(params.candidate_features) + " is invalid (expected 1.." +
                std::to_string(view.dim()) + ", the number of features)");
  view.weights.resize(data.features.size());
  for (std::size_t i = 0; i < view.weights.size(); ++i)
    view.weights[i] = data.weights.empty() ? 1.0 : static_cast<double>(data.weights[i]);
  if (params.class_weighting) {
    // Inverse class frequency (by weight): every present class then carries
    // the same total weight, so rare classes such as chairs still drive splits.
    Histogram class_total{};
    for (std::size_t i = 0; i < view.weights.size(); ++i)
      class_total[data.labels[i]] += view.weights[i];
    double total = 0.0;
    int present = 0;
    for (double c : class_total) {
      total += c;
      present += c > 0.0;
    }
    Histogram factor{};
    for (int c = 0; c < kNumLabels; ++c)
      factor[c] = class_total[c] > 0.0 ? total / (present * class_total[c]) : 0.0;
    for (std::size_t i = 0; i < view.weights.size(); ++i) view.weights[i] *= factor[data.labels[i]];
  }

  RandomForest forest;
  forest.params_ = params;
  for (auto name : kFeatureNames) forest.feature_names_.emplace_back(name);
  for (const auto& name : data.extra_names) forest.feature_names_.push_back(name);
  forest.trees_.resize(static_cast<std::size_t>(params.num_trees));

  int threads = params.num_threads > 0 ? params.num_threads
                                       : static_cast<int>(std::thread::hardware_concurrency());
  threads = std::clamp(threads, 1, params.num_trees);

  std::atomic<int> next_tree{0};
  std::mutex mutex;
  std::condition_variable finished_cv;
  int finished = 0;
  std::exception_ptr failure;
  auto worker = [&] {
    for (;;) {
      const int t = next_tree.fetch_add(1);
      if (t >= params.num_trees) return;
      try {
        TreeBuilder builder(view, params, params.seed + static_cast<std::uint64_t>(t));
        forest.trees_[static_cast<std::size_t>(t)] = builder.build();
      } catch (...) {
        std::lock_guard lock(mutex);
        if (!failure) failure = std::current_exception();
        next_tree = params.num_trees;  // stop handing out work
      }
      {
        std::lock_guard lock(mutex);
        ++finished;
      }
      finished_cv.notify_one();
    }
  };
  std::vector<std::thread> pool;
  // The calling thread reports progress while the workers train, so the
  // callback never runs concurrently with itself or on a worker thread.
  for (int i = 0; i < threads; ++i) pool.emplace_back(worker);
  {
    int reported = 0;
    std::unique_lock lock(mutex);
    while (reported < params.num_trees && !failure) {
      finished_cv.wait(lock, [&] { return finished > reported || failure; });
      while (reported < finished && !failure) {
        ++reported;
        if (progress) {
          lock.unlock();
          try {
            progress(reported, params.num_trees);
          } catch (...) {
            // Stop the workers and rethrow after joining them.
            lock.lock();
            if (!failure) failure = std::current_exception();
            next_tree = params.num_trees;
            break;
          }
          lock.lock();
        }
      }
    }
  }
  for (auto& th : pool) th.join();
  if (failure) std::rethrow_exception(failure);

  forest.setExtractionSettings({});
  return forest;
}

void RandomForest::setExtractionSettings(Settings settings) {
  if (settings.size() > kMaxSettings)
    throw Error("RandomForest: " + std::to_string(settings.size()) +
                " extraction settings (at most " + std::to_string(kMaxSettings) + ")");
  for (const auto& [key, value] : settings) {
    if (key.empty() || key.size() > kMaxNameLength || value.size() > kMaxNameLength)
      throw Error("RandomForest: extraction setting '" + key + "' has an empty or too long name/value");
  }
  extraction_settings_ = std::move(settings);
  updateId();
}

void RandomForest::setContextStage(RandomForest stage) {
  if (stage.empty()) throw Error("RandomForest: the context stage is empty (not trained)");
  if (stage.contextStage())
    throw Error("RandomForest: a context stage cannot have a context stage of its own");
  const auto& names = stage.featureNames();
  if (names.size() <= feature_names_.size() ||
      !std::equal(feature_names_.begin(), feature_names_.end(), names.begin()))
    throw Error("RandomForest: the context stage's rows must start with the first stage's " +
                std::to_string(feature_names_.size()) + " columns and add context columns");
  context_stage_ = std::make_shared<const RandomForest>(std::move(stage));
  updateId();
}

void RandomForest::updateId() {
  // The id names the model's content: settings and context stage included.
  const auto bytes = serialize(*this);
  std::uint64_t checksum = 0;
  for (std::size_t i = 0; i < kChecksumSize; ++i)
    checksum |= static_cast<std::uint64_t>(bytes[bytes.size() - kChecksumSize + i]) << (8 * i);
  id_ = idFromChecksum(checksum);
}

ClassProbabilities RandomForest::predict(std::span<const float> x) const {
  if (trees_.empty())
    throw Error("RandomForest::predict: the forest is empty (not trained/loaded)");
  if (x.size() != feature_names_.size())
    throw Error("RandomForest::predict: a row of " + std::to_string(x.size()) +
                " features for a forest of " + std::to_string(feature_names_.size()));
  std::array<float, kNumLabels> sum{};
  for (const Tree& tree : trees_) {
    const Node* nodes = tree.data();
    std::int32_t i = 0;
    while (nodes[i].feature >= 0)
      i = x[nodes[i].feature] < nodes[i].threshold ? nodes[i].left : nodes[i].right;
    const auto& d = nodes[i].distribution;
    for (int c = 0; c < kNumLabels; ++c) sum[c] += d[c];
  }
  const float inv = 1.0f / static_cast<float>(trees_.size());
  for (float& p : sum) p *= inv;
  return sum;
}

void RandomForest::save(const std::string& path) const {
  if (trees_.empty()) throw Error(path + ": refusing to save an empty forest");
  const auto bytes = serialize(*this);
  // Write to a temporary file and rename, so a crash never leaves a half model.
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(path + ": cannot open '" + tmp + "' for writing");
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    out.flush();
    if (!out) throw Error(path + ": write failed");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw Error(path + ": cannot rename '" + tmp + "' into place");
  }
}

RandomForest RandomForest::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open forest model (missing or unreadable)");
  std::vector<std::uint8_t> buf((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
  if (in.bad()) throw Error(path + ": read error");

  // Magic and version first: a different file type or format gets a message
  // that says so rather than a checksum complaint.
  if (buf.size() < sizeof kMagic + 4) {
    if (buf.size() >= sizeof kMagic && std::memcmp(buf.data(), kMagic, sizeof kMagic) != 0)
      throw Error(path + ": not a findmug forest model (wrong magic)");
    throw Error(path + ": forest model is truncated (" + std::to_string(buf.size()) +
                " bytes, too short for the header)");
  }
  if (std::memcmp(buf.data(), kMagic, sizeof kMagic) != 0)
    throw Error(path + ": not a findmug forest model (wrong magic)");
  std::uint32_t version = 0;
  for (int i = 0; i < 4; ++i)
    version |= static_cast<std::uint32_t>(buf[sizeof kMagic + i]) << (8 * i);
  if (version < kOldestFormatVersion || version > kFormatVersion)
    throw Error(path + ": forest model format version " + std::to_string(version) +
                " is not supported (this build reads versions " +
                std::to_string(kOldestFormatVersion) + ".." + std::to_string(kFormatVersion) + ")");

  // Whether the trailing checksum matches tells apart "truncated or corrupt"
  // from "intact but not loadable by this build" in the messages below.
  bool checksum_ok = false;
  std::uint64_t stored_checksum = 0;
  if (buf.size() >= sizeof kMagic + 4 + kChecksumSize) {
    const std::size_t body = buf.size() - kChecksumSize;
    for (std::size_t i = 0; i < kChecksumSize; ++i)
      stored_checksum |= static_cast<std::uint64_t>(buf[body + i]) << (8 * i);
    checksum_ok = fnv1a64(buf.data(), body) == stored_checksum;
  }

  RandomForest forest;
  try {
    Reader r(buf, buf.size(), path);
    for (std::size_t i = 0; i < sizeof kMagic; ++i) r.u8("magic");
    r.u32("format version");

    const std::uint32_t num_labels = r.u32("label count");
    if (num_labels != kNumLabels)
      throw Error(path + ": forest model has " + std::to_string(num_labels) +
                  " labels, this build has " + std::to_string(kNumLabels));
    for (int c = 0; c < kNumLabels; ++c) {
      const std::string name = r.str("label name");
      if (name != kLabelNames[c])
        throw Error(path + ": forest model label " + std::to_string(c) + " is '" + name +
                    "', this build expects '" + std::string(kLabelNames[c]) +
                    "' (label names differ)");
    }
    // Column names: the 14 base features first; format 3 may add extras.
    auto readFeatureNames = [&](const std::string& stage) {
      const std::uint32_t num_features = r.u32(stage + "feature count");
      if (version == 2 ? num_features != kFeatureDim
                       : (num_features < kFeatureDim || num_features > kMaxFeatures))
        throw Error(path + ": forest model " + stage + "has " + std::to_string(num_features) +
                    " features, this build computes " + std::to_string(kFeatureDim) +
                    (version == 2 ? "" : " base features plus at most " +
                                             std::to_string(kMaxFeatures - kFeatureDim) +
                                             " extra ones"));
      std::vector<std::string> names;
      for (std::uint32_t f = 0; f < num_features; ++f) {
        std::string name = r.str(stage + "feature name");
        if (f < kFeatureDim && name != kFeatureNames[f])
          throw Error(path + ": forest model " + stage + "feature " + std::to_string(f) + " is '" +
                      name + "', this build computes '" + std::string(kFeatureNames[f]) +
                      "' (feature layout differs)");
        if (name.empty()) throw Error(path + ": forest model " + stage + "feature name is empty");
        names.push_back(std::move(name));
      }
      return names;
    };
    auto readParams = [&](ForestParams& p, const std::string& stage) {
      p.num_trees = r.i32(stage + "params.num_trees");
      p.max_depth = r.i32(stage + "params.max_depth");
      p.min_samples_leaf = r.i32(stage + "params.min_samples_leaf");
      p.candidate_features = r.i32(stage + "params.candidate_features");
      p.candidate_thresholds = r.i32(stage + "params.candidate_thresholds");
      const std::uint8_t weighting = r.u8(stage + "params.class_weighting");
      if (weighting > 1)
        throw Error(path + ": forest model " + stage + "params.class_weighting = " +
                    std::to_string(weighting) + " (expected 0 or 1)");
      p.class_weighting = weighting == 1;
      p.bagging_fraction = r.f64(stage + "params.bagging_fraction");
      p.seed = r.u64(stage + "params.seed");
      validateParams(p, path);
    };
    auto readTrees = [&](RandomForest& f, const std::string& stage) {
      const std::uint32_t num_trees = r.u32(stage + "tree count");
      if (num_trees == 0 || num_trees > kMaxTrees)
        throw Error(path + ": forest model " + stage + "has an absurd num_trees " +
                    std::to_string(num_trees) + " (expected 1.." + std::to_string(kMaxTrees) + ")");
      if (num_trees != static_cast<std::uint32_t>(f.params_.num_trees))
        throw Error(path + ": forest model " + stage + "holds " + std::to_string(num_trees) +
                    " trees but params.num_trees = " + std::to_string(f.params_.num_trees));
      f.trees_.resize(num_trees);
      for (std::uint32_t t = 0; t < num_trees; ++t) {
        const std::string tree_name = stage + "tree " + std::to_string(t);
        const std::uint32_t num_nodes = r.u32(tree_name + " node count");
        // Every node takes at least kInnerNodeBytes, so a count the rest of the
        // file cannot hold is refused before allocating for it.
        if (num_nodes == 0) throw Error(path + ": forest model " + tree_name + " has no nodes");
        if (num_nodes > r.remaining() / kInnerNodeBytes)
          throw Error(path + ": forest model " + tree_name + " has node count " +
                      std::to_string(num_nodes) + " but only " + std::to_string(r.remaining()) +
                      " bytes remain (absurd count, or the file is truncated)");
        Tree& tree = f.trees_[t];
        tree.resize(num_nodes);
        for (std::uint32_t i = 0; i < num_nodes; ++i) {
          Node& node = tree[i];
          node.feature = r.i32(tree_name + " node feature");
          if (node.feature >= 0) {
            node.threshold = r.f32(tree_name + " node threshold");
            node.left = r.i32(tree_name + " node left");
            node.right = r.i32(tree_name + " node right");
          } else {
            r.need(kLeafNodeBytes - 4, tree_name + " leaf distribution");
            for (float& prob : node.distribution) prob = r.f32(tree_name + " leaf distribution");
          }
        }
        validateTree(tree, t, f.dim(), path);
      }
    };

    forest.feature_names_ = readFeatureNames("");
    readParams(forest.params_, "");

    const std::uint32_t num_settings = r.u32("extraction setting count");
    if (num_settings > kMaxSettings)
      throw Error(path + ": forest model has an absurd extraction setting count " +
                  std::to_string(num_settings) + " (at most " + std::to_string(kMaxSettings) + ")");
    for (std::uint32_t i = 0; i < num_settings; ++i) {
      std::string key = r.str("extraction setting name");
      std::string value = r.str("extraction setting value");
      if (key.empty()) throw Error(path + ": forest model has an extraction setting without a name");
      forest.extraction_settings_.emplace_back(std::move(key), std::move(value));
    }

    readTrees(forest, "");
    if (version >= 3) {
      const std::uint8_t has_stage = r.u8("context stage flag");
      if (has_stage > 1)
        throw Error(path + ": forest model context stage flag = " + std::to_string(has_stage) +
                    " (expected 0 or 1)");
      if (has_stage == 1) {
        RandomForest stage;
        stage.feature_names_ = readFeatureNames("context stage ");
        if (stage.feature_names_.size() <= forest.feature_names_.size() ||
            !std::equal(forest.feature_names_.begin(), forest.feature_names_.end(),
                        stage.feature_names_.begin()))
          throw Error(path + ": forest model context stage columns do not start with the " +
                      std::to_string(forest.feature_names_.size()) +
                      " first-stage columns followed by context columns");
        readParams(stage.params_, "context stage ");
        readTrees(stage, "context stage ");
        stage.format_version_ = version;
        forest.context_stage_ = std::make_shared<const RandomForest>(std::move(stage));
      }
    }
    if (r.remaining() < kChecksumSize) r.need(kChecksumSize, "checksum");
    if (r.remaining() > kChecksumSize)
      throw Error(path + ": forest model has " + std::to_string(r.remaining() - kChecksumSize) +
                  " unexpected bytes after the trees");
  } catch (const Error& e) {
    if (checksum_ok) throw;
    throw Error(std::string(e.what()) + " [checksum mismatch too: file truncated or corrupt]");
  }
  if (!checksum_ok)
    throw Error(path + ": forest model checksum mismatch (file corrupt; stored " +
                idFromChecksum(stored_checksum) + "...)");
  forest.id_ = idFromChecksum(stored_checksum);
  forest.source_ = path;
  forest.format_version_ = version;
  return forest;
}

}  // namespace findmug
