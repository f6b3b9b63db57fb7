#include "findmug/offline/training.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "findmug/common/error.hpp"
#include "findmug/labels/label_holes.hpp"
#include "findmug/offline/mrf_context.hpp"

namespace findmug {

std::vector<std::uint8_t> segmentMajorityLabels(const Oversegmentation& segmentation,
                                                const std::vector<std::uint8_t>& gt_labels) {
  if (gt_labels.size() != segmentation.pixel_segment.size()) {
    throw Error("segmentMajorityLabels: label image has " + std::to_string(gt_labels.size()) +
                " pixels, segmentation has " + std::to_string(segmentation.pixel_segment.size()));
  }
  std::vector<std::uint8_t> out(segmentation.segments.size(), kVoidLabel);
  for (std::size_t s = 0; s < segmentation.segments.size(); ++s) {
    std::array<int, kNumLabels> counts{};
    int void_count = 0;
    for (int pixel : segmentation.segments[s]) {
      const std::uint8_t y = gt_labels[pixel];
      if (y < kNumLabels) {
        ++counts[y];
      } else {
        ++void_count;
      }
    }
    const auto best = std::max_element(counts.begin(), counts.end());
    // The plurality label; a patch that is mostly void has no trustworthy label.
    if (*best > 0 && void_count * 2 < static_cast<int>(segmentation.segments[s].size())) {
      out[s] = static_cast<std::uint8_t>(best - counts.begin());
    }
  }
  return out;
}

LabeledFrames framesOf(const DatasetFolder& dataset) {
  return {dataset.dir(), dataset.size(), [&dataset](std::size_t i) { return dataset.load(i); }};
}

LabeledFrames framesOf(const NyuMatFile& mat, const std::string& path) {
  return {path, mat.size(), [&mat](std::size_t i) { return mat.load(i); }};
}

std::uint64_t degradationSeed(std::uint64_t seed, std::size_t frame_index) {
  return seed * 1000003u + frame_index;
}

LabeledFrames degradedFrames(const LabeledFrames& frames, const DepthDegradationConfig& config,
                             std::uint64_t seed) {
  return {frames.description + " (raw-like depth, seed " + std::to_string(seed) + ")",
          frames.count, [frames, config, seed](std::size_t i) {
            LabeledFrame out = frames.load(i);
            out.frame = degradeDepth(out.frame, config, degradationSeed(seed, i));
            return out;
          }};
}

std::vector<FrameSample> extractSamples(const DatasetFolder& dataset, const Segmenter& segmenter,
                                        ExtractionReport& report,
                                        const std::function<void(int, int)>& progress) {
  return extractSamples(framesOf(dataset), segmenter, report, progress);
}

namespace {

// The training weight of a patch of `pixels` pixels in a frame of weight
// `frame_weight` (FrameSample::training_weight).
float patchWeight(SampleWeighting weighting, std::uint32_t pixels, float frame_weight) {
  const auto p = static_cast<float>(pixels);
  switch (weighting) {
    case SampleWeighting::Pixels:
      return p * frame_weight;
    case SampleWeighting::SqrtPixels:
      return std::sqrt(p) * frame_weight;
    case SampleWeighting::Patches:
      break;
  }
  return frame_weight;
}

// Whether a training set from these frames needs per-sample weights: pixel
// weighting, or a frame whose patches weigh other than 1 (pseudo labels).
// Otherwise the weights stay empty (one vote per patch), as they always were.
bool needsWeights(SampleWeighting weighting, const std::vector<const FrameSample*>& frames) {
  if (weighting != SampleWeighting::Patches) return true;
  for (const FrameSample* s : frames)
    if (s->training_weight != 1.0f) return true;
  return false;
}

// Object feature columns per segment of a frame's features (0 without them).
std::size_t objectColumnsOf(const SegmentFeatures& f) {
  return f.features.empty() ? 0 : f.objects.size() / f.features.size();
}

// Names of the first round's extra columns: region, scene, then object
// features (`object_columns` of them: one of the ObjectColumns sets).
std::vector<std::string> extraColumnNames(bool regions, bool scene, std::size_t object_columns) {
  std::vector<std::string> names;
  if (regions) names.assign(kRegionFeatureNames.begin(), kRegionFeatureNames.end());
  if (scene) names.insert(names.end(), kSceneFeatureNames.begin(), kSceneFeatureNames.end());
  if (object_columns > 0) {
    for (const auto name : objectFeatureNames(objectColumnsWithCount(object_columns)))
      names.emplace_back(name);
  }
  return names;
}

// Segment k's extra columns (region, scene, then object features, as present).
void appendExtraColumns(const SegmentFeatures& f, std::size_t k, std::vector<float>& out) {
  if (!f.regions.empty()) {
    const auto begin = f.regions.begin() + static_cast<std::ptrdiff_t>(k * kRegionFeatureDim);
    out.insert(out.end(), begin, begin + kRegionFeatureDim);
  }
  if (!f.scene.empty()) {
    const auto begin = f.scene.begin() + static_cast<std::ptrdiff_t>(k * kSceneFeatureDim);
    out.insert(out.end(), begin, begin + kSceneFeatureDim);
  }
  if (!f.objects.empty()) {
    const std::size_t dim = objectColumnsOf(f);
    const auto begin = f.objects.begin() + static_cast<std::ptrdiff_t>(k * dim);
    out.insert(out.end(), begin, begin + static_cast<std::ptrdiff_t>(dim));
  }
}

// Per segment, the plurality fine class among the pixels whose coarse label
// is the segment's (so that a patch's split label always belongs to its
// label); 0 for void segments. Ties go to the lower id.
std::vector<std::uint8_t> segmentFineLabels(const Oversegmentation& segmentation,
                                            const std::vector<std::uint8_t>& labels,
                                            const std::vector<std::uint8_t>& fine,
                                            const std::vector<std::uint8_t>& segment_labels) {
  if (fine.size() != labels.size())
    throw Error("segmentFineLabels: " + std::to_string(fine.size()) + " fine labels for " +
                std::to_string(labels.size()) + " pixels");
  std::vector<std::uint8_t> out(segmentation.segments.size(), 0);
  std::array<std::uint32_t, kNyu40Classes + 1> votes{};
  for (std::size_t s = 0; s < segmentation.segments.size(); ++s) {
    const std::uint8_t label = segment_labels[s];
    if (label >= kNumLabels) continue;
    votes.fill(0);
    for (const auto p : segmentation.segments[s]) {
      const auto pixel = static_cast<std::size_t>(p);
      if (labels[pixel] == label && fine[pixel] <= kNyu40Classes) ++votes[fine[pixel]];
    }
    // Pixels of the segment's class with fine id 0 would be a data error
    // (labelled coarse, unlabelled fine); they do not vote.
    std::size_t best = 0;
    std::uint32_t best_votes = 0;
    for (std::size_t c = 1; c < votes.size(); ++c) {
      if (votes[c] > best_votes) {
        best = c;
        best_votes = votes[c];
      }
    }
    out[s] = static_cast<std::uint8_t>(best);
  }
  return out;
}

// A frame's sample from one oversegmentation of its prepared geometry.
FrameSample sampleOf(const Segmenter& segmenter, PreparedFrame prepared,
                     const std::vector<std::uint8_t>& labels,
                     const std::vector<std::uint8_t>& fine_labels) {
  const SegmentedFrame segmented = segmenter.oversegment(std::move(prepared));
  FrameSample sample;
  sample.width = segmented.segmentation.width;
  sample.height = segmented.segmentation.height;
  sample.features = segmenter.features(segmented);
  sample.segment_labels = segmentMajorityLabels(segmented.segmentation, labels);
  if (!fine_labels.empty())
    sample.segment_fine_labels =
        segmentFineLabels(segmented.segmentation, labels, fine_labels, sample.segment_labels);
  sample.segment_pixels.reserve(segmented.segmentation.segments.size());
  for (const auto& pixels : segmented.segmentation.segments) {
    sample.segment_pixels.push_back(static_cast<std::uint32_t>(pixels.size()));
  }
  sample.edges = segmented.segmentation.edges;
  sample.pixel_segment = segmented.segmentation.pixel_segment;
  return sample;
}

// Segmenters (no forest) for the training-only oversegmentations: seed
// resolution scaled by s, 1/s, s^2, 1/s^2, ... (training.extra_*).
std::vector<Segmenter> variantSegmenters(const SegmenterConfig& config, const TrainingOptions& t) {
  std::vector<Segmenter> out;
  for (int k = 0; k < t.extra_oversegmentations; ++k) {
    const int power = (k / 2 + 1) * (k % 2 == 0 ? 1 : -1);
    SegmenterConfig variant = config;
    variant.oversegmentation.seed_resolution_m =
        config.oversegmentation.seed_resolution_m *
        std::pow(t.extra_seed_scale, static_cast<float>(power));
    if (variant.oversegmentation.seed_resolution_m <= variant.oversegmentation.voxel_resolution_m) {
      throw Error("training.extra_oversegmentations = " + std::to_string(t.extra_oversegmentations) +
                  " with training.extra_seed_scale = " + std::to_string(t.extra_seed_scale) +
                  " takes oversegmentation.seed_resolution_m down to " +
                  std::to_string(variant.oversegmentation.seed_resolution_m) +
                  ", not above oversegmentation.voxel_resolution_m");
    }
    variant.ground.reestimate_every_frames = 1;
    out.emplace_back(variant, nullptr);
  }
  return out;
}

}  // namespace

std::vector<FrameSample> extractSamples(const LabeledFrames& frames, const Segmenter& segmenter,
                                        ExtractionReport& report,
                                        const std::function<void(int, int)>& progress) {
  return extractTrainingSamples(frames, segmenter, OfflineConfig{}, report, progress);
}

std::vector<FrameSample> extractTrainingSamples(const LabeledFrames& frames,
                                                const Segmenter& segmenter,
                                                const OfflineConfig& offline,
                                                ExtractionReport& report,
                                                const std::function<void(int, int)>& progress) {
  std::vector<FrameSample> samples;
  report = {};
  report.frames_total = static_cast<int>(frames.count);
  const TrainingOptions& training = offline.training;
  const std::vector<Segmenter> variants = variantSegmenters(segmenter.config(), training);
  for (std::size_t i = 0; i < frames.count; ++i) {
    LabeledFrame labelled = frames.load(i);
    // Raw-like copies (training.degraded_copies), each through the whole
    // geometry; a copy whose ground is lost is left out.
    std::vector<FrameSample> degraded;
    for (int k = 0; k < training.degraded_copies; ++k) {
      RgbdFrame copy =
          degradeDepth(labelled.frame, offline.degrade,
                       degradationSeed(training.degraded_seed + static_cast<std::uint64_t>(k), i));
      PreparedFrame prepared_copy = segmenter.prepare(std::move(copy), &labelled.labels);
      if (!prepared_copy.ground) continue;
      degraded.push_back(sampleOf(segmenter, std::move(prepared_copy), labelled.labels,
                                  labelled.fine_labels));
      degraded.back().name = labelled.name + "~raw" + std::to_string(k);
      degraded.back().source_index = i;
    }
    PreparedFrame prepared = segmenter.prepare(std::move(labelled.frame), &labelled.labels);
    if (!prepared.ground) {
      report.dropped.push_back(labelled.name + ": no ground plane found");
    } else {
      const GroundMethod method = prepared.ground->method;
      std::vector<FrameSample> views;
      for (const Segmenter& variant : variants) {
        views.push_back(sampleOf(variant, prepared, labelled.labels, labelled.fine_labels));
        views.back().name = labelled.name;
        views.back().source_index = i;
        views.back().ground_method = method;
      }
      std::vector<std::uint16_t> depth_mm = prepared.frame.depth_mm;
      FrameSample sample =
          sampleOf(segmenter, std::move(prepared), labelled.labels, labelled.fine_labels);
      sample.depth_mm = std::move(depth_mm);
      sample.name = labelled.name;
      sample.source_index = i;
      sample.ground_truth = std::move(labelled.labels);
      sample.ground_method = method;
      sample.variants = std::move(views);
      for (auto& d : degraded) {
        d.ground_method = method;
        sample.variants.push_back(std::move(d));
      }
      report.ground_methods.emplace_back(sample.name, groundMethodName(method));
      samples.push_back(std::move(sample));
      ++report.frames_used;
    }
    if (progress) progress(static_cast<int>(i + 1), report.frames_total);
  }
  return samples;
}

std::string fineLabelsFolder(const SegmenterConfig& config, const TrainingOptions& training) {
  switch (config.learner.classes) {
    case ClassScheme::Nyu13:
      return "label13";
    case ClassScheme::Nyu40:
      return "label40";
    case ClassScheme::Labels:
      break;
  }
  return fineLabelsFolder(training.split_labels);
}

std::string fineLabelsFolder(SplitLabels split) {
  switch (split) {
    case SplitLabels::Labels:
      return "";
    case SplitLabels::Nyu40:
      return "label40";
    case SplitLabels::Nyu13:
      return "label13";
  }
  return "";
}

TrainingSet makeTrainingSet(const std::vector<FrameSample>& samples,
                            const std::vector<std::size_t>& frame_indices,
                            SampleWeighting weighting, SplitLabels split,
                            MissingFineLabels missing) {
  std::vector<const FrameSample*> frames;
  for (std::size_t f : frame_indices) frames.push_back(&samples.at(f));
  return makeTrainingSet(frames, weighting, split, missing);
}

namespace {

// Classes of a split kind: ids 0..n-1 (0 unused: unlabelled).
int splitClasses(SplitLabels split) {
  switch (split) {
    case SplitLabels::Labels:
      return kNumLabels;
    case SplitLabels::Nyu40:
      return kNyu40Classes + 1;
    case SplitLabels::Nyu13:
      return kNyu13Classes + 1;
  }
  return kNumLabels;
}

const char* splitName(SplitLabels split) {
  return split == SplitLabels::Nyu13 ? "NYU-13" : "NYU-40";
}

// The split label of segment k (training.split_labels), or an error naming the frame.
// A frame without fine labels gives kMissingFineLabel when `missing` allows it
// (its patches' fine classes are inferred afterwards: inferMissingFineLabels).
std::uint8_t splitLabelOf(const FrameSample& s, std::size_t k, SplitLabels split,
                          MissingFineLabels missing) {
  const std::string setting = std::string("training.split_labels = ") +
                              (split == SplitLabels::Nyu13 ? "nyu13" : "nyu40");
  if (s.segment_fine_labels.empty() && missing == MissingFineLabels::Infer)
    return kMissingFineLabel;
  if (s.segment_fine_labels.size() != s.segment_labels.size())
    throw Error(setting + ": frame " + s.name + " has no " + splitName(split) +
                " labels (a dataset folder needs " + fineLabelsFolder(split) + "/)");
  const std::uint8_t fine = s.segment_fine_labels[k];
  if (fine == 0 || fine >= splitClasses(split))
    throw Error(setting + ": frame " + s.name + " segment " + std::to_string(k) +
                " is labelled " + std::string(labelName(s.segment_labels[k])) + " but has no " +
                splitName(split) + " class (id " + std::to_string(fine) + ")");
  return fine;
}

// Names of the fine classes (index = id; 0 unlabelled).
constexpr std::array<const char*, kNyu13Classes + 1> kNyu13Names = {
    "unlabelled", "bed", "books", "ceiling", "chair", "floor", "furniture", "objects",
    "picture", "sofa", "table", "tv", "wall", "window"};
constexpr std::array<const char*, kNyu40Classes + 1> kNyu40Names = {
    "unlabelled", "wall", "floor", "cabinet", "bed", "chair", "sofa", "table", "door", "window", "bookshelf", "picture", "counter", "blinds", "desk", "shelves", "curtain", "dresser", "pillow", "mirror", "floor mat", "clothes", "ceiling", "books", "refridgerator", "television", "paper", "towel", "shower curtain", "box", "whiteboard", "person", "night stand", "toilet", "sink", "lamp", "bathtub", "bag", "otherstructure", "otherfurniture", "otherprop"};

// Internal classes (learner.classes): one per (label, fine class) pair of
// the training set, so that each is pure in both: NYU-13 "furniture" becomes
// cabinet/furniture, table/furniture (counters) and unknown/furniture (other
// furniture); NYU-40 ids each fall in one label. Ordered by label, then id.
struct InternalMap {
  InternalClasses classes;
  static constexpr int kKeys = kNumLabels * (kNyu40Classes + 1);
  std::array<int, kKeys> id_of_pair{};  // label * 41 + fine -> internal id, -1 if absent
};

int pairKey(std::uint8_t label, std::uint8_t fine) { return label * (kNyu40Classes + 1) + fine; }

InternalMap internalMapOf(const TrainingSet& set, ClassScheme scheme) {
  std::array<bool, InternalMap::kKeys> present{};
  for (std::size_t i = 0; i < set.labels.size(); ++i)
    present[static_cast<std::size_t>(pairKey(set.labels[i], set.split_labels[i]))] = true;
  InternalMap map;
  map.id_of_pair.fill(-1);
  map.classes.scheme = classSchemeName(scheme);
  map.classes.names.clear();
  map.classes.to_label.clear();
  for (int key = 0; key < InternalMap::kKeys; ++key) {
    if (!present[static_cast<std::size_t>(key)]) continue;
    const int label = key / (kNyu40Classes + 1);
    const int fine = key % (kNyu40Classes + 1);
    map.id_of_pair[static_cast<std::size_t>(key)] = map.classes.count();
    map.classes.names.push_back(std::string(kLabelNames[label]) + "/" +
                                (scheme == ClassScheme::Nyu13 ? kNyu13Names[fine]
                                                              : kNyu40Names[fine]));
    map.classes.to_label.push_back(static_cast<std::uint8_t>(label));
  }
  if (map.classes.count() > kMaxInternalClasses)
    throw Error(std::string("learner.classes = ") + classSchemeName(scheme) + ": " +
                std::to_string(map.classes.count()) + " internal classes exceed the limit of " +
                std::to_string(kMaxInternalClasses));
  return map;
}

// Replaces a set's fine split labels with internal class ids; class weighting
// then balances the internal classes or the labels (learner.class_weight).
void applyInternalMap(TrainingSet& set, const InternalMap& map, ClassWeight weight) {
  for (std::size_t i = 0; i < set.labels.size(); ++i) {
    const int id = map.id_of_pair[static_cast<std::size_t>(pairKey(set.labels[i], set.split_labels[i]))];
    if (id < 0)
      throw Error("learner.classes = " + map.classes.scheme + ": training sample " +
                  std::to_string(i) + " has a class pair absent from the model's classes");
    set.split_labels[i] = static_cast<std::uint8_t>(id);
  }
  set.split_classes = map.classes.count();
  set.weight_by_split_labels = weight == ClassWeight::Classes;
}

SplitLabels fineKindOf(ClassScheme scheme) {
  return scheme == ClassScheme::Nyu13 ? SplitLabels::Nyu13 : SplitLabels::Nyu40;
}

// Column scales for the nearest-neighbour vote: each feature column (base and
// extra) divided by its standard deviation over the set, so that no unit
// (metres, degrees, CIELAB) outweighs the others. Constant columns get 1.
std::vector<float> columnScales(const TrainingSet& set) {
  const std::size_t extra = set.extra_names.size(), dims = kFeatureDim + extra;
  std::vector<double> sum(dims, 0.0), sum2(dims, 0.0);
  for (std::size_t i = 0; i < set.labels.size(); ++i) {
    for (std::size_t d = 0; d < dims; ++d) {
      const double v = d < kFeatureDim ? set.features[i][d] : set.extra[i * extra + d - kFeatureDim];
      sum[d] += v;
      sum2[d] += v * v;
    }
  }
  std::vector<float> scale(dims, 1.0f);
  const auto n = static_cast<double>(set.labels.size());
  for (std::size_t d = 0; d < dims && n > 0; ++d) {
    const double var = sum2[d] / n - (sum[d] / n) * (sum[d] / n);
    if (var > 1e-12) scale[d] = static_cast<float>(1.0 / std::sqrt(var));
  }
  return scale;
}

}  // namespace

void inferMissingFineLabels(TrainingSet& set, int neighbours) {
  if (set.split_labels.size() != set.labels.size()) return;
  std::vector<std::size_t> missing;
  std::array<std::vector<std::size_t>, kNumLabels> known;  // fine-labelled samples per label
  for (std::size_t i = 0; i < set.labels.size(); ++i) {
    if (set.split_labels[i] == kMissingFineLabel)
      missing.push_back(i);
    else
      known[set.labels[i]].push_back(i);
  }
  if (missing.empty()) return;
  const std::size_t extra = set.extra_names.size(), dims = kFeatureDim + extra;
  const std::vector<float> scale = columnScales(set);
  std::vector<float> rows(set.labels.size() * dims);  // every sample's scaled columns
  for (std::size_t i = 0; i < set.labels.size(); ++i)
    for (std::size_t d = 0; d < dims; ++d)
      rows[i * dims + d] =
          (d < kFeatureDim ? set.features[i][d] : set.extra[i * extra + d - kFeatureDim]) * scale[d];
  const auto k = static_cast<std::size_t>(std::max(1, neighbours));
  std::vector<std::pair<float, std::size_t>> nearest;
  for (const std::size_t i : missing) {
    const std::vector<std::size_t>& pool = known[set.labels[i]];
    if (pool.empty())
      throw Error(std::string("finer classes for label '") + std::string(labelName(set.labels[i])) +
                  "': patches labelled with the 8 labels only (a folder without label13/ or "
                  "label40/) need frames with finer labels of the same label to learn from; "
                  "train with the NYU frames beside them, or set learner.classes = labels");
    nearest.clear();
    for (const std::size_t j : pool) {
      float d2 = 0.0f;
      for (std::size_t d = 0; d < dims; ++d) {
        const float diff = rows[i * dims + d] - rows[j * dims + d];
        d2 += diff * diff;
      }
      nearest.emplace_back(d2, j);
    }
    const std::size_t take = std::min(k, nearest.size());
    std::partial_sort(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(take),
                      nearest.end());
    // Majority of the k nearest; a tie goes to the class of the nearer one.
    std::array<int, kMaxSplitClasses> votes{};
    std::uint8_t best = set.split_labels[nearest[0].second];
    for (std::size_t n = 0; n < take; ++n) {
      const std::uint8_t fine = set.split_labels[nearest[n].second];
      if (++votes[fine] > votes[best]) best = fine;
    }
    set.split_labels[i] = best;
  }
}

TrainingSet makeTrainingSet(const std::vector<const FrameSample*>& given,
                            SampleWeighting weighting, SplitLabels split,
                            MissingFineLabels missing) {
  TrainingSet set;
  std::vector<const FrameSample*> frames;
  for (const FrameSample* s : given) {
    frames.push_back(s);
    for (const FrameSample& v : s->variants) frames.push_back(&v);
  }
  const bool regions = !frames.empty() && !frames.front()->features.regions.empty();
  const bool scene = !frames.empty() && !frames.front()->features.scene.empty();
  const std::size_t object_columns = frames.empty() ? 0 : objectColumnsOf(frames.front()->features);
  const bool objects = object_columns > 0;
  set.extra_names = extraColumnNames(regions, scene, object_columns);
  const bool weighted = needsWeights(weighting, frames);
  for (const FrameSample* s : frames) {
    if (s->features.regions.empty() == regions && !s->features.features.empty()) {
      throw Error("makeTrainingSet: frame " + s->name + (regions ? " lacks" : " has") +
                  " region features unlike the first frame");
    }
    if (s->features.scene.empty() == scene && !s->features.features.empty()) {
      throw Error("makeTrainingSet: frame " + s->name + (scene ? " lacks" : " has") +
                  " scene features unlike the first frame");
    }
    if ((s->features.objects.empty() == objects ||
         (objects && objectColumnsOf(s->features) != object_columns)) &&
        !s->features.features.empty()) {
      throw Error("makeTrainingSet: frame " + s->name + (objects ? " lacks" : " has") +
                  " object features, or other object columns, unlike the first frame");
    }
    for (std::size_t k = 0; k < s->segment_labels.size(); ++k) {
      if (s->segment_labels[k] >= kNumLabels) continue;
      set.features.push_back(s->features.features[k]);
      appendExtraColumns(s->features, k, set.extra);
      set.labels.push_back(s->segment_labels[k]);
      if (split != SplitLabels::Labels)
        set.split_labels.push_back(splitLabelOf(*s, k, split, missing));
      if (weighted)
        set.weights.push_back(patchWeight(weighting, s->segment_pixels[k], s->training_weight));
    }
  }
  if (split != SplitLabels::Labels) {
    set.split_classes = splitClasses(split);
    inferMissingFineLabels(set);
  }
  return set;
}

namespace {

std::vector<float> segmentWeights(const FrameSample& sample) {
  return {sample.segment_pixels.begin(), sample.segment_pixels.end()};
}

}  // namespace

std::vector<ClassProbabilities> predictSample(const RandomForest& model, const FrameSample& sample,
                                              const SegmenterConfig& config) {
  return predictSegments(model, sample.features, segmentWeights(sample), config.context);
}

namespace {

// The pairwise term of mrf.pairwise = context, learned from the frames' own
// patches (their training-only views are left out).
PairwiseContext learnedPairwiseTerm(const std::vector<const FrameSample*>& frames) {
  std::vector<LabelledGraph> graphs;
  graphs.reserve(frames.size());
  for (const FrameSample* s : frames)
    graphs.push_back({&s->features.features, &s->edges, &s->segment_labels});
  return learnPairwiseContext(graphs);
}

}  // namespace

RandomForest trainModel(const std::vector<const FrameSample*>& frames,
                        const SegmenterConfig& config, const TrainingOptions& training,
                        const std::function<void(int, int)>& progress) {
  const bool boosted = config.learner.kind == LearnerKind::XGBoost;
  const bool internal = config.learner.classes != ClassScheme::Labels;
  if (boosted && config.context.enabled)
    throw Error("learner.kind = xgboost has no auto-context round; set features.context = false");
  if (internal && training.split_labels != SplitLabels::Labels)
    throw Error(std::string("learner.classes = ") + classSchemeName(config.learner.classes) +
                " cannot be combined with training.split_labels");
  const int folds = config.context.enabled && config.context.cross_fit_folds >= 2
                        ? std::min<int>(config.context.cross_fit_folds,
                                        static_cast<int>(frames.size()))
                        : 0;
  const int total = config.context.enabled ? 2 + (folds >= 2 ? folds : 0) : 1;
  int done = 0;
  auto tick = [&] {
    if (progress) progress(++done, total);
  };
  const SampleWeighting weighting = training.sample_weight;
  const SplitLabels split = internal ? fineKindOf(config.learner.classes) : training.split_labels;
  // Frames labelled with the 8 labels only (a user's own, from the Label page)
  // may join a training with internal classes: their fine classes are inferred.
  const MissingFineLabels missing = internal ? MissingFineLabels::Infer : MissingFineLabels::Refuse;
  TrainingSet first_set = makeTrainingSet(frames, weighting, split, missing);
  InternalMap map;
  if (internal) {
    map = internalMapOf(first_set, config.learner.classes);
    applyInternalMap(first_set, map, config.learner.class_weight);
  }
  auto trainFirst = [&](const TrainingSet& set, const ForestParams& params) {
    if (boosted)
      return RandomForest::trainBoosted(set, internal ? map.classes : labelClasses(),
                                        config.xgboost, params.class_weighting,
                                        params.num_threads);
    RandomForest forest = RandomForest::train(set, params);
    if (internal) forest.setInternalClasses(map.classes);
    return forest;
  };
  RandomForest first = trainFirst(first_set, config.forest);
  if (config.mrf.pairwise == MrfPairwise::Context)
    first.setPairwiseContext(learnedPairwiseTerm(frames));
  tick();
  if (!config.context.enabled) return first;

  // First-round distributions of every training frame, each from a forest
  // that did not see it (folds >= 2), or in-sample.
  const std::size_t n = frames.size();
  std::vector<std::vector<ClassProbabilities>> probs(n);
  SegmenterConfig first_only = config;
  first_only.context.enabled = false;
  if (folds >= 2) {
    for (int g = 0; g < folds; ++g) {
      std::vector<const FrameSample*> train, held_out;
      std::vector<std::size_t> held_index;
      for (std::size_t i = 0; i < n; ++i) {
        if (static_cast<int>(i * folds / n) == g) {
          held_out.push_back(frames[i]);
          held_index.push_back(i);
        } else {
          train.push_back(frames[i]);
        }
      }
      if (held_out.empty()) continue;
      ForestParams params = config.forest;
      params.seed += 1000 + static_cast<std::uint64_t>(g);
      TrainingSet set = makeTrainingSet(train, weighting, split, missing);
      if (set.labels.empty()) throw Error("trainModel: cross-fitting group " + std::to_string(g) +
                                          " leaves no labelled segment to train on");
      if (internal) applyInternalMap(set, map, config.learner.class_weight);
      const RandomForest forest = trainFirst(set, params);
      for (std::size_t k = 0; k < held_out.size(); ++k)
        probs[held_index[k]] = predictSample(forest, *held_out[k], first_only);
      tick();
    }
  } else {
    for (std::size_t i = 0; i < n; ++i) probs[i] = predictSample(first, *frames[i], first_only);
  }

  // Context-round rows: first-round rows, then context columns.
  TrainingSet set;
  if (!frames.empty())
    set.extra_names = extraColumnNames(!frames.front()->features.regions.empty(),
                                       !frames.front()->features.scene.empty(),
                                       objectColumnsOf(frames.front()->features));
  for (const auto& name : contextFeatureNames()) set.extra_names.push_back(name);
  const bool weighted = needsWeights(weighting, frames);
  for (std::size_t i = 0; i < n; ++i) {
    const FrameSample& s = *frames[i];
    const std::vector<float> ctx =
        computeContextFeatures(probs[i], s.features.centroids, segmentWeights(s), config.context);
    for (std::size_t k = 0; k < s.segment_labels.size(); ++k) {
      if (s.segment_labels[k] >= kNumLabels) continue;
      set.features.push_back(s.features.features[k]);
      appendExtraColumns(s.features, k, set.extra);
      const auto begin = ctx.begin() + static_cast<std::ptrdiff_t>(k * kContextFeatureDim);
      set.extra.insert(set.extra.end(), begin, begin + kContextFeatureDim);
      set.labels.push_back(s.segment_labels[k]);
      if (split != SplitLabels::Labels)
        set.split_labels.push_back(splitLabelOf(s, k, split, missing));
      if (weighted)
        set.weights.push_back(patchWeight(weighting, s.segment_pixels[k], s.training_weight));
    }
  }
  if (split != SplitLabels::Labels) {
    set.split_classes = splitClasses(split);
    inferMissingFineLabels(set);
  }
  if (internal) applyInternalMap(set, map, config.learner.class_weight);
  ForestParams params = config.forest;
  params.seed += 500;
  RandomForest second = RandomForest::train(set, params);
  tick();
  first.setContextRound(std::move(second));
  return first;
}

RegionFeatures sampleRegionFeatures(const FrameSample& s, const RegionConfig& config) {
  Oversegmentation segmentation;
  segmentation.width = s.width;
  segmentation.height = s.height;
  segmentation.pixel_segment = s.pixel_segment;
  segmentation.segments.resize(s.features.features.size());
  for (std::size_t i = 0; i < s.pixel_segment.size(); ++i) {
    const int segment = s.pixel_segment[i];
    if (segment < 0) continue;
    if (static_cast<std::size_t>(segment) >= segmentation.segments.size()) {
      throw Error(s.name + ": pixel " + std::to_string(i) + " is in segment " +
                  std::to_string(segment) + " of " + std::to_string(segmentation.segments.size()));
    }
    segmentation.segments[static_cast<std::size_t>(segment)].push_back(static_cast<int>(i));
  }
  segmentation.edges = s.edges;
  return computeRegionFeatures(s.features, segmentation, config);
}

std::vector<std::uint8_t> pixelLabels(const FrameSample& sample,
                                      const std::vector<std::uint8_t>& segment_labels) {
  std::vector<std::uint8_t> out(sample.pixel_segment.size(), kVoidLabel);
  for (std::size_t p = 0; p < out.size(); ++p) {
    const int s = sample.pixel_segment[p];
    if (s >= 0) out[p] = segment_labels.at(static_cast<std::size_t>(s));
  }
  return out;
}

std::vector<std::uint8_t> publishedPixelLabels(const FrameSample& sample,
                                               const std::vector<std::uint8_t>& segment_labels,
                                               const LabelHoleFillConfig& fill) {
  LabelImage image{sample.width, sample.height, pixelLabels(sample, segment_labels), {}};
  if (!fill.enabled) return std::move(image.labels);
  if (sample.depth_mm.size() != image.labels.size()) {
    throw Error("publishedPixelLabels: frame " + sample.name + " has " +
                std::to_string(sample.depth_mm.size()) + " depth pixels for " +
                std::to_string(image.labels.size()) + " pixels");
  }
  image.confidence.assign(image.labels.size(), 0.0f);
  fillLabelHoles(sample.depth_mm, fill, image);
  return std::move(image.labels);
}

const char* nyu40ClassName(int id) {
  if (id < 0 || id > kNyu40Classes)
    throw Error("NYU-40 class id " + std::to_string(id) + " is not in 0.." +
                std::to_string(kNyu40Classes));
  return kNyu40Names[static_cast<std::size_t>(id)];
}

}  // namespace findmug
