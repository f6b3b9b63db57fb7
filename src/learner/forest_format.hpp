// forest_format.hpp — internal to findmug_core (not installed): the binary
// model file of RandomForest (forest_format.cpp writes and reads it), its
// limits, its checksum, and the parameter check shared by training and the
// loader. Tests include it to build files that are intact (valid checksum)
// but wrong in one field, instead of re-stating the checksum.
//
// Model file (all little-endian):
//   char[8]  "FMUGFRST"
//   uint32   format version (kFormatVersion)
//   uint32   label count, then per label: uint32 length + bytes   (kLabelNames)
//   (version 4) uint8 learner (0 forest, 1 xgboost); internal classes: scheme as
//            uint32 length + bytes ("labels", "nyu13", "nyu40"), uint32 class count,
//            per class: name as uint32 length + bytes, uint8 label it merges into
//   uint32   feature count, then per feature: uint32 length + bytes (kFeatureNames,
//            then in version 3 any extra columns: region/context features)
//   params   int32 num_trees, max_depth, min_samples_leaf, candidate_features,
//            candidate_thresholds; uint8 class_weighting; float64 bagging_fraction;
//            uint64 seed   (num_threads is not stored: it is not a property of
//            the model, and a seed must give the same file whatever it is)
//            (version 4, xgboost instead: int32 rounds, max_depth; float64 eta,
//            subsample, colsample, min_child_weight, lambda; int32 seed; uint8
//            class_weighting)
//   uint32   extraction setting count (version 2), then per setting: key, value
//            as uint32 length + bytes (cloud.*, normals.*, oversegmentation.* of training)
//   uint32   tree count; per tree: uint32 node count, then per node:
//            int32 feature; inner (feature >= 0): float32 threshold, int32 left, int32 right;
//            leaf (feature == -1): float32[kNumLabels] distribution
//            (version 4, xgboost instead: uint64 length + the booster's bytes,
//            XGBoost's UBJSON model; its output width must be the class count)
//   uint8    (version 3) 1 when an auto-context round follows, else 0; the round is
//            feature count + names, params, tree count + trees as above
//   uint8    (version 5) 1 when the learned pairwise term of mrf.pairwise = context
//            follows, else 0; the term is float64 bias, weights[4], mean[4], scale[4],
//            mean_cost, then uint64 training edge count (context_pairwise.hpp)
//   uint64   FNV-1a 64 checksum of every byte before it
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "findmug/learner/forest.hpp"

namespace findmug::forest_format {

inline constexpr char kMagic[8] = {'F', 'M', 'U', 'G', 'F', 'R', 'S', 'T'};
inline constexpr std::uint32_t kFormatVersion = 5;
// Format 2: the 14 base features only, no context round. Still read; such a
// model means features.regions = false and features.context = false.
inline constexpr std::uint32_t kOldestFormatVersion = 2;
inline constexpr std::uint32_t kMaxFeatures = 1024;
inline constexpr std::uint32_t kMaxSettings = 256;
inline constexpr int kMaxTrees = 10000;
// Tree size is bounded by the training samples (every leaf holds at least
// one), not by the depth; this limit only refuses absurd values.
inline constexpr int kMaxDepth = 64;
inline constexpr std::uint32_t kMaxNameLength = 256;
inline constexpr std::size_t kChecksumSize = 8;
// Smallest encodings of a node, used to bound counts before allocating.
inline constexpr std::size_t kInnerNodeBytes = 4 + 4 + 4 + 4;
inline constexpr std::size_t kLeafNodeBytes = 4 + 4 * kNumLabels;

// FNV-1a 64 of `size` bytes: the file's trailing checksum.
std::uint64_t fnv1a64(const std::uint8_t* data, std::size_t size);
// Short model id (RandomForest::id) from a checksum: its upper 32 bits in hex.
std::string idFromChecksum(std::uint64_t checksum);
// The model file's bytes, checksum included (format kFormatVersion).
std::vector<std::uint8_t> serialize(const RandomForest& forest);
// Throws findmug::Error naming `where` and the field when a parameter is out
// of range (training input, or parameters read from a model file).
void validateParams(const ForestParams& p, const std::string& where);
// Throws findmug::Error naming `where` and "bad class map" when the internal
// classes are not a loadable class map (scheme, count, names, labels).
void validateInternalClasses(const InternalClasses& classes, const std::string& where);

}  // namespace findmug::forest_format
