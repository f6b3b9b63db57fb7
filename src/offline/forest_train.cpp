// forest_train.cpp — RandomForest::train: node splitting by information
// gain over random (feature, threshold) candidates, seeded per tree, trees
// built by a pool of threads that lives only for the call; the calling thread
// reports progress. Built into findmug_offline, not the core: the daemon and the
// package never train (RandomForest::train and trainBoosted are declared with the
// model type in forest.hpp and defined here and in xgboost_train.cpp).
//
// Training follows Criminisi et al.: at every node a few random features and,
// per feature, a few random thresholds between the node's minimum and maximum
// of that feature are tried; the candidate with the highest weighted
// information gain (Shannon entropy of the weighted label histograms) wins.
// A node becomes a leaf at max_depth, when it is pure, or when no candidate
// leaves at least min_samples_leaf samples on each side. With forest.shrinkage
// the leaves hold their path's histograms shrunk towards the root's
// (hierarchical shrinkage), so that a leaf of five patches says less than
// its ancestors of thousands.
//
// Split labels (TrainingSet::split_labels): the gain may be measured over
// finer classes than the ones the leaves hold (e.g. NYU-40 "bookshelf",
// "dresser", "night stand" instead of one "cabinet"). A coarse class made of
// unlike things then gets split by what tells its parts apart, while the
// leaves, and so the model file and prediction, stay in the 8 classes.
//
// Reproducibility: tree t draws every random number from its own generator
// seeded with seed + t, and random numbers are turned into integers/reals by
// our own code (not std::*_distribution, whose output is implementation
// defined), so a seed gives a byte-identical model whatever the thread count.
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <limits>
#include <mutex>
#include <random>
#include <thread>

#include "findmug/common/error.hpp"
#include "findmug/learner/forest.hpp"
#include "learner/forest_format.hpp"

namespace findmug {

using namespace forest_format;

namespace {

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
  if (data.weight_by_split_labels && data.split_labels.empty())
    throw Error("forest training: weighting by split labels without split labels");
  if (!data.split_labels.empty()) {
    if (data.split_labels.size() != n)
      throw Error("forest training: " + std::to_string(n) + " feature vectors but " +
                  std::to_string(data.split_labels.size()) + " split labels");
    if (data.split_classes < 1 || data.split_classes > kMaxSplitClasses)
      throw Error("forest training: split_classes = " + std::to_string(data.split_classes) +
                  " (expected 1.." + std::to_string(kMaxSplitClasses) + ")");
    for (std::size_t i = 0; i < n; ++i)
      if (data.split_labels[i] >= data.split_classes)
        throw Error("forest training: sample " + std::to_string(i) + " has split label " +
                    std::to_string(data.split_labels[i]) + " (expected 0.." +
                    std::to_string(data.split_classes - 1) + ")");
  }
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

// Entropy of the first k bins of a histogram with the given total.
double entropy(const double* h, int k, double total) {
  if (total <= 0.0) return 0.0;
  double e = 0.0;
  for (int c = 0; c < k; ++c) {
    if (h[c] > 0.0) {
      const double p = h[c] / total;
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
  // The classes the split gain is measured over: `labels` itself (k = 8) or
  // the training set's split labels.
  const std::vector<std::uint8_t>& split_labels;
  int split_classes;
  std::vector<double> weights;  // per sample, including class weighting
  int dim() const { return kFeatureDim + extra_dim; }
  float value(std::uint32_t sample, int f) const {
    return f < kFeatureDim
               ? features[sample][f]
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
    // Hierarchical shrinkage (forest.shrinkage): a node's answer is its
    // parent's answer plus its own histogram's change over the parent's,
    // damped by 1 / (1 + lambda / parent samples), so small nodes deep down
    // move the root's answer less (Agarwal et al., 2022). Each pending node
    // carries its parent's histogram, sample count and answer.
    struct Pending {
      std::int32_t node;
      std::size_t begin, end;
      int depth;
      Histogram parent_mean{};
      Histogram parent_answer{};
      double parent_count = 0;  // 0 at the root
    };
    std::vector<Pending> stack{{0, 0, samples.size(), 0, {}, {}, 0}};
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

      const std::size_t count = job.end - job.begin;
      Histogram mean{}, answer{};
      for (int c = 0; c < kNumLabels; ++c) mean[c] = hist[c] / total;
      // Without shrinkage (or at the root) the node's own histogram, to the bit.
      const bool shrink = params_.shrinkage > 0.0 && job.parent_count > 0;
      const double damping = shrink ? 1.0 / (1.0 + params_.shrinkage / job.parent_count) : 1.0;
      for (int c = 0; c < kNumLabels; ++c)
        answer[c] = shrink ? job.parent_answer[c] + (mean[c] - job.parent_mean[c]) * damping
                           : mean[c];

      Split split;
      const bool can_split = job.depth < params_.max_depth && classes_present > 1 &&
                             count >= 2 * static_cast<std::size_t>(params_.min_samples_leaf);
      if (can_split) {
        // The parent histogram over the split classes (the same sums as
        // `hist` when the split classes are the labels).
        const int k = data_.split_classes;
        parent_.assign(static_cast<std::size_t>(k), 0.0);
        for (std::size_t s = job.begin; s < job.end; ++s)
          parent_[data_.split_labels[samples[s]]] += data_.weights[samples[s]];
        double split_total = 0.0;
        for (double c : parent_) split_total += c;
        split = findSplit(samples, job.begin, job.end, parent_.data(), split_total);
      }

      if (!split.valid) {
        RandomForest::Node& leaf = tree[job.node];
        leaf.feature = -1;
        for (int c = 0; c < kNumLabels; ++c) leaf.distribution[c] = static_cast<float>(answer[c]);
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
      const auto parent_count = static_cast<double>(count);
      stack.push_back({right, mid, job.end, job.depth + 1, mean, answer, parent_count});
      stack.push_back({left, job.begin, mid, job.depth + 1, mean, answer, parent_count});
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
                  const double* parent, double parent_total) {
    const int k_classes = data_.split_classes;
    const auto k_size = static_cast<std::size_t>(k_classes);
    const double parent_entropy = entropy(parent, k_classes, parent_total);
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
    bins_.assign((static_cast<std::size_t>(num_thresholds) + 1) * k_size, 0.0);
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
      std::fill(bins_.begin(), bins_.end(), 0.0);
      std::fill(bin_counts_.begin(), bin_counts_.end(), 0);
      for (std::size_t s = begin; s < end; ++s) {
        const std::uint32_t sample = samples[s];
        const float v = data_.value(sample, feature);
        const auto bin = static_cast<std::size_t>(
            std::upper_bound(thresholds_.begin(), thresholds_.end(), v) - thresholds_.begin());
        bins_[bin * k_size + data_.split_labels[sample]] += data_.weights[sample];
        ++bin_counts_[bin];
      }
      left_.assign(k_size, 0.0);
      right_.resize(k_size);
      double* left = left_.data();
      double* right = right_.data();
      double left_total = 0.0;
      std::size_t left_count = 0;
      const std::size_t count = end - begin;
      for (int b = 0; b < num_thresholds; ++b) {
        const double* bin = bins_.data() + static_cast<std::size_t>(b) * k_size;
        for (int c = 0; c < k_classes; ++c) {
          left[c] += bin[c];
          left_total += bin[c];
        }
        left_count += bin_counts_[b];
        const std::size_t right_count = count - left_count;
        if (left_count < min_leaf || right_count < min_leaf) continue;
        double right_total = 0.0;
        for (int c = 0; c < k_classes; ++c) {
          right[c] = std::max(0.0, parent[c] - left[c]);
          right_total += right[c];
        }
        const double children = (left_total * entropy(left, k_classes, left_total) +
                                 right_total * entropy(right, k_classes, right_total)) /
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
  std::vector<double> bins_;  // (thresholds + 1) x split classes
  std::vector<std::size_t> bin_counts_;
  std::vector<double> parent_, left_, right_;
};

}  // namespace

// ---------------------------------------------------------------------------

RandomForest RandomForest::train(const TrainingSet& data, const ForestParams& params,
                                 const Progress& progress) {
  validateParams(params, "forest training");
  validateTrainingSet(data);

  const bool own_split_labels = !data.split_labels.empty();
  TrainingView view{data.features,
                    data.extra,
                    static_cast<int>(data.extra_names.size()),
                    data.labels,
                    own_split_labels ? data.split_labels : data.labels,
                    own_split_labels ? data.split_classes : kNumLabels,
                    {}};
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
    // With weight_by_split_labels the classes are the internal ones
    // (learner.classes): each fine class then carries the same total weight.
    const bool by_split = data.weight_by_split_labels;
    const std::vector<std::uint8_t>& classes = by_split ? data.split_labels : data.labels;
    const auto num_classes = static_cast<std::size_t>(by_split ? data.split_classes : kNumLabels);
    std::vector<double> class_total(num_classes, 0.0);
    for (std::size_t i = 0; i < view.weights.size(); ++i)
      class_total[classes[i]] += view.weights[i];
    double total = 0.0;
    int present = 0;
    for (double c : class_total) {
      total += c;
      present += c > 0.0;
    }
    std::vector<double> factor(num_classes, 0.0);
    for (std::size_t c = 0; c < num_classes; ++c)
      factor[c] = class_total[c] > 0.0 ? total / (present * class_total[c]) : 0.0;
    for (std::size_t i = 0; i < view.weights.size(); ++i) view.weights[i] *= factor[classes[i]];
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

}  // namespace findmug
