// findmug/offline/training.hpp — turning a labelled dataset into forest training data.
//
// The expensive part of training and evaluation (cloud, ground plane,
// oversegmentation, features) is done once per frame; cross-validation and
// parameter sweeps then only retrain forests and rerun the MRF.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "findmug/frame/dataset.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/offline/depth_degradation.hpp"
#include "findmug/offline/nyu_mat.hpp"
#include "findmug/segmenter/segmenter.hpp"

namespace findmug {

// One frame reduced to what training and evaluation need.
struct FrameSample {
  std::string name;
  std::size_t source_index = 0;                  // index in the LabeledFrames it came from
  int width = 0, height = 0;
  std::vector<int> pixel_segment;                // from the oversegmentation
  std::vector<std::pair<int, int>> edges;        // adjacency
  SegmentFeatures features;                      // one per segment
  std::vector<std::uint8_t> segment_labels;      // plurality ground truth per segment (255 = void)
  // Per segment, the plurality fine class (NYU-40 or NYU-13) among its pixels
  // of class segment_labels (0 where void); empty when the frame came
  // without fine labels (LabeledFrame::fine_labels).
  std::vector<std::uint8_t> segment_fine_labels;
  std::vector<std::uint32_t> segment_pixels;     // pixel count per segment
  std::vector<std::uint8_t> ground_truth;        // per pixel, 255 = void
  // The frame's depth (0 = none), for the label image's hole filling
  // (labels.fill_holes, label_holes.hpp); empty in training-only views.
  std::vector<std::uint16_t> depth_mm;
  GroundMethod ground_method = GroundMethod::Given;  // how its ground frame was obtained
  // Training weight of each of its patches, times the pixel weighting
  // (training.sample_weight): 1 for labelled frames, training.pseudo_weight
  // for pseudo-labelled ones (pseudo_labels.hpp).
  float training_weight = 1.0f;
  // Training-only views of the same frame through other oversegmentations
  // (training.extra_oversegmentations): their patches join every training
  // set this frame is part of; predictions use this sample's own patches.
  std::vector<FrameSample> variants;
};

// Any indexed collection of labelled frames (a dataset folder, the official
// NYU .mat file, ...), seen through one small interface.
struct LabeledFrames {
  std::string description;  // for messages
  std::size_t count = 0;
  std::function<LabeledFrame(std::size_t)> load;
};
LabeledFrames framesOf(const DatasetFolder& dataset);
LabeledFrames framesOf(const NyuMatFile& mat, const std::string& path);
// The same frames with raw-like depth (degradeDepth; frame i with
// degradationSeed(seed, i)), for evaluation on what a live camera gives.
// `frames` is copied: what its load() refers to must outlive the result.
LabeledFrames degradedFrames(const LabeledFrames& frames, const DepthDegradationConfig& config,
                             std::uint64_t seed);
// The seed frame `frame_index` of a set is degraded with, from a set's seed.
std::uint64_t degradationSeed(std::uint64_t seed, std::size_t frame_index);

struct ExtractionReport {
  int frames_total = 0;
  int frames_used = 0;
  std::vector<std::string> dropped;  // "name: reason" for frames without a ground plane etc.
  // Every used frame with groundMethodName of how its ground was obtained, in order.
  std::vector<std::pair<std::string, std::string>> ground_methods;
};

// Per-segment training labels: the majority ground-truth label of each
// segment's pixels; segments whose pixels are mostly void get kVoidLabel.
std::vector<std::uint8_t> segmentMajorityLabels(const Oversegmentation& segmentation,
                                                const std::vector<std::uint8_t>& gt_labels);

// Runs the Segmenter's geometric steps on every frame. Frames for which no
// ground plane is found are dropped (the paper drops frames with too few floor
// points) and listed in the report. `progress(done, total)` after each frame.
std::vector<FrameSample> extractSamples(const LabeledFrames& frames, const Segmenter& segmenter,
                                        ExtractionReport& report,
                                        const std::function<void(int, int)>& progress = {});
std::vector<FrameSample> extractSamples(const DatasetFolder& dataset, const Segmenter& segmenter,
                                        ExtractionReport& report,
                                        const std::function<void(int, int)>& progress = {});
// The same for training: with offline.training.extra_oversegmentations each sample
// also gets its variants, and with training.degraded_copies raw-like copies
// (degradeDepth with offline.degrade) among them.
std::vector<FrameSample> extractTrainingSamples(const LabeledFrames& frames,
                                                const Segmenter& segmenter,
                                                const OfflineConfig& offline,
                                                ExtractionReport& report,
                                                const std::function<void(int, int)>& progress = {});

// Segments with a non-void label from the given frames and their variants,
// as a training set. Sample weights follow `weighting` (training.sample_weight;
// Patches leaves them empty: one vote per patch); class weighting is the
// forest's job. Region features, when the samples have them, become the
// extra columns. With SplitLabels::Nyu40 / Nyu13 the set carries each patch's
// NYU-40 / NYU-13 class as its split label; a frame without fine labels (or
// with ids beyond the classes) is then an error.
// With MissingFineLabels::Infer a frame without fine labels is accepted and
// its patches' fine classes are inferred (inferMissingFineLabels).
enum class MissingFineLabels { Refuse, Infer };
TrainingSet makeTrainingSet(const std::vector<FrameSample>& samples,
                            const std::vector<std::size_t>& frame_indices,
                            SampleWeighting weighting = SampleWeighting::Patches,
                            SplitLabels split = SplitLabels::Labels,
                            MissingFineLabels missing = MissingFineLabels::Refuse);
TrainingSet makeTrainingSet(const std::vector<const FrameSample*>& frames,
                            SampleWeighting weighting = SampleWeighting::Patches,
                            SplitLabels split = SplitLabels::Labels,
                            MissingFineLabels missing = MissingFineLabels::Refuse);

// The split label a sample gets while its fine class is not known yet.
inline constexpr std::uint8_t kMissingFineLabel = 0;

// Patches of frames labelled with the 8 labels only (a robot owner's frames
// from the Label page, which has no finer classes) in a set whose split
// labels are fine classes: each gets the fine class most of its `neighbours`
// nearest fine-labelled patches of the same label hold (feature columns scaled
// by their spread), so a mixture label (wall: wall, window, picture) is split
// the way the finely labelled frames split it, and no frame is thrown away.
// Samples marked kMissingFineLabel are the ones inferred. Throws
// findmug::Error naming the label when no fine-labelled patch has it.
void inferMissingFineLabels(TrainingSet& set, int neighbours = 5);

// The dataset folder training.split_labels reads ("" for Labels).
std::string fineLabelsFolder(SplitLabels split);
// The dataset folder a config's training reads fine labels from: learner.classes
// (label13/, label40/) or else training.split_labels ("" when neither needs one).
std::string fineLabelsFolder(const SegmenterConfig& config, const TrainingOptions& training);

// Trains the model `config` asks for on the given frames: the first-round
// forest (config.forest) or booster (learner.kind = xgboost, config.xgboost),
// on the 8 labels or on internal classes (learner.classes: (label, NYU class)
// pairs present in the frames, recorded in the model), and with features.context an auto-context
// round trained on first-round distributions that are cross-fitted over
// features.context_cross_fit_folds contiguous groups of the frames (each
// group's distributions come from a forest trained on the other groups), so
// the context round learns from first-round answers as good as those it will
// get on new frames. With mrf.pairwise = context the model also carries the
// pairwise term learned from the frames' labelled neighbours
// (learnPairwiseContext). Extraction settings are not set (the caller does).
// `training` says how patches are weighed and which classes choose the splits
// (training.sample_weight, training.split_labels). `progress(done, total)` counts forests.
RandomForest trainModel(const std::vector<const FrameSample*>& frames,
                        const SegmenterConfig& config, const TrainingOptions& training = {},
                        const std::function<void(int, int)>& progress = {});

// The model's per-segment class distributions for one extracted frame.
std::vector<ClassProbabilities> predictSample(const RandomForest& model, const FrameSample& sample,
                                              const SegmenterConfig& config);

// The regions of a sample's segmentation (region_features.hpp), rebuilt from
// what the sample kept (its segments' moments and its adjacency), for the
// table region vote that follows the MRF. Throws findmug::Error naming the
// frame when a pixel's segment is out of range.
RegionFeatures sampleRegionFeatures(const FrameSample& sample, const RegionConfig& config);

// The NYU-40 class name of `id` (1..40; 0 "unlabelled"); throws findmug::Error beyond.
const char* nyu40ClassName(int id);

// Per-pixel labels of a frame from per-segment labels (255 where no segment).
std::vector<std::uint8_t> pixelLabels(const FrameSample& sample,
                                      const std::vector<std::uint8_t>& segment_labels);
// The same with the pixels without a segment filled as Segmenter::classify
// fills the label image it publishes (labels.fill_holes): what the robot's
// user sees, and what findmug-eval scores.
std::vector<std::uint8_t> publishedPixelLabels(const FrameSample& sample,
                                               const std::vector<std::uint8_t>& segment_labels,
                                               const LabelHoleFillConfig& fill);

}  // namespace findmug
