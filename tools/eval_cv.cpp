// findmug-eval's cross-validation (eval_cv.hpp).
#include "eval_cv.hpp"

#include <algorithm>
#include <cstdio>
#include <optional>
#include <utility>

#include "findmug/common/error.hpp"
#include "findmug/offline/cv_folds.hpp"
#include "findmug/tables/table_regions.hpp"

namespace findmug::tools {
namespace {

std::uint8_t argmax(const ClassProbabilities& p) {
  return static_cast<std::uint8_t>(std::max_element(p.begin(), p.end()) - p.begin());
}

}  // namespace

std::vector<RegionFeatures> sampleRegions(const std::vector<FrameSample>& samples,
                                          const SegmenterConfig& config) {
  if (!config.regions.enabled || !config.tables.region_vote) return {};
  std::vector<RegionFeatures> out;
  out.reserve(samples.size());
  for (const FrameSample& s : samples) out.push_back(sampleRegionFeatures(s, config.regions));
  return out;
}

void labelFrames(const RandomForest& forest, const SegmenterConfig& config,
                 const std::vector<FrameSample>& samples, const std::vector<std::size_t>& frames,
                 const std::vector<RegionFeatures>& regions, Evaluation& eval, bool keep_pixels) {
  SegmenterConfig with_mrf = config;
  with_mrf.use_mrf = true;  // the "+MRF" figures, whatever use_mrf says
  std::optional<LayoutPrior> layout;
  if (with_mrf.mrf.pairwise == MrfPairwise::Layout)
    layout = loadLayoutPrior(with_mrf.mrf.layout_prior_path);
  for (std::size_t f : frames) {
    const FrameSample& s = samples[f];
    const std::size_t n = s.features.features.size();
    SampleLabelling labelling = labelSample(
        forest, s, with_mrf, regions.empty() ? nullptr : &regions[f], layout ? &*layout : nullptr);
    std::vector<std::uint8_t> forest_labels(n);
    for (std::size_t k = 0; k < n; ++k) forest_labels[k] = argmax(labelling.probabilities[k]);
    eval.forest.add(s.ground_truth, publishedPixelLabels(s, forest_labels, config.label_holes));
    auto mrf_pixels = publishedPixelLabels(s, labelling.mrf.labels, config.label_holes);
    eval.mrf.add(s.ground_truth, mrf_pixels);
    if (keep_pixels) {
      eval.mrf_pixels[f] = std::move(mrf_pixels);
      eval.probabilities[f] = std::move(labelling.probabilities);
      eval.mrf_results[f] = std::move(labelling.mrf);
    }
  }
}

Evaluation crossValidate(const std::vector<FrameSample>& samples,
                         const std::vector<FrameSample>& test_samples,
                         const std::vector<FrameSample>& extra_training, const FoldPlan& plan,
                         const SegmenterConfig& config, const TrainingOptions& training,
                         const std::vector<RegionFeatures>& regions, bool keep_pixels,
                         const TrainSubset& subset, const std::vector<FrameSample>& unlabelled,
                         std::vector<Evaluation>* per_round) {
  Evaluation eval;
  auto sized = [&](Evaluation& e) {
    e.mrf_pixels.resize(samples.size());
    e.probabilities.resize(samples.size());
    e.mrf_results.resize(samples.size());
  };
  sized(eval);
  const int rounds = unlabelled.empty() ? 0 : training.pseudo_rounds;
  if (per_round) {
    per_round->assign(static_cast<std::size_t>(rounds) + 1, Evaluation{});
    for (auto& e : *per_round) sized(e);
  }
  const std::size_t n = samples.size();
  for (int fold = 0; fold < plan.folds; ++fold) {
    std::vector<std::size_t> train, test;
    for (std::size_t i = 0; i < n; ++i)
      (plan.fold_of_sample[i] == fold ? test : train).push_back(i);
    if (test.empty() || train.empty()) continue;
    if (subset.frames > 0) {
      train = chooseTrainingSubset(train, plan.scene_of_sample, subset.frames,
                                   subset.seed + static_cast<std::uint64_t>(fold));
    }
    std::vector<const FrameSample*> frames;
    for (std::size_t i : train) frames.push_back(&samples[i]);
    for (const auto& s : extra_training) frames.push_back(&s);
    if (makeTrainingSet(frames).labels.empty()) continue;
    SegmenterConfig fold_config = config;
    fold_config.forest.seed += static_cast<std::uint64_t>(fold);
    PseudoLabelReport pseudo;
    if (rounds > 0) {
      // The pool: unlabelled frames only. A frame also among the labelled
      // inputs was refused when the inputs were read (extractUnlabelled);
      // checked again here, per fold, against this fold's test frames.
      for (const FrameSample& u : unlabelled)
        for (std::size_t t : test)
          if (u.name == samples[t].name)
            throw Error("fold " + std::to_string(fold) + ": test frame " + u.name +
                        " is among the unlabelled frames");
      const RandomForest forest = trainModelWithPseudoLabels(
          frames, unlabelled, fold_config, training, &pseudo,
          [&](int r, const RandomForest& model) {
            if (per_round && r < rounds)
              labelFrames(model, config, test_samples, test, regions,
                          (*per_round)[static_cast<std::size_t>(r)], keep_pixels);
          });
      labelFrames(forest, config, test_samples, test, regions, eval, keep_pixels);
    } else {
      const RandomForest forest = trainModel(frames, fold_config, training);
      labelFrames(forest, config, test_samples, test, regions, eval, keep_pixels);
    }
    eval.folds.push_back({fold, train, test, std::move(pseudo)});
  }
  if (per_round) {
    per_round->back() = eval;
    for (auto& e : *per_round) e.folds = eval.folds;
  }
  return eval;
}

std::string describeFolds(const FoldPlan& plan, const std::string& nyu_rule,
                          const TrainSubset& subset) {
  std::string text = std::to_string(plan.folds) + "-fold cross-validation by frame, ";
  text += plan.rule == "scenes" ? "folds of whole scenes (frames.csv scene, else " + nyu_rule +
                                      "; largest scene first into the smallest fold)"
                                : "contiguous blocks of frames in input order";
  if (subset.frames > 0) {
    text += "; each fold trained on " + std::to_string(subset.frames) +
            " of its training frames (subset seed " + std::to_string(subset.seed) + " + fold)";
  }
  return text;
}

std::vector<EvalReport::Fold> foldRecords(const Evaluation& eval, const FoldPlan& plan,
                                          const std::vector<FrameSample>& samples) {
  std::vector<EvalReport::Fold> out;
  for (const auto& fold : eval.folds) {
    EvalReport::Fold r;
    r.fold = fold.fold;
    r.train_frames = static_cast<int>(fold.train.size());
    for (std::size_t i : fold.test) {
      r.test_frames.push_back(samples[i].name);
      r.test_scenes.push_back(plan.scene_of_sample[i]);
    }
    for (std::size_t i : fold.train) r.train_frame_names.push_back(samples[i].name);
    r.pseudo_pool = fold.pseudo.pool;
    for (const auto& round : fold.pseudo.rounds) {
      r.pseudo_frames.push_back(round.frames);
      r.pseudo_patches.push_back(round.keptTotal());
    }
    out.push_back(std::move(r));
  }
  return out;
}

void runSweeps(const std::vector<FrameSample>& samples,
               const std::vector<FrameSample>& test_samples,
               const std::vector<FrameSample>& extra_training, const FoldPlan& plan,
               const Config& config, const std::vector<RegionFeatures>& regions,
               const TrainSubset& subset, EvalReport& report) {
  for (int trees : {1, 2, 4, 6, 8, 10, 12, 14, 16}) {
    SegmenterConfig c = config.segmenter;
    c.forest.num_trees = trees;
    const Evaluation e = crossValidate(samples, test_samples, extra_training, plan, c,
                                       config.offline.training, regions, false, subset);
    report.sweep_trees.push_back({trees, c.forest.max_depth, e.forest, e.mrf});
    std::fprintf(stderr, "sweep trees=%d: forest %.1f/%.1f mrf %.1f/%.1f\n", trees,
                 100 * e.forest.classAverageAccuracy(), 100 * e.forest.globalAccuracy(),
                 100 * e.mrf.classAverageAccuracy(), 100 * e.mrf.globalAccuracy());
  }
  for (int depth : {2, 4, 6, 8, 10, 12, 14, 16}) {
    SegmenterConfig c = config.segmenter;
    c.forest.max_depth = depth;
    const Evaluation e = crossValidate(samples, test_samples, extra_training, plan, c,
                                       config.offline.training, regions, false, subset);
    report.sweep_depth.push_back({c.forest.num_trees, depth, e.forest, e.mrf});
    std::fprintf(stderr, "sweep depth=%d: forest %.1f/%.1f mrf %.1f/%.1f\n", depth,
                 100 * e.forest.classAverageAccuracy(), 100 * e.forest.globalAccuracy(),
                 100 * e.mrf.classAverageAccuracy(), 100 * e.mrf.globalAccuracy());
  }
}

}  // namespace findmug::tools
