// forest_format.cpp — the RandomForest model file: writing (save), reading
// with every length and index checked before use (load, one step per section
// of the file), and the checksum / id. The layout is documented in forest_format.hpp.
#include "learner/forest_format.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <memory>
#include <optional>
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

namespace {

// The whole file; refuses one that cannot be opened or read.
std::vector<std::uint8_t> readModelFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open forest model (missing or unreadable)");
  std::vector<std::uint8_t> buf((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
  if (in.bad()) throw Error(path + ": read error");
  return buf;
}

// Magic and version first: a different file type or format gets a message
// that says so rather than a checksum complaint. Returns the version.
std::uint32_t checkMagicAndVersion(const std::vector<std::uint8_t>& buf, const std::string& path) {
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
  return version;
}

// The trailing checksum and whether it matches the bytes before it. It tells
// apart "truncated or corrupt" from "intact but not loadable by this build"
// in load's messages.
struct StoredChecksum {
  std::uint64_t value = 0;
  bool matches = false;
};
StoredChecksum storedChecksum(const std::vector<std::uint8_t>& buf) {
  StoredChecksum checksum;
  if (buf.size() >= sizeof kMagic + 4 + kChecksumSize) {
    const std::size_t body = buf.size() - kChecksumSize;
    for (std::size_t i = 0; i < kChecksumSize; ++i)
      checksum.value |= static_cast<std::uint64_t>(buf[body + i]) << (8 * i);
    checksum.matches = fnv1a64(buf.data(), body) == checksum.value;
  }
  return checksum;
}

// Reads the sections of one model file in their order (forest_format.hpp),
// each checked as it is read. `which` prefixes the fields of the context
// round ("context round ") in the messages.
class SectionReader {
 public:
  SectionReader(Reader& r, const std::string& path, std::uint32_t version)
      : r_(r), path_(path), version_(version) {}

  void header() {
    for (std::size_t i = 0; i < sizeof kMagic; ++i) r_.u8("magic");
    r_.u32("format version");
  }

  void labelNames() {
    const std::uint32_t num_labels = r_.u32("label count");
    if (num_labels != kNumLabels)
      throw Error(path_ + ": forest model has " + std::to_string(num_labels) +
                  " labels, this build has " + std::to_string(kNumLabels));
    for (int c = 0; c < kNumLabels; ++c) {
      const std::string name = r_.str("label name");
      if (name != kLabelNames[c])
        throw Error(path_ + ": forest model label " + std::to_string(c) + " is '" + name +
                    "', this build expects '" + std::string(kLabelNames[c]) +
                    "' (label names differ)");
    }
  }

  // Format 4: the learner and the internal classes. Returns whether the
  // learner is xgboost.
  bool learnerAndClasses(InternalClasses& internal_classes) {
    const std::uint8_t kind = r_.u8("learner");
    if (kind > 1)
      throw Error(path_ + ": forest model learner = " + std::to_string(kind) +
                  " (expected 0 forest or 1 xgboost)");
    InternalClasses classes;
    classes.names.clear();
    classes.scheme = r_.str("internal class scheme");
    const std::uint32_t count = r_.u32("internal class count");
    if (count < 1 || count > kMaxInternalClasses)
      throw Error(path_ + ": bad class map: " + std::to_string(count) +
                  " internal classes (expected 1.." + std::to_string(kMaxInternalClasses) + ")");
    for (std::uint32_t c = 0; c < count; ++c) {
      classes.names.push_back(r_.str("internal class name"));
      classes.to_label.push_back(r_.u8("internal class label"));
    }
    validateInternalClasses(classes, path_);
    internal_classes = std::move(classes);
    return kind == 1;
  }

  // Column names: the 14 base features first; format 3 may add extras.
  std::vector<std::string> featureNames(const std::string& which) {
    const std::uint32_t num_features = r_.u32(which + "feature count");
    if (version_ == 2 ? num_features != kFeatureDim
                      : (num_features < kFeatureDim || num_features > kMaxFeatures))
      throw Error(path_ + ": forest model " + which + "has " + std::to_string(num_features) +
                  " features, this build computes " + std::to_string(kFeatureDim) +
                  (version_ == 2 ? ""
                                 : " base features plus at most " +
                                       std::to_string(kMaxFeatures - kFeatureDim) + " extra ones"));
    std::vector<std::string> names;
    for (std::uint32_t f = 0; f < num_features; ++f) {
      std::string name = r_.str(which + "feature name");
      if (f < kFeatureDim && name != kFeatureNames[f])
        throw Error(path_ + ": forest model " + which + "feature " + std::to_string(f) + " is '" +
                    name + "', this build computes '" + std::string(kFeatureNames[f]) +
                    "' (feature layout differs)");
      if (name.empty()) throw Error(path_ + ": forest model " + which + "feature name is empty");
      names.push_back(std::move(name));
    }
    return names;
  }

  void forestParams(ForestParams& p, const std::string& which) {
    p.num_trees = r_.i32(which + "params.num_trees");
    p.max_depth = r_.i32(which + "params.max_depth");
    p.min_samples_leaf = r_.i32(which + "params.min_samples_leaf");
    p.candidate_features = r_.i32(which + "params.candidate_features");
    p.candidate_thresholds = r_.i32(which + "params.candidate_thresholds");
    const std::uint8_t weighting = r_.u8(which + "params.class_weighting");
    if (weighting > 1)
      throw Error(path_ + ": forest model " + which +
                  "params.class_weighting = " + std::to_string(weighting) + " (expected 0 or 1)");
    p.class_weighting = weighting == 1;
    p.bagging_fraction = r_.f64(which + "params.bagging_fraction");
    p.seed = r_.u64(which + "params.seed");
    validateParams(p, path_);
  }

  // An xgboost model's parameters; its class weighting goes to
  // `class_weighting` (the forest parameters' field, as for a forest).
  void boosterParams(XGBoostParams& p, bool& class_weighting) {
    p.rounds = r_.i32("xgboost.rounds");
    p.max_depth = r_.i32("xgboost.max_depth");
    p.eta = r_.f64("xgboost.eta");
    p.subsample = r_.f64("xgboost.subsample");
    p.colsample = r_.f64("xgboost.colsample");
    p.min_child_weight = r_.f64("xgboost.min_child_weight");
    p.lambda = r_.f64("xgboost.lambda");
    p.seed = r_.i32("xgboost.seed");
    const std::uint8_t weighting = r_.u8("xgboost class_weighting");
    if (weighting > 1)
      throw Error(path_ + ": forest model xgboost class_weighting = " + std::to_string(weighting) +
                  " (expected 0 or 1)");
    class_weighting = weighting == 1;
    xgboost_learner::validateParams(p, path_);
  }

  void extractionSettings(RandomForest::Settings& settings) {
    const std::uint32_t num_settings = r_.u32("extraction setting count");
    if (num_settings > kMaxSettings)
      throw Error(path_ + ": forest model has an absurd extraction setting count " +
                  std::to_string(num_settings) + " (at most " + std::to_string(kMaxSettings) + ")");
    for (std::uint32_t i = 0; i < num_settings; ++i) {
      std::string key = r_.str("extraction setting name");
      std::string value = r_.str("extraction setting value");
      if (key.empty())
        throw Error(path_ + ": forest model has an extraction setting without a name");
      settings.emplace_back(std::move(key), std::move(value));
    }
  }

  // XGBoost's own parser gets only bytes the checksum vouches for.
  std::shared_ptr<const RandomForest::Booster> booster(bool checksum_ok, int num_classes, int dim) {
    const std::uint64_t length = r_.u64("booster length");
    if (length == 0 || length > r_.remaining())
      throw Error(path_ + ": xgboost booster blob of " + std::to_string(length) +
                  " bytes but only " + std::to_string(r_.remaining()) +
                  " remain (booster blob truncated)");
    if (!checksum_ok)
      throw Error(path_ +
                  ": forest model checksum mismatch (file corrupt; the xgboost booster "
                  "was not read)");
    std::vector<std::uint8_t> blob(length);
    for (auto& b : blob) b = r_.u8("booster");
    return RandomForest::Booster::fromBlob(std::move(blob), num_classes, dim, path_);
  }

  // The trees of a forest on `dim` features, into `out`: as many as its
  // params.num_trees (`num_trees_param`) says.
  void trees(std::vector<RandomForest::Tree>& out, int num_trees_param, int dim,
             const std::string& which) {
    const std::uint32_t num_trees = r_.u32(which + "tree count");
    if (num_trees == 0 || num_trees > kMaxTrees)
      throw Error(path_ + ": forest model " + which + "has an absurd num_trees " +
                  std::to_string(num_trees) + " (expected 1.." + std::to_string(kMaxTrees) + ")");
    if (num_trees != static_cast<std::uint32_t>(num_trees_param))
      throw Error(path_ + ": forest model " + which + "holds " + std::to_string(num_trees) +
                  " trees but params.num_trees = " + std::to_string(num_trees_param));
    out.resize(num_trees);
    for (std::uint32_t t = 0; t < num_trees; ++t) {
      tree(out[t], which + "tree " + std::to_string(t));
      validateTree(out[t], t, dim, path_);
    }
  }

  // Format 3: whether an auto-context round follows.
  bool contextRoundFlag(bool boosted) {
    const std::uint8_t has_round = r_.u8("context round flag");
    if (has_round > 1)
      throw Error(path_ + ": forest model context round flag = " + std::to_string(has_round) +
                  " (expected 0 or 1)");
    if (has_round == 1 && boosted)
      throw Error(path_ + ": an xgboost model cannot have an auto-context round");
    return has_round == 1;
  }

  // The context round's columns: the first round's, then context columns.
  void checkContextColumns(const std::vector<std::string>& first,
                           const std::vector<std::string>& round) const {
    if (round.size() <= first.size() || !std::equal(first.begin(), first.end(), round.begin()))
      throw Error(path_ + ": forest model context round columns do not start with the " +
                  std::to_string(first.size()) +
                  " first-round columns followed by context columns");
  }

  // Format 5: the learned pairwise term, if the file has one.
  std::optional<PairwiseContext> pairwiseTerm() {
    const std::uint8_t has_pairwise = r_.u8("pairwise term flag");
    if (has_pairwise > 1)
      throw Error(path_ + ": forest model pairwise term flag = " + std::to_string(has_pairwise) +
                  " (expected 0 or 1)");
    if (has_pairwise != 1) return std::nullopt;
    PairwiseContext term;
    term.bias = r_.f64("pairwise term bias");
    for (double& v : term.weights) v = r_.f64("pairwise term weights");
    for (double& v : term.mean) v = r_.f64("pairwise term means");
    for (double& v : term.scale) v = r_.f64("pairwise term scales");
    term.mean_cost = r_.f64("pairwise term mean cost");
    term.training_edges = r_.u64("pairwise term training edges");
    validatePairwiseContext(term, path_ + ": forest model");
    return term;
  }

  // Nothing but the checksum after the last section.
  void end() {
    if (r_.remaining() < kChecksumSize) r_.need(kChecksumSize, "checksum");
    if (r_.remaining() > kChecksumSize)
      throw Error(path_ + ": forest model has " + std::to_string(r_.remaining() - kChecksumSize) +
                  " unexpected bytes after the trees");
  }

 private:
  void tree(RandomForest::Tree& out, const std::string& tree_name) {
    const std::uint32_t num_nodes = r_.u32(tree_name + " node count");
    // Every node takes at least kInnerNodeBytes, so a count the rest of the
    // file cannot hold is refused before allocating for it.
    if (num_nodes == 0) throw Error(path_ + ": forest model " + tree_name + " has no nodes");
    if (num_nodes > r_.remaining() / kInnerNodeBytes)
      throw Error(path_ + ": forest model " + tree_name + " has node count " +
                  std::to_string(num_nodes) + " but only " + std::to_string(r_.remaining()) +
                  " bytes remain (absurd count, or the file is truncated)");
    out.resize(num_nodes);
    for (std::uint32_t i = 0; i < num_nodes; ++i) {
      RandomForest::Node& node = out[i];
      node.feature = r_.i32(tree_name + " node feature");
      if (node.feature >= 0) {
        node.threshold = r_.f32(tree_name + " node threshold");
        node.left = r_.i32(tree_name + " node left");
        node.right = r_.i32(tree_name + " node right");
      } else {
        r_.need(kLeafNodeBytes - 4, tree_name + " leaf distribution");
        for (float& prob : node.distribution) prob = r_.f32(tree_name + " leaf distribution");
      }
    }
  }

  Reader& r_;
  const std::string& path_;
  std::uint32_t version_;
};

}  // namespace

RandomForest RandomForest::load(const std::string& path) {
  const std::vector<std::uint8_t> buf = readModelFile(path);
  const std::uint32_t version = checkMagicAndVersion(buf, path);
  const StoredChecksum checksum = storedChecksum(buf);

  RandomForest forest;
  try {
    Reader r(buf, buf.size(), path);
    SectionReader read(r, path, version);
    read.header();
    read.labelNames();
    const bool boosted = version >= 4 && read.learnerAndClasses(forest.internal_classes_);
    forest.feature_names_ = read.featureNames("");
    if (boosted) {
      read.boosterParams(forest.xgboost_params_, forest.params_.class_weighting);
    } else {
      read.forestParams(forest.params_, "");
    }
    read.extractionSettings(forest.extraction_settings_);
    if (boosted) {
      forest.booster_ =
          read.booster(checksum.matches, forest.internal_classes_.count(), forest.dim());
    } else {
      read.trees(forest.trees_, forest.params_.num_trees, forest.dim(), "");
    }
    if (version >= 3 && read.contextRoundFlag(boosted)) {
      RandomForest round;
      round.feature_names_ = read.featureNames("context round ");
      read.checkContextColumns(forest.feature_names_, round.feature_names_);
      read.forestParams(round.params_, "context round ");
      read.trees(round.trees_, round.params_.num_trees, round.dim(), "context round ");
      round.format_version_ = version;
      forest.context_round_ = std::make_shared<const RandomForest>(std::move(round));
    }
    if (version >= 5) forest.pairwise_context_ = read.pairwiseTerm();
    read.end();
  } catch (const Error& e) {
    if (checksum.matches) throw;
    throw Error(std::string(e.what()) + " [checksum mismatch too: file truncated or corrupt]");
  }
  if (!checksum.matches)
    throw Error(path + ": forest model checksum mismatch (file corrupt; stored " +
                idFromChecksum(checksum.value) + "...)");
  forest.id_ = idFromChecksum(checksum.value);
  forest.source_ = path;
  forest.format_version_ = version;
  return forest;
}

}  // namespace findmug
