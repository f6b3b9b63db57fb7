// findmug-eval's cross-validation: the frames split into folds, a forest trained on each
// fold's training frames and its test frames labelled with it (forest alone and forest +
// MRF), and the sweeps over trees and depth that repeat it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "eval_report.hpp"
#include "findmug/features/region_features.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/mrf/mrf.hpp"
#include "findmug/offline/metrics.hpp"
#include "findmug/offline/pseudo_labels.hpp"
#include "findmug/offline/training.hpp"
#include "findmug/settings/config.hpp"

namespace findmug::tools {

// What labelling the evaluated frames gave: the confusions of the forest alone and with the
// MRF, and per frame what the table measures and the pictures need.
struct Evaluation {
  ConfusionMatrix forest, mrf;
  std::vector<std::vector<std::uint8_t>> mrf_pixels;  // per frame, for overlays
  // Per frame and segment (kept with mrf_pixels): the model's p(y|x) and the
  // MRF's labels and confidence, for the table stage and its diagnosis.
  std::vector<std::vector<ClassProbabilities>> probabilities;
  std::vector<MrfResult> mrf_results;
  // Cross-validation only: each fold's training and test samples.
  struct Fold {
    int fold = 0;
    std::vector<std::size_t> train, test;
    PseudoLabelReport pseudo;  // semi-supervised rounds (--unlabelled)
  };
  std::vector<Fold> folds;
};

// How the frames are split: each sample's fold and scene (cv_folds.hpp).
struct FoldPlan {
  std::string rule;  // "scenes" or "blocks"
  int folds = 0;
  std::vector<int> fold_of_sample;
  std::vector<std::string> scene_of_sample;  // "frame:NAME" where no scene is known
};

// Training on N frames of each fold (0 = all), chosen by `seed` + fold.
struct TrainSubset {
  int frames = 0;
  std::uint64_t seed = 0;
};

// The regions of every sample's segmentation (region_features.hpp), for the
// table region vote that follows the MRF in the Segmenter (table_regions.hpp);
// empty when the vote is off. They come from what the sample kept: its
// segments' moments (SegmentFeatures::moments) and its adjacency.
std::vector<RegionFeatures> sampleRegions(const std::vector<FrameSample>& samples,
                                          const SegmenterConfig& config);

// Labels the test frames with `forest` and accumulates both confusions. The
// "+MRF" labels are the Segmenter's final ones: with `regions`, after the
// table region vote, as in Segmenter::classify. With mrf.pairwise = context
// the term is the one the fold's model learned from its training frames.
void labelFrames(const RandomForest& forest, const SegmenterConfig& config,
                 const std::vector<FrameSample>& samples, const std::vector<std::size_t>& frames,
                 const std::vector<RegionFeatures>& regions, Evaluation& eval, bool keep_pixels);

// Frame i of `samples` is tested as test_samples[i] (the same frame, or its
// raw-like copy with --degrade).
// With `unlabelled` frames and training.pseudo_rounds, each fold's model
// comes from trainModelWithPseudoLabels on that fold's training frames: the
// unlabelled frames are labelled by the fold's own models only, and the fold's
// test frames are never among them. `per_round`, when given, gets the figures
// of every round's models side by side (0 = labelled frames only).
Evaluation crossValidate(const std::vector<FrameSample>& samples,
                         const std::vector<FrameSample>& test_samples,
                         const std::vector<FrameSample>& extra_training, const FoldPlan& plan,
                         const SegmenterConfig& config, const TrainingOptions& training,
                         const std::vector<RegionFeatures>& regions, bool keep_pixels,
                         const TrainSubset& subset = {},
                         const std::vector<FrameSample>& unlabelled = {},
                         std::vector<Evaluation>* per_round = nullptr);

// The protocol line of the reports: the fold rule (NYU scenes formed by `nyu_rule`) and the
// training subset.
std::string describeFolds(const FoldPlan& plan, const std::string& nyu_rule,
                          const TrainSubset& subset);

// Each fold's test frames and scenes and its training frames, for the reports.
std::vector<EvalReport::Fold> foldRecords(const Evaluation& eval, const FoldPlan& plan,
                                          const std::vector<FrameSample>& samples);

// --sweep: the cross-validation again with 1..16 trees, then depths 2..16.
void runSweeps(const std::vector<FrameSample>& samples,
               const std::vector<FrameSample>& test_samples,
               const std::vector<FrameSample>& extra_training, const FoldPlan& plan,
               const Config& config, const std::vector<RegionFeatures>& regions,
               const TrainSubset& subset, EvalReport& report);

}  // namespace findmug::tools
