// findmug/offline/pseudo_labels.hpp — semi-supervised training rounds on unlabelled frames.
//
// Offline only (findmug-train, findmug-eval --unlabelled DIR). A round: label
// every unlabelled frame with the whole Segmenter of the current model
// (forest, table weight, MRF, table region vote: labelSample), keep the
// patches whose confidence exceeds training.pseudo_min_confidence as training
// patches of weight training.pseudo_weight, at most training.pseudo_class_cap
// times as many per label as the labelled frames hold (the most confident
// first, so that floor and wall do not swamp the rest), and retrain on the
// labelled frames and those patches. training.pseudo_rounds rounds; each
// round labels the unlabelled frames afresh with the last round's model.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "findmug/mrf/layout_prior.hpp"
#include "findmug/mrf/mrf.hpp"
#include "findmug/offline/training.hpp"

namespace findmug {

// The Segmenter's answer for one extracted frame: the model's p(y|x) per
// segment, and the final labels with their confidence (the MRF's belief, or
// the forest's probability when config.use_mrf is off; after the table region
// vote when features.regions and tables.region_vote are on, which needs
// `regions` = sampleRegionFeatures of the sample). With mrf.pairwise =
// context the term is the model's (refused when it has none, as by the
// Segmenter); with mrf.pairwise = layout, `layout` is the prior
// (loadLayoutPrior of mrf.layout_prior_path; refused when missing).
struct SampleLabelling {
  std::vector<ClassProbabilities> probabilities;
  MrfResult mrf;
};
SampleLabelling labelSample(const RandomForest& model, const FrameSample& sample,
                            const SegmenterConfig& config, const RegionFeatures* regions,
                            const LayoutPrior* layout = nullptr);

// What one round added: per label, the patches that passed the confidence
// threshold and those kept after the per-label cap; the frames they came from.
struct PseudoLabelRound {
  int round = 0;  // 1-based
  std::array<int, kNumLabels> confident{}, kept{};
  std::vector<std::string> frames;  // unlabelled frames with at least one kept patch
  int keptTotal() const;
};

struct PseudoLabelReport {
  std::vector<std::string> pool;  // names of the unlabelled frames offered
  std::vector<PseudoLabelRound> rounds;
};

// The pseudo-labelled copies of `unlabelled` from one labelling each
// (labellings[i] of unlabelled[i]): segment_labels are the labels of the
// kept patches, void elsewhere; with internal classes (learner.classes) each
// kept patch's fine class is its label's most frequent fine class among the
// labelled frames' patches (a label no labelled patch has is not kept).
// Frames without a kept patch are left out. Fills `round` (not its number).
std::vector<FrameSample> pseudoLabelledSamples(const std::vector<FrameSample>& unlabelled,
                                               const std::vector<SampleLabelling>& labellings,
                                               const std::vector<const FrameSample*>& labelled,
                                               const SegmenterConfig& config,
                                               const TrainingOptions& training,
                                               PseudoLabelRound& round);

// trainModel on `labelled`, then training.pseudo_rounds rounds over
// `unlabelled` (extracted frames whose labels are ignored). `after_round(r,
// model)` sees the model after each round r = 0 (labelled frames only) ..
// pseudo_rounds, e.g. to evaluate them side by side. `report`, when given,
// gets what each round added. Every retraining uses config.forest's seed, so
// a round that keeps no patch gives the round-0 model again.
RandomForest trainModelWithPseudoLabels(
    const std::vector<const FrameSample*>& labelled, const std::vector<FrameSample>& unlabelled,
    const SegmenterConfig& config, const TrainingOptions& training,
    PseudoLabelReport* report = nullptr,
    const std::function<void(int, const RandomForest&)>& after_round = {});

// The configuration unlabelled frames are extracted with (by extractSamples, so
// with no training-only views, whose patches could not carry the labels of the
// frame's own patches): the ground re-estimated every frame, and found in the
// frame itself where ground.source would read labelled floor.
SegmenterConfig unlabelledExtractionConfig(SegmenterConfig config);

// One line per round: "round 1: 1234 patches kept of 2345 confident (floor
// 300, wall 400, ...) from 9 frames".
std::string formatPseudoLabelReport(const PseudoLabelReport& report);

}  // namespace findmug
