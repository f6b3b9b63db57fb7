// findmug/segmenter/segmenter.hpp — the core's steps for one frame, in order.
//
// frame [-> short depth gaps filled, cloud.fill_depth_*] -> cloud + normals
//       -> ground plane -> oversegmentation -> features [-> region features]
//       -> forest p(y|x) [-> context features -> context forest p(y|x)] -> MRF
//       (Potts, or with mrf.pairwise = context the model's learned pairwise
//       term) -> label image -> tables -> objects on the tables' tops
//       (table_objects.*; with table_objects.relabel their table pixels
//       become Object) [-> the label image's depth holes filled,
//       labels.fill_holes]
// The bracketed steps run when the model has them (features.regions,
// features.context); the model file is the source of truth and a config
// that disagrees with it is refused.
//
// Each step is a method taking and returning plain data so that the daemon
// can run them in stages on different threads and tests can check each alone.
// `process` runs them all in sequence. No threads, no LCM.
#pragma once

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/features/features.hpp"
#include "findmug/features/object_features.hpp"
#include "findmug/features/region_features.hpp"
#include "findmug/frame/frame.hpp"
#include "findmug/ground/ground.hpp"
#include "findmug/ground/ground_tracker.hpp"
#include "findmug/labels/label_image.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/mrf/layout_prior.hpp"
#include "findmug/mrf/mrf.hpp"
#include "findmug/objects/table_objects.hpp"
#include "findmug/settings/config.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"
#include "findmug/tables/table_regions.hpp"
#include "findmug/tables/tables.hpp"

namespace findmug {

// Time of each step in milliseconds: wall time in `timings`, the calling
// thread's CPU time in `cpu_timings` (what a step costs on a shared machine,
// where wall time also counts the time other processes ran). In
// `cpu_timings` the context round is part of forest_ms (context_ms stays 0).
// Named for what they become: the timing stages findmugd reports in status_t
// (daemon/pipeline.cpp subStages), one per step or group of steps.
struct StageTimings {
  double cloud_ms = 0, normals_ms = 0, ground_ms = 0, oversegmentation_ms = 0, features_ms = 0,
         regions_ms = 0, forest_ms = 0, context_ms = 0, mrf_ms = 0, labels_ms = 0,
         tables_ms = 0, objects_ms = 0;
  double total() const {
    return cloud_ms + normals_ms + ground_ms + oversegmentation_ms + features_ms + regions_ms +
           forest_ms + context_ms + mrf_ms + labels_ms + tables_ms + objects_ms;
  }
};

// Step 1 (prepare) output: geometry in camera and ground frames.
struct PreparedFrame {
  RgbdFrame frame;
  OrganizedCloud cloud_camera;
  NormalImage normals_camera;
  std::optional<GroundPlane> ground;  // nullopt: no ground plane -> frame cannot be labelled
  OrganizedCloud cloud_ground;        // empty when no ground
  NormalImage normals_ground;
  StageTimings timings;
  StageTimings cpu_timings;
};

// Step 2 (oversegment) output.
struct SegmentedFrame {
  PreparedFrame prepared;
  Oversegmentation segmentation;
  StageTimings timings;
  StageTimings cpu_timings;
};

// Step 3 (classify) output: everything a client needs.
struct LabelledFrame {
  SegmentedFrame segmented;
  SegmentFeatures features;
  // The model's p(y|x) per segment: the context round's when the model has
  // one (the first round's are then in first_round_probabilities).
  std::vector<ClassProbabilities> forest_probabilities;
  std::vector<ClassProbabilities> first_round_probabilities;  // empty without a context round
  std::vector<std::uint8_t> forest_labels;  // argmax of forest_probabilities
  MrfResult mrf;
  LabelImage labels;                        // final (MRF if enabled, else forest)
  std::vector<TableCluster> tables;
  // Why tables were not found or were rejected (for the caller to log).
  std::vector<std::string> table_diagnostics;
  // The object candidates standing on `tables` (table_objects.*), with their
  // diagnostics and counts; empty with table_objects.enabled false.
  TableObjectDetection table_objects;
  StageTimings timings;
  StageTimings cpu_timings;
};

class Segmenter {
 public:
  // `forest` may be null for feature extraction only (training). With a forest,
  // the settings it records replace `config`'s where `config.given` does not
  // hold them, and a given one that differs is refused (configForModel); then
  // checkModelMatchesConfig. config() is the result.
  Segmenter(SegmenterConfig config, std::shared_ptr<const RandomForest> forest);

  // `gt_labels` is only used when config.ground.source == FloorLabels.
  // Each frame on its own: an estimated floor is this frame's estimate.
  PreparedFrame prepare(RgbdFrame frame, const std::vector<std::uint8_t>* gt_labels = nullptr) const;
  // A frame of the stream `ground` follows: with ground.reestimate_every_frames > 1 an
  // estimated floor may be the one an earlier frame of the stream found (GroundTracker).
  // The stream's owner keeps `ground` across frames and models.
  PreparedFrame prepare(RgbdFrame frame, GroundTracker& ground,
                        const std::vector<std::uint8_t>* gt_labels = nullptr) const;
  SegmentedFrame oversegment(PreparedFrame prepared) const;
  // Features only (used by the trainer): the same feature rows classify computes, by the
  // same step (featureRowsInto), so that training and running cannot drift apart.
  SegmentFeatures features(const SegmentedFrame& segmented) const;
  // The steps after the oversegmentation, in order (each a private step below): the feature
  // rows, the learner, the MRF and the table region vote, the label image, the tables, the
  // objects on their tops, the label image's depth holes filled.
  LabelledFrame classify(SegmentedFrame segmented) const;
  // All steps. Throws findmug::Error for invalid frames; a frame without a
  // ground plane comes back with an all-void label image.
  LabelledFrame process(RgbdFrame frame, const std::vector<std::uint8_t>* gt_labels = nullptr) const;
  LabelledFrame process(RgbdFrame frame, GroundTracker& ground,
                        const std::vector<std::uint8_t>* gt_labels = nullptr) const;

  // Hands the buffers of a frame the caller is done with back to the
  // Segmenter: the next prepare(), oversegment() and classify() write into
  // them instead of allocating (clouds, normal images, the segmentation with
  // its per-segment pixel lists, features, distributions, MRF result, label
  // image). Optional: without it every frame allocates fresh buffers; with it
  // a stream of frames of one size allocates next to nothing (BENCHMARKS.md
  // section 2; perf-log §9i). Results are the same either way. Thread-safe; at most
  // kRecycledFrames frames are kept, further ones are freed.
  void recycle(LabelledFrame&& done) const;
  static constexpr std::size_t kRecycledFrames = 2;

  const SegmenterConfig& config() const { return config_; }
  const RandomForest* forest() const { return forest_.get(); }

 private:
  // The pairwise term classify's MRF step uses, chosen once from the config (and so from
  // the model's settings): none (mrf.enabled false), Potts, the model's learned pairwise
  // term (mrf.pairwise = context) or the label-layout prior (mrf.pairwise = layout).
  enum class MrfVariant { None, Potts, LearnedPairwise, LayoutPrior };
  static MrfVariant mrfVariantFor(const SegmenterConfig& config);
  // classify's stopwatch and per-thread working memory (segmenter.cpp).
  class Laps;
  struct ClassifyScratch;

  // The feature-row step, shared by classify and features(): the per-patch features, then
  // contextRowsInto. `laps` (null when training) takes features_ms and regions_ms.
  void featureRowsInto(const SegmentedFrame& segmented, SegmentFeatures& features,
                       RegionFeatures& regions, ObjectFeatures& objects, Laps* laps) const;
  // The output frame: one handed back by recycle() if any, with the timings so far.
  LabelledFrame takeRecycledOutput(const SegmentedFrame& segmented) const;
  // A frame without a ground plane: every pixel void, nothing found.
  void unlabelledFrameInto(const SegmentedFrame& segmented, LabelledFrame& out) const;
  // The learner's distributions and argmax labels per patch (forest_ms, context_ms).
  void learnerInto(const Oversegmentation& segmentation, ClassifyScratch& scratch,
                   LabelledFrame& out, Laps& laps) const;
  // The MRF variant's labels per patch (the learner's with none), their confidence into
  // scratch.confidence.
  const std::vector<std::uint8_t>& mrfLabelsInto(const Oversegmentation& segmentation,
                                                 ClassifyScratch& scratch,
                                                 LabelledFrame& out) const;
  // With tables.region_vote and features.regions, one label per horizontal surface at table
  // height (table_regions.hpp) into `vote`; else `labels` as they are.
  const std::vector<std::uint8_t>& tableRegionVote(const std::vector<std::uint8_t>& labels,
                                                   ClassifyScratch& scratch,
                                                   RegionVoteResult& vote) const;
  // The tables in the label image, and their soft tops (beds, sofas) relabelled.
  void tablesInto(const PreparedFrame& prepared, ClassifyScratch& scratch,
                  LabelledFrame& out) const;
  // The objects standing on the tables' tops, and their pixels relabelled Object.
  void objectsOnTopsInto(const PreparedFrame& prepared, LabelledFrame& out) const;
  // The feature-row step after the per-patch features: the coplanar regions (kept in
  // `regions` for the table region vote), and the region, scene and object columns and
  // object groups the config turns on, into `features`; `objects` is working memory.
  void contextRowsInto(const SegmentedFrame& segmented, SegmentFeatures& features,
                       RegionFeatures& regions, ObjectFeatures& objects) const;
  // prepare with the stream's tracker, or none (every frame its own estimate).
  PreparedFrame prepareWith(RgbdFrame frame, GroundTracker* stream,
                            const std::vector<std::uint8_t>* gt_labels) const;
  // The floor estimated from the frame alone: by `stream` when there is one.
  std::optional<GroundPlane> estimatedGround(const OrganizedCloud& cloud,
                                             const NormalImage& normals,
                                             GroundTracker* stream) const;

  SegmenterConfig config_;
  std::shared_ptr<const RandomForest> forest_;
  std::unique_ptr<Oversegmenter> oversegmenter_;
  MrfVariant mrf_variant_ = MrfVariant::None;
  // mrf.pairwise = layout: the prior file's costs, loaded once.
  std::shared_ptr<const LayoutPrior> layout_prior_;
  // Buffers handed back by recycle(), taken by prepare() and oversegment().
  struct Recycled {
    std::mutex mutex;
    std::vector<PreparedFrame> prepared;         // clouds and normal images
    std::vector<Oversegmentation> segmentations;
    std::vector<LabelledFrame> labelled;  // classify()'s outputs
  };
  std::unique_ptr<Recycled> recycled_ = std::make_unique<Recycled>();
};

// Throws findmug::Error naming the model and every setting whose value
// differs when `forest` was trained with other feature-extraction settings
// than `config` has (features would not mean what the trees learnt), or when
// its columns or rounds are not those the config computes (features.regions,
// features.context; a format-2 model has neither), or when the config has
// mrf.pairwise = context and the model carries no learned pairwise term. A
// model without recorded settings (trained in-process) is only checked for
// its columns, rounds and pairwise term.
void checkModelMatchesConfig(const RandomForest& forest, const SegmenterConfig& config);

// Column names of the first round's rows for `config` (kFeatureNames, then
// kRegionFeatureNames with features.regions, then kSceneFeatureNames with
// features.scene), and of the context round's.
std::vector<std::string> firstRoundFeatureNames(const SegmenterConfig& config);
std::vector<std::string> contextRoundFeatureNames(const SegmenterConfig& config);

// Row-major first-round rows of every segment: base features, then region
// features when `features.regions` is non-empty, then scene features when
// `features.scene` is.
std::vector<float> firstRoundRows(const SegmentFeatures& features);

// The model's per-segment class distributions: the first round, then, when
// the model has a context round, the context round on the first round's rows
// plus context features of the first round's answers. `weights` are the
// segments' sizes (pixel counts). `first_round` (optional) receives the first
// round's distributions.
std::vector<ClassProbabilities> predictSegments(
    const RandomForest& model, const SegmentFeatures& features, const std::vector<float>& weights,
    const ContextConfig& context, std::vector<ClassProbabilities>* first_round = nullptr,
    double* context_ms = nullptr);

}  // namespace findmug
