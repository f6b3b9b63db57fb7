#include "findmug/segmenter/segmenter.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>

#include "findmug/common/error.hpp"
#include "findmug/features/object_features.hpp"
#include "findmug/features/scene_features.hpp"
#include "findmug/frame/depth_holes.hpp"
#include "findmug/labels/label_holes.hpp"
#include "findmug/mrf/context_pairwise.hpp"
#include "findmug/mrf/object_consistency.hpp"
#include "findmug/settings/settings.hpp"
#include "findmug/tables/table_regions.hpp"
#include "common/scratch.hpp"

namespace findmug {

// A named namespace, not an unnamed one: Segmenter::Laps holds a Stopwatch, and a member of a
// class with linkage may not have a type of an unnamed namespace once this file is compiled
// inside a unity batch (FINDMUG_UNITY).
namespace segmenter_detail {

double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()), cpu_start_(threadCpuMs()) {}
  // Milliseconds since construction or the previous lap.
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - start_).count();
    start_ = now;
    return ms;
  }
  // Wall time into `field` of `wall`, this thread's CPU time into the same
  // field of `cpu`, both since construction or the previous lap.
  void lap(StageTimings& wall, StageTimings& cpu, double StageTimings::*field) {
    wall.*field = lap();
    const double now = threadCpuMs();
    cpu.*field = now - cpu_start_;
    cpu_start_ = now;
  }
  // The same, added to what `field` holds (a step done in two parts).
  void addLap(StageTimings& wall, StageTimings& cpu, double StageTimings::*field) {
    const double wall_before = wall.*field, cpu_before = cpu.*field;
    lap(wall, cpu, field);
    wall.*field += wall_before;
    cpu.*field += cpu_before;
  }

 private:
  std::chrono::steady_clock::time_point start_;
  double cpu_start_;
};

}  // namespace segmenter_detail

namespace {

using segmenter_detail::Stopwatch;

std::uint8_t argmax(const ClassProbabilities& p) {
  return static_cast<std::uint8_t>(std::max_element(p.begin(), p.end()) - p.begin());
}

// A label image in which every pixel is void: the answer for a frame that
// cannot be labelled (no ground plane), so that the consumer still gets one
// message per frame.
void voidLabelsInto(int width, int height, LabelImage& image) {
  image.width = width;
  image.height = height;
  image.labels.assign(static_cast<std::size_t>(width) * height, kVoidLabel);
  image.confidence.assign(image.labels.size(), 0.0f);
}

}  // namespace

Segmenter::Segmenter(SegmenterConfig config, std::shared_ptr<const RandomForest> forest)
    : config_(forest ? configForModel(std::move(config), *forest) : std::move(config)),
      forest_(std::move(forest)),
      oversegmenter_(makeOversegmenter(config_.oversegmentation)) {
  if (forest_) checkModelMatchesConfig(*forest_, config_);
  mrf_variant_ = mrfVariantFor(config_);
  if (forest_ && mrf_variant_ == MrfVariant::LayoutPrior)
    layout_prior_ = std::make_shared<const LayoutPrior>(loadLayoutPrior(config_.mrf.layout_prior_path));
}

Segmenter::MrfVariant Segmenter::mrfVariantFor(const SegmenterConfig& config) {
  if (!config.use_mrf) return MrfVariant::None;
  switch (config.mrf.pairwise) {
    case MrfPairwise::Layout:
      return MrfVariant::LayoutPrior;
    case MrfPairwise::Context:
      // checkModelMatchesConfig has refused a model without the learned term.
      return MrfVariant::LearnedPairwise;
    case MrfPairwise::Potts:
      break;
  }
  return MrfVariant::Potts;
}

std::vector<std::string> firstRoundFeatureNames(const SegmenterConfig& config) {
  std::vector<std::string> names(kFeatureNames.begin(), kFeatureNames.end());
  if (config.regions.enabled) names.insert(names.end(), kRegionFeatureNames.begin(), kRegionFeatureNames.end());
  if (config.scene.enabled) names.insert(names.end(), kSceneFeatureNames.begin(), kSceneFeatureNames.end());
  if (config.objects.enabled) {
    for (const auto name : objectFeatureNames(config.objects.columns)) names.emplace_back(name);
  }
  return names;
}

std::vector<std::string> contextRoundFeatureNames(const SegmenterConfig& config) {
  std::vector<std::string> names = firstRoundFeatureNames(config);
  const auto context = contextFeatureNames();
  names.insert(names.end(), context.begin(), context.end());
  return names;
}

namespace {

// firstRoundRows into `rows`, reusing its memory.
void firstRoundRowsInto(const SegmentFeatures& features, std::vector<float>& rows) {
  const std::size_t n = features.features.size();
  const bool regions = !features.regions.empty();
  if (regions && features.regions.size() != n * kRegionFeatureDim) {
    throw Error("firstRoundRows: " + std::to_string(n) + " segments but " +
                std::to_string(features.regions.size()) + " region feature values");
  }
  const bool scene = !features.scene.empty();
  if (scene && features.scene.size() != n * kSceneFeatureDim) {
    throw Error("firstRoundRows: " + std::to_string(n) + " segments but " +
                std::to_string(features.scene.size()) + " scene feature values");
  }
  const bool objects = !features.objects.empty();
  const std::size_t object_dim = objects && n > 0 ? features.objects.size() / n : 0;
  if (objects && (object_dim * n != features.objects.size() ||
                  objectColumnSetWithCount(object_dim) == nullptr)) {
    throw Error("firstRoundRows: " + std::to_string(n) + " segments but " +
                std::to_string(features.objects.size()) + " object feature values");
  }
  const std::size_t region_dim = regions ? kRegionFeatureDim : 0;
  const std::size_t scene_dim = scene ? kSceneFeatureDim : 0;
  const std::size_t dim = kFeatureDim + region_dim + scene_dim + object_dim;
  rows.resize(n * dim);
  for (std::size_t i = 0; i < n; ++i) {
    float* row = rows.data() + i * dim;
    std::copy(features.features[i].begin(), features.features[i].end(), row);
    if (regions) {
      std::copy_n(features.regions.begin() + static_cast<std::ptrdiff_t>(i * kRegionFeatureDim),
                  kRegionFeatureDim, row + kFeatureDim);
    }
    if (scene) {
      std::copy_n(features.scene.begin() + static_cast<std::ptrdiff_t>(i * kSceneFeatureDim),
                  kSceneFeatureDim, row + kFeatureDim + region_dim);
    }
    if (objects) {
      std::copy_n(features.objects.begin() + static_cast<std::ptrdiff_t>(i * object_dim),
                  object_dim, row + kFeatureDim + region_dim + scene_dim);
    }
  }
}

// predictSegments into `out` and `first_round` (emptied without a context
// round), reusing their memory; the rows are per-thread scratch.
void predictSegmentsInto(const RandomForest& model, const SegmentFeatures& features,
                         const std::vector<float>& weights, const ContextConfig& context,
                         std::vector<ClassProbabilities>& out,
                         std::vector<ClassProbabilities>& first_round, double* context_ms) {
  const std::size_t n = features.features.size();
  thread_local std::vector<float> rows_tls, row_tls;
  detail::Borrowed rows_buffer(rows_tls), row_buffer(row_tls);
  std::vector<float>& rows = *rows_buffer;
  firstRoundRowsInto(features, rows);
  const auto dim = static_cast<std::size_t>(model.dim());
  if (rows.size() != n * dim) {
    throw Error("predictSegments: the model reads " + std::to_string(dim) +
                " columns per segment, the features give " +
                std::to_string(n == 0 ? 0 : rows.size() / n) +
                " (features.regions, features.scene or features.objects differs from the "
                "model's)");
  }
  const RandomForest* round = model.contextRound();
  // Without a context round the first round's answers are the output.
  std::vector<ClassProbabilities>& probs = round ? first_round : out;
  probs.resize(n);
  model.predictRows(rows, n, probs);
  if (!round) {
    first_round.clear();
    return;
  }

  Stopwatch watch;
  const std::vector<float> ctx = computeContextFeatures(probs, features.centroids, weights, context);
  const std::size_t dim2 = dim + kContextFeatureDim;
  if (static_cast<std::size_t>(round->dim()) != dim2) {
    throw Error("predictSegments: the context round reads " + std::to_string(round->dim()) +
                " columns, expected " + std::to_string(dim2));
  }
  std::vector<float>& row = *row_buffer;
  row.resize(dim2);
  out.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::copy_n(rows.begin() + static_cast<std::ptrdiff_t>(i * dim), dim, row.begin());
    std::copy_n(ctx.begin() + static_cast<std::ptrdiff_t>(i * kContextFeatureDim),
                kContextFeatureDim, row.begin() + static_cast<std::ptrdiff_t>(dim));
    out[i] = round->predict(row);
  }
  if (context_ms) *context_ms = watch.lap();
}

}  // namespace

std::vector<float> firstRoundRows(const SegmentFeatures& features) {
  std::vector<float> rows;
  firstRoundRowsInto(features, rows);
  return rows;
}

std::vector<ClassProbabilities> predictSegments(const RandomForest& model,
                                                const SegmentFeatures& features,
                                                const std::vector<float>& weights,
                                                const ContextConfig& context,
                                                std::vector<ClassProbabilities>* first_round,
                                                double* context_ms) {
  std::vector<ClassProbabilities> out, first;
  predictSegmentsInto(model, features, weights, context, out, first, context_ms);
  if (first_round) *first_round = std::move(first);
  return out;
}

void checkModelMatchesConfig(const RandomForest& forest, const SegmenterConfig& config) {
  const std::string name = forest.source().empty() ? "forest " + forest.id()
                                                    : forest.source() + " (" + forest.id() + ")";
  // The learner and its classes: a model answers only what it was trained as.
  if (forest.learnerKind() != config.learner.kind) {
    throw Error("model " + name + " is a " + learnerKindName(forest.learnerKind()) +
                " model but the config has learner.kind = " +
                learnerKindName(config.learner.kind) + "; set learner.kind = " +
                learnerKindName(forest.learnerKind()) + " or retrain");
  }
  if (forest.internalClasses().scheme != classSchemeName(config.learner.classes)) {
    throw Error("model " + name + " was trained on internal classes '" +
                forest.internalClasses().scheme + "' (" +
                std::to_string(forest.internalClasses().count()) +
                " classes) but the config has learner.classes = " +
                classSchemeName(config.learner.classes) + "; set learner.classes = " +
                forest.internalClasses().scheme + " or retrain");
  }
  // Columns and rounds first: they say in one line what is wrong.
  const auto expected = firstRoundFeatureNames(config);
  if (forest.featureNames() != expected) {
    // Which column groups the model reads, by their names (its width alone cannot say once
    // scene and object columns come after the region ones).
    const auto& names = forest.featureNames();
    const bool model_regions =
        std::find(names.begin(), names.end(), std::string(kRegionFeatureNames[0])) != names.end();
    const bool model_scene =
        std::find(names.begin(), names.end(), std::string(kSceneFeatureNames[0])) != names.end();
    const auto model_object_columns = std::count_if(names.begin(), names.end(), [](const std::string& n) {
      return std::find(kObjectFeatureNames.begin(), kObjectFeatureNames.end(), n) !=
             kObjectFeatureNames.end();
    });
    const bool model_objects = model_object_columns > 0;
    throw Error("model " + name + " reads " + std::to_string(forest.dim()) +
                " feature columns" + (model_regions ? " (with region features)" : "") +
                (model_scene ? " (with scene features)" : "") +
                (model_objects ? " (with object features)" : "") +
                " but the config computes " + std::to_string(expected.size()) +
                " (features.regions = " + (config.regions.enabled ? "true" : "false") +
                ", features.scene = " + (config.scene.enabled ? "true" : "false") +
                ", features.objects = " + (config.objects.enabled ? "true" : "false") +
                (config.objects.enabled
                     ? ", features.objects_columns = " +
                           std::string(objectColumnSet(config.objects.columns).name) + " (" +
                           std::to_string(objectColumnSet(config.objects.columns).indices.size()) +
                           " object columns; the model has " + std::to_string(model_object_columns) +
                           ")"
                     : std::string()) +
                "); set features.regions, features.scene, features.objects and "
                "features.objects_columns to match the model or retrain" +
                (forest.formatVersion() == 2 ? " (a format-2 model has no region features)" : ""));
  }
  // The learned pairwise term travels with the model (context_pairwise.hpp).
  if (config.use_mrf && config.mrf.pairwise == MrfPairwise::Context && !forest.pairwiseContext()) {
    throw Error("model " + name + " carries no learned pairwise term but the config has "
                "mrf.pairwise = context; set mrf.pairwise = potts or retrain with mrf.pairwise = "
                "context" +
                (forest.formatVersion() != 0 && forest.formatVersion() < 5
                     ? " (a format-" + std::to_string(forest.formatVersion()) +
                           " model has no pairwise term)"
                     : std::string()));
  }
  if (config.context.enabled != (forest.contextRound() != nullptr)) {
    throw Error("model " + name + (forest.contextRound() ? " has" : " has no") +
                " auto-context round but the config has features.context = " +
                (config.context.enabled ? "true" : "false") +
                "; set it to match the model or retrain" +
                (forest.formatVersion() == 2 ? " (a format-2 model has no context round)" : ""));
  }
  if (forest.contextRound() &&
      forest.contextRound()->featureNames() != contextRoundFeatureNames(config)) {
    throw Error("model " + name +
                ": the context round's columns are not those this build computes");
  }
  const auto& trained = forest.extractionSettings();
  if (trained.empty()) return;
  const auto current = extractionSettings(config);
  std::string differences;
  for (const auto& [trained_key, value] : trained) {
    // A model keeps the key names it was trained with (overseg.* before the rename).
    const std::string key = currentSettingKey(trained_key);
    const auto it = std::find_if(current.begin(), current.end(),
                                 [&name = key](const auto& kv) { return kv.first == name; });
    if (it == current.end()) {
      differences += "\n  " + key + ": trained with " + value + ", unknown to this build";
    } else if (it->second != value) {
      differences += "\n  " + key + ": trained with " + value + ", config has " + it->second;
    }
  }
  if (!differences.empty()) {
    throw Error("model " + name +
                " was trained with other feature-extraction settings than the config; "
                "set them back or retrain:" + differences);
  }
}

void Segmenter::recycle(LabelledFrame&& done) const {
  PreparedFrame& prepared = done.segmented.prepared;
  prepared.frame = RgbdFrame{};  // the frame's own buffers are the caller's
  std::lock_guard lock(recycled_->mutex);
  if (recycled_->prepared.size() < kRecycledFrames) {
    recycled_->prepared.push_back(std::move(prepared));
  }
  // A frame without a ground plane has no segments: nothing worth keeping.
  if (!done.segmented.segmentation.segments.empty() &&
      recycled_->segmentations.size() < kRecycledFrames) {
    recycled_->segmentations.push_back(std::move(done.segmented.segmentation));
  }
  // The rest: the classify step's outputs (features, distributions, MRF,
  // label image, tables: detectTablesInto reuses the tables' pixel lists).
  if (recycled_->labelled.size() < kRecycledFrames) {
    done.segmented = SegmentedFrame{};
    recycled_->labelled.push_back(std::move(done));
  }
}

PreparedFrame Segmenter::prepare(RgbdFrame frame, const std::vector<std::uint8_t>* gt_labels) const {
  return prepareWith(std::move(frame), nullptr, gt_labels);
}

PreparedFrame Segmenter::prepare(RgbdFrame frame, GroundTracker& ground,
                                 const std::vector<std::uint8_t>* gt_labels) const {
  return prepareWith(std::move(frame), &ground, gt_labels);
}

PreparedFrame Segmenter::prepareWith(RgbdFrame frame, GroundTracker* stream,
                                     const std::vector<std::uint8_t>* gt_labels) const {
  PreparedFrame out;
  {
    std::lock_guard lock(recycled_->mutex);
    if (!recycled_->prepared.empty()) {
      out = std::move(recycled_->prepared.back());
      recycled_->prepared.pop_back();
      out.ground.reset();
      out.timings = {};
      out.cpu_timings = {};
    }
  }
  Stopwatch watch;
  // The cloud step's time counts the fill.
  fillDepthHoles(frame.depth_mm, frame.width, frame.height, config_.depth_holes);
  frameToCloud(frame, config_.max_depth_m, out.cloud_camera);
  watch.lap(out.timings, out.cpu_timings, &StageTimings::cloud_ms);
  computeNormals(out.cloud_camera, config_.normals, out.normals_camera);
  watch.lap(out.timings, out.cpu_timings, &StageTimings::normals_ms);

  switch (config_.ground.source) {
    case GroundSource::Auto:
      out.ground = frame.extrinsics ? std::optional(groundFromExtrinsics(*frame.extrinsics))
                                    : estimatedGround(out.cloud_camera, out.normals_camera, stream);
      break;
    case GroundSource::Extrinsics:
      if (!frame.extrinsics) {
        throw Error(frame.source + ": ground.source is 'extrinsics' but the frame carries none "
                                   "(set ground.source to auto or estimated)");
      }
      out.ground = groundFromExtrinsics(*frame.extrinsics);
      break;
    case GroundSource::FloorLabels:
      if (gt_labels == nullptr) {
        throw Error(frame.source + ": ground.source is 'floor_labels' but no ground truth was given");
      }
      if (gt_labels->size() != out.cloud_camera.size()) {
        throw Error(frame.source + ": ground-truth labels have " +
                    std::to_string(gt_labels->size()) + " pixels, frame has " +
                    std::to_string(out.cloud_camera.size()));
      }
      out.ground = fitGroundToLabels(out.cloud_camera, *gt_labels, config_.ground);
      break;
    case GroundSource::Estimated:
      out.ground = estimatedGround(out.cloud_camera, out.normals_camera, stream);
      break;
    case GroundSource::Gravity:
      // A robot knows its mount; a dataset frame brings its gravity; a frame
      // with neither falls back to the labelled floor, then to the frame alone.
      if (frame.extrinsics) {
        out.ground = groundFromExtrinsics(*frame.extrinsics);
      } else if (frame.gravity_up) {
        const auto& g = *frame.gravity_up;
        const Eigen::Vector3f up(static_cast<float>(g[0]), static_cast<float>(g[1]),
                                 static_cast<float>(g[2]));
        if (gt_labels && gt_labels->size() != out.cloud_camera.size()) {
          throw Error(frame.source + ": ground-truth labels have " +
                      std::to_string(gt_labels->size()) + " pixels, frame has " +
                      std::to_string(out.cloud_camera.size()));
        }
        out.ground =
            groundFromGravity(out.cloud_camera, out.normals_camera, up, gt_labels, config_.ground);
      } else {
        if (gt_labels && gt_labels->size() == out.cloud_camera.size()) {
          out.ground = fitGroundToLabels(out.cloud_camera, *gt_labels, config_.ground);
        }
        if (!out.ground) {
          out.ground = estimateGround(out.cloud_camera, out.normals_camera, config_.ground);
        }
      }
      break;
  }
  if (out.ground) {
    transformCloud(out.cloud_camera, out.ground->camera_to_ground, out.cloud_ground);
    rotateNormals(out.normals_camera, out.ground->camera_to_ground.linear(), out.normals_ground);
  } else {
    // Empty without a ground plane (a recycled frame's buffers are kept).
    out.cloud_ground.width = out.cloud_ground.height = 0;
    out.cloud_ground.points.clear();
    out.cloud_ground.colors.clear();
    out.normals_ground.width = out.normals_ground.height = 0;
    out.normals_ground.normals.clear();
  }
  watch.lap(out.timings, out.cpu_timings, &StageTimings::ground_ms);
  out.frame = std::move(frame);
  return out;
}

std::optional<GroundPlane> Segmenter::estimatedGround(const OrganizedCloud& cloud,
                                                      const NormalImage& normals,
                                                      GroundTracker* stream) const {
  if (stream) return stream->groundOf(cloud, normals, config_.ground);
  return estimateGround(cloud, normals, config_.ground);
}

SegmentedFrame Segmenter::oversegment(PreparedFrame prepared) const {
  SegmentedFrame out;
  out.timings = prepared.timings;
  out.cpu_timings = prepared.cpu_timings;
  if (prepared.ground) {
    std::lock_guard lock(recycled_->mutex);
    if (!recycled_->segmentations.empty()) {
      out.segmentation = std::move(recycled_->segmentations.back());
      recycled_->segmentations.pop_back();
    }
  }
  Stopwatch watch;
  if (prepared.ground) {
    oversegmenter_->segmentInto(prepared.cloud_camera, prepared.normals_camera, out.segmentation);
  } else {
    // Without a ground plane no feature can be computed: skip the work.
    out.segmentation.width = prepared.cloud_camera.width;
    out.segmentation.height = prepared.cloud_camera.height;
    out.segmentation.pixel_segment.assign(prepared.cloud_camera.size(), -1);
  }
  watch.lap(out.timings, out.cpu_timings, &StageTimings::oversegmentation_ms);
  out.prepared = std::move(prepared);
  return out;
}

void Segmenter::contextRowsInto(const SegmentedFrame& segmented, SegmentFeatures& features,
                                RegionFeatures& regions, ObjectFeatures& objects) const {
  if (config_.regions.enabled || config_.objects.enabled)
    computeRegionFeaturesInto(features, segmented.segmentation, config_.regions, regions);
  if (config_.regions.enabled) features.regions = regions.values;
  if (config_.scene.enabled) {
    std::vector<float> scene = std::move(features.scene);
    computeSceneFeaturesInto(segmented.prepared.cloud_ground, segmented.segmentation, features,
                             segmented.prepared.ground->camera_to_ground.translation(),
                             config_.scene, scene);
    features.scene = std::move(scene);
  }
  if (config_.objects.enabled) {
    computeObjectFeaturesInto(features, segmented.segmentation, regions, config_.objects, objects);
    features.objects = objects.values;
    objectCandidatesInto(objects, features.object_group);
  } else {
    features.objects.clear();
    features.object_group.clear();
  }
}

// The stopwatch of one classify call and the frame's timings its laps go into.
class Segmenter::Laps {
 public:
  explicit Laps(LabelledFrame& frame) : frame_(frame) {}
  void lap(double StageTimings::*field) { watch_.lap(frame_.timings, frame_.cpu_timings, field); }
  void addLap(double StageTimings::*field) {
    watch_.addLap(frame_.timings, frame_.cpu_timings, field);
  }

 private:
  LabelledFrame& frame_;
  segmenter_detail::Stopwatch watch_;
};

// classify's per-thread working memory (scratch.hpp), borrowed for one call.
struct Segmenter::ClassifyScratch {
  RegionFeatures regions;  // kept from the feature rows for the table region vote
  ObjectFeatures objects;
  std::vector<float> weights;     // each patch's pixel count
  std::vector<float> confidence;  // of the labels the MRF step settles on
  // The learner's distributions with the decision's bias towards tables.
  std::vector<ClassProbabilities> weighted;
  ObjectMeanScratch object_means;  // mrf.object_consistency
  std::vector<float> heights;      // mrf.pairwise = layout
  MrfPairFactors factors;
  std::vector<float> edge_scales;    // mrf.pairwise = context
  std::vector<int> soft_top_pixels;  // the table-top test's rejected clusters
};

void Segmenter::featureRowsInto(const SegmentedFrame& segmented, SegmentFeatures& features,
                                RegionFeatures& regions, ObjectFeatures& objects,
                                Laps* laps) const {
  computeFeaturesInto(segmented.prepared.cloud_ground, segmented.prepared.normals_ground,
                      segmented.segmentation, features);
  if (laps) laps->lap(&StageTimings::features_ms);
  contextRowsInto(segmented, features, regions, objects);
  // Region, scene and object features share this step's time.
  if (laps) laps->lap(&StageTimings::regions_ms);
}

SegmentFeatures Segmenter::features(const SegmentedFrame& segmented) const {
  if (!segmented.prepared.ground) return {};
  SegmentFeatures out;
  RegionFeatures regions;
  ObjectFeatures objects;
  featureRowsInto(segmented, out, regions, objects, nullptr);
  return out;
}

LabelledFrame Segmenter::takeRecycledOutput(const SegmentedFrame& segmented) const {
  LabelledFrame out;
  {
    std::lock_guard lock(recycled_->mutex);
    if (!recycled_->labelled.empty()) {
      out = std::move(recycled_->labelled.back());
      recycled_->labelled.pop_back();
    }
  }
  out.timings = segmented.timings;
  out.cpu_timings = segmented.cpu_timings;
  return out;
}

void Segmenter::unlabelledFrameInto(const SegmentedFrame& segmented, LabelledFrame& out) const {
  // Emptied, not replaced: a recycled frame's vectors keep their capacity
  // for the frames after this one (a stream with frames lacking a ground
  // plane otherwise reallocated them all on the next frame with one).
  // (A new member of either struct must be emptied here too.)
  static_assert(sizeof(SegmentFeatures) == 7 * sizeof(std::vector<float>));
  static_assert(sizeof(MrfResult) == 2 * sizeof(std::vector<float>) + sizeof(std::int64_t));
  out.features.features.clear();
  out.features.centroids.clear();
  out.features.moments.clear();
  out.features.regions.clear();
  out.features.scene.clear();
  out.features.objects.clear();
  out.features.object_group.clear();
  out.forest_probabilities.clear();
  out.first_round_probabilities.clear();
  out.forest_labels.clear();
  out.mrf.labels.clear();
  out.mrf.confidence.clear();
  out.mrf.iterations = 0;
  out.mrf.converged = false;
  voidLabelsInto(segmented.prepared.cloud_camera.width, segmented.prepared.cloud_camera.height,
                 out.labels);
  out.tables.clear();  // a recycled frame's
  out.table_diagnostics.clear();
  findTableObjectsInto({}, out.labels, out.tables, config_.table_objects, out.table_objects);
}

void Segmenter::learnerInto(const Oversegmentation& segmentation, ClassifyScratch& scratch,
                            LabelledFrame& out, Laps& laps) const {
  const std::size_t n = out.features.features.size();
  std::vector<float>& weights = scratch.weights;
  weights.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    weights[i] = static_cast<float>(segmentation.segments[i].size());
  double context_ms = 0;
  predictSegmentsInto(*forest_, out.features, weights, config_.context, out.forest_probabilities,
                      out.first_round_probabilities, &context_ms);
  out.forest_labels.resize(n);
  for (std::size_t i = 0; i < n; ++i) out.forest_labels[i] = argmax(out.forest_probabilities[i]);
  // The context round's time is measured inside and reported on its own.
  out.timings.context_ms = context_ms;
  laps.lap(&StageTimings::forest_ms);
  out.timings.forest_ms -= context_ms;  // CPU time: the context round stays in forest_ms
}

const std::vector<std::uint8_t>& Segmenter::mrfLabelsInto(const Oversegmentation& segmentation,
                                                         ClassifyScratch& scratch,
                                                         LabelledFrame& out) const {
  const std::size_t n = out.features.features.size();
  std::vector<ClassProbabilities>& weighted = scratch.weighted;
  weighted = out.forest_probabilities;
  if (mrf_variant_ != MrfVariant::None)
    mixObjectMeansInPlace(weighted, out.features.object_group, scratch.weights,
                          config_.mrf.object_consistency, scratch.object_means);
  weightTableProbabilityInPlace(weighted, config_.tables.table_weight);
  switch (mrf_variant_) {
    case MrfVariant::LayoutPrior: {
      const float threshold = layoutHeightsInto(
          config_.mrf, {&segmentation.pixel_segment, segmentation.width, &out.features.features},
          scratch.heights);
      layoutPairFactorsInto(*layout_prior_, config_.mrf.layout_weight, threshold,
                            scratch.heights, segmentation.edges, scratch.factors);
      solveMrfWithFactorsInto(weighted, out.features.centroids, segmentation.edges,
                              scratch.factors, config_.mrf, out.mrf);
      break;
    }
    case MrfVariant::LearnedPairwise:
      pairwiseContextScalesInto(*forest_->pairwiseContext(), out.features.features,
                                segmentation.edges, scratch.edge_scales);
      solveMrfScaledInto(weighted, out.features.centroids, segmentation.edges,
                         scratch.edge_scales, config_.mrf, out.mrf);
      break;
    case MrfVariant::Potts:
      solveMrfInto(weighted, out.features.centroids, segmentation.edges, config_.mrf, out.mrf);
      break;
    case MrfVariant::None:
      out.mrf = MrfResult{};
      scratch.confidence.resize(n);
      for (std::size_t i = 0; i < n; ++i)
        scratch.confidence[i] = out.forest_probabilities[i][out.forest_labels[i]];
      return out.forest_labels;
  }
  scratch.confidence = out.mrf.confidence;
  return out.mrf.labels;
}

const std::vector<std::uint8_t>& Segmenter::tableRegionVote(
    const std::vector<std::uint8_t>& labels, ClassifyScratch& scratch,
    RegionVoteResult& vote) const {
  if (!config_.tables.region_vote || !config_.regions.enabled) return labels;
  vote = voteTableRegions(labels, scratch.confidence, scratch.weighted, scratch.weights,
                          scratch.regions, config_.tables);
  scratch.confidence = std::move(vote.confidence);
  return vote.labels;
}

void Segmenter::tablesInto(const PreparedFrame& prepared, ClassifyScratch& scratch,
                           LabelledFrame& out) const {
  // A recycled frame's tables lend their buffers to this frame's.
  TableDetection detection;
  detection.tables = std::move(out.tables);
  detection.diagnostics = std::move(out.table_diagnostics);
  detection.soft_top_pixels = std::move(scratch.soft_top_pixels);
  detectTablesInto(prepared.cloud_ground, out.labels, config_.tables, &prepared.normals_ground,
                   detection);
  // A bed or sofa is not a table (the table-top test): its pixels Unknown.
  if (config_.tables.relabel_soft_tops) relabelSoftTops(detection, out.labels);
  scratch.soft_top_pixels = std::move(detection.soft_top_pixels);
  out.tables = std::move(detection.tables);
  out.table_diagnostics = std::move(detection.diagnostics);
}

void Segmenter::objectsOnTopsInto(const PreparedFrame& prepared, LabelledFrame& out) const {
  // Their pixel lists reuse a recycled frame's.
  findTableObjectsInto(prepared.cloud_ground, out.labels, out.tables, config_.table_objects,
                       out.table_objects);
  // Before the hole filling, which then spreads Object into the gaps beside them.
  if (config_.table_objects.relabel) relabelTableObjects(out.table_objects.objects, out.labels);
}

LabelledFrame Segmenter::classify(SegmentedFrame segmented) const {
  if (!forest_ || forest_->empty()) {
    throw Error("Segmenter::classify: no trained forest loaded");
  }
  // The outputs go into the vectors of a frame handed back by recycle(), if any.
  LabelledFrame out = takeRecycledOutput(segmented);
  if (!segmented.prepared.ground) {
    unlabelledFrameInto(segmented, out);
    out.segmented = std::move(segmented);
    return out;
  }
  thread_local ClassifyScratch scratch_of_thread;
  detail::Borrowed scratch(scratch_of_thread);
  const Oversegmentation& segmentation = segmented.segmentation;
  const PreparedFrame& prepared = segmented.prepared;

  Laps laps(out);
  featureRowsInto(segmented, out.features, scratch->regions, scratch->objects, &laps);
  learnerInto(segmentation, *scratch, out, laps);
  RegionVoteResult vote;  // One label per horizontal surface at table height.
  const std::vector<std::uint8_t>& labels =
      tableRegionVote(mrfLabelsInto(segmentation, *scratch, out), *scratch, vote);
  laps.lap(&StageTimings::mrf_ms);
  projectLabelsInto(segmentation, labels, scratch->confidence, out.labels);
  laps.lap(&StageTimings::labels_ms);
  tablesInto(prepared, *scratch, out);
  laps.lap(&StageTimings::tables_ms);
  objectsOnTopsInto(prepared, out);
  laps.lap(&StageTimings::objects_ms);
  // After the tables: the filled pixels have no point, and the table step
  // counts the table pixels without one as a diagnostic.
  fillLabelHoles(prepared.frame.depth_mm, config_.label_holes, out.labels);
  laps.addLap(&StageTimings::labels_ms);
  out.segmented = std::move(segmented);
  return out;
}

LabelledFrame Segmenter::process(RgbdFrame frame, const std::vector<std::uint8_t>* gt_labels) const {
  return classify(oversegment(prepare(std::move(frame), gt_labels)));
}

LabelledFrame Segmenter::process(RgbdFrame frame, GroundTracker& ground,
                                 const std::vector<std::uint8_t>* gt_labels) const {
  return classify(oversegment(prepare(std::move(frame), ground, gt_labels)));
}

}  // namespace findmug
