// forest_format.cpp — the RandomForest model file: writing (save), reading
// with every length and index checked before use (load), and the checksum /
// id. The layout is documented in forest_format.hpp.
#include "learner/forest_format.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <sstream>

#include "findmug/common/error.hpp"
#include "learner/xgboost_learner.hpp"

namespace findmug {

namespace forest_format {

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

}  // namespace forest_format

using namespace forest_format;

namespace {

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

}  // namespace

std::vector<std::uint8_t> forest_format::serialize(const RandomForest& forest) {
  Writer w;
  w.bytes(kMagic, sizeof kMagic);
  w.u32(kFormatVersion);
  w.u32(kNumLabels);
  for (auto name : kLabelNames) w.str(name);
  const RandomForest::Booster* booster = forest.booster();
  w.u8(static_cast<std::uint8_t>(forest.learnerKind()));
  const InternalClasses& classes = forest.internalClasses();
  w.str(classes.scheme);
  w.u32(static_cast<std::uint32_t>(classes.names.size()));
  for (std::size_t c = 0; c < classes.names.size(); ++c) {
    w.str(classes.names[c]);
    w.u8(classes.to_label[c]);
  }
  writeFeatureNames(w, forest.featureNames());
  if (booster) {
    const XGBoostParams& p = forest.xgboostParams();
    w.i32(p.rounds);
    w.i32(p.max_depth);
    w.f64(p.eta);
    w.f64(p.subsample);
    w.f64(p.colsample);
    w.f64(p.min_child_weight);
    w.f64(p.lambda);
    w.i32(p.seed);
    w.u8(forest.params().class_weighting ? 1 : 0);
  } else {
    writeParams(w, forest.params());
  }
  const auto& settings = forest.extractionSettings();
  w.u32(static_cast<std::uint32_t>(settings.size()));
  for (const auto& [key, value] : settings) {
    w.str(key);
    w.str(value);
  }
  if (booster) {
    w.u64(booster->blob.size());
    w.bytes(booster->blob.data(), booster->blob.size());
  } else {
    writeTrees(w, forest.trees());
  }
  const RandomForest* round = forest.contextRound();
  w.u8(round ? 1 : 0);
  if (round) {
    writeFeatureNames(w, round->featureNames());
    writeParams(w, round->params());
    writeTrees(w, round->trees());
  }
  const PairwiseContext* pairwise = forest.pairwiseContext();
  w.u8(pairwise ? 1 : 0);
  if (pairwise) {
    w.f64(pairwise->bias);
    for (double v : pairwise->weights) w.f64(v);
    for (double v : pairwise->mean) w.f64(v);
    for (double v : pairwise->scale) w.f64(v);
    w.f64(pairwise->mean_cost);
    w.u64(pairwise->training_edges);
  }
  auto& buf = w.buffer();
  w.u64(fnv1a64(buf.data(), buf.size()));
  return std::move(buf);
}

namespace {

// Structural checks of one loaded tree: indices in range, every node except
// the root referenced exactly once and only from a node with a smaller index
// (so there are no cycles and every node is reachable), sane leaves.
void validateTree(const RandomForest::Tree& tree, std::size_t t, int dim, const std::string& path) {
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

void RandomForest::save(const std::string& path) const {
  if (empty()) throw Error(path + ": refusing to save an empty model");
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
    // Format 4: the learner and the internal classes.
    bool boosted = false;
    if (version >= 4) {
      const std::uint8_t kind = r.u8("learner");
      if (kind > 1)
        throw Error(path + ": forest model learner = " + std::to_string(kind) +
                    " (expected 0 forest or 1 xgboost)");
      boosted = kind == 1;
      InternalClasses classes;
      classes.names.clear();
      classes.scheme = r.str("internal class scheme");
      const std::uint32_t count = r.u32("internal class count");
      if (count < 1 || count > kMaxInternalClasses)
        throw Error(path + ": bad class map: " + std::to_string(count) +
                    " internal classes (expected 1.." + std::to_string(kMaxInternalClasses) + ")");
      for (std::uint32_t c = 0; c < count; ++c) {
        classes.names.push_back(r.str("internal class name"));
        classes.to_label.push_back(r.u8("internal class label"));
      }
      validateInternalClasses(classes, path);
      forest.internal_classes_ = std::move(classes);
    }
    // Column names: the 14 base features first; format 3 may add extras.
    auto readFeatureNames = [&](const std::string& which) {
      const std::uint32_t num_features = r.u32(which + "feature count");
      if (version == 2 ? num_features != kFeatureDim
                       : (num_features < kFeatureDim || num_features > kMaxFeatures))
        throw Error(path + ": forest model " + which + "has " + std::to_string(num_features) +
                    " features, this build computes " + std::to_string(kFeatureDim) +
                    (version == 2
                         ? ""
                         : " base features plus at most " +
                               std::to_string(kMaxFeatures - kFeatureDim) + " extra ones"));
      std::vector<std::string> names;
      for (std::uint32_t f = 0; f < num_features; ++f) {
        std::string name = r.str(which + "feature name");
        if (f < kFeatureDim && name != kFeatureNames[f])
          throw Error(path + ": forest model " + which + "feature " + std::to_string(f) + " is '" +
                      name + "', this build computes '" + std::string(kFeatureNames[f]) +
                      "' (feature layout differs)");
        if (name.empty()) throw Error(path + ": forest model " + which + "feature name is empty");
        names.push_back(std::move(name));
      }
      return names;
    };
    auto readParams = [&](ForestParams& p, const std::string& which) {
      p.num_trees = r.i32(which + "params.num_trees");
      p.max_depth = r.i32(which + "params.max_depth");
      p.min_samples_leaf = r.i32(which + "params.min_samples_leaf");
      p.candidate_features = r.i32(which + "params.candidate_features");
      p.candidate_thresholds = r.i32(which + "params.candidate_thresholds");
      const std::uint8_t weighting = r.u8(which + "params.class_weighting");
      if (weighting > 1)
        throw Error(path + ": forest model " + which +
                    "params.class_weighting = " + std::to_string(weighting) + " (expected 0 or 1)");
      p.class_weighting = weighting == 1;
      p.bagging_fraction = r.f64(which + "params.bagging_fraction");
      p.seed = r.u64(which + "params.seed");
      validateParams(p, path);
    };
    auto readTrees = [&](RandomForest& f, const std::string& which) {
      const std::uint32_t num_trees = r.u32(which + "tree count");
      if (num_trees == 0 || num_trees > kMaxTrees)
        throw Error(path + ": forest model " + which + "has an absurd num_trees " +
                    std::to_string(num_trees) + " (expected 1.." + std::to_string(kMaxTrees) + ")");
      if (num_trees != static_cast<std::uint32_t>(f.params_.num_trees))
        throw Error(path + ": forest model " + which + "holds " + std::to_string(num_trees) +
                    " trees but params.num_trees = " + std::to_string(f.params_.num_trees));
      f.trees_.resize(num_trees);
      for (std::uint32_t t = 0; t < num_trees; ++t) {
        const std::string tree_name = which + "tree " + std::to_string(t);
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
    if (boosted) {
      XGBoostParams& p = forest.xgboost_params_;
      p.rounds = r.i32("xgboost.rounds");
      p.max_depth = r.i32("xgboost.max_depth");
      p.eta = r.f64("xgboost.eta");
      p.subsample = r.f64("xgboost.subsample");
      p.colsample = r.f64("xgboost.colsample");
      p.min_child_weight = r.f64("xgboost.min_child_weight");
      p.lambda = r.f64("xgboost.lambda");
      p.seed = r.i32("xgboost.seed");
      const std::uint8_t weighting = r.u8("xgboost class_weighting");
      if (weighting > 1)
        throw Error(path + ": forest model xgboost class_weighting = " +
                    std::to_string(weighting) + " (expected 0 or 1)");
      forest.params_.class_weighting = weighting == 1;
      xgboost_learner::validateParams(p, path);
    } else {
      readParams(forest.params_, "");
    }

    const std::uint32_t num_settings = r.u32("extraction setting count");
    if (num_settings > kMaxSettings)
      throw Error(path + ": forest model has an absurd extraction setting count " +
                  std::to_string(num_settings) + " (at most " + std::to_string(kMaxSettings) + ")");
    for (std::uint32_t i = 0; i < num_settings; ++i) {
      std::string key = r.str("extraction setting name");
      std::string value = r.str("extraction setting value");
      if (key.empty())
        throw Error(path + ": forest model has an extraction setting without a name");
      forest.extraction_settings_.emplace_back(std::move(key), std::move(value));
    }

    if (boosted) {
      const std::uint64_t length = r.u64("booster length");
      if (length == 0 || length > r.remaining())
        throw Error(path + ": xgboost booster blob of " + std::to_string(length) +
                    " bytes but only " + std::to_string(r.remaining()) +
                    " remain (booster blob truncated)");
      // XGBoost's own parser gets only bytes the checksum vouches for.
      if (!checksum_ok)
        throw Error(path + ": forest model checksum mismatch (file corrupt; the xgboost booster "
                    "was not read)");
      std::vector<std::uint8_t> blob(length);
      for (auto& b : blob) b = r.u8("booster");
      forest.booster_ = Booster::fromBlob(std::move(blob), forest.internal_classes_.count(),
                                          forest.dim(), path);
    } else {
      readTrees(forest, "");
    }
    if (version >= 3) {
      const std::uint8_t has_round = r.u8("context round flag");
      if (has_round > 1)
        throw Error(path + ": forest model context round flag = " + std::to_string(has_round) +
                    " (expected 0 or 1)");
      if (has_round == 1 && boosted)
        throw Error(path + ": an xgboost model cannot have an auto-context round");
      if (has_round == 1) {
        RandomForest round;
        round.feature_names_ = readFeatureNames("context round ");
        if (round.feature_names_.size() <= forest.feature_names_.size() ||
            !std::equal(forest.feature_names_.begin(), forest.feature_names_.end(),
                        round.feature_names_.begin()))
          throw Error(path + ": forest model context round columns do not start with the " +
                      std::to_string(forest.feature_names_.size()) +
                      " first-round columns followed by context columns");
        readParams(round.params_, "context round ");
        readTrees(round, "context round ");
        round.format_version_ = version;
        forest.context_round_ = std::make_shared<const RandomForest>(std::move(round));
      }
    }
    if (version >= 5) {
      const std::uint8_t has_pairwise = r.u8("pairwise term flag");
      if (has_pairwise > 1)
        throw Error(path + ": forest model pairwise term flag = " + std::to_string(has_pairwise) +
                    " (expected 0 or 1)");
      if (has_pairwise == 1) {
        PairwiseContext term;
        term.bias = r.f64("pairwise term bias");
        for (double& v : term.weights) v = r.f64("pairwise term weights");
        for (double& v : term.mean) v = r.f64("pairwise term means");
        for (double& v : term.scale) v = r.f64("pairwise term scales");
        term.mean_cost = r.f64("pairwise term mean cost");
        term.training_edges = r.u64("pairwise term training edges");
        validatePairwiseContext(term, path + ": forest model");
        forest.pairwise_context_ = term;
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
