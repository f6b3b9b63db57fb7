#include "findmug/training.hpp"

#include "findmug/error.hpp"

namespace findmug {

LabeledFrames framesOf(const DatasetFolder& dataset) {
  return {dataset.dir(), dataset.size(), [&dataset](std::size_t i) { return dataset.load(i); }};
}

LabeledFrames framesOf(const NyuMatFile& mat, const std::string& path) {
  return {path, mat.size(), [&mat](std::size_t i) { return mat.load(i); }};
}

std::vector<FrameSample> extractSamples(const DatasetFolder& dataset, const Segmenter& segmenter,
                                        ExtractionReport& report,
                                        const std::function<void(int, int)>& progress) {
  return extractSamples(framesOf(dataset), segmenter, report, progress);
}

std::vector<FrameSample> extractSamples(const LabeledFrames& frames, const Segmenter& segmenter,
                                        ExtractionReport& report,
                                        const std::function<void(int, int)>& progress) {
  std::vector<FrameSample> samples;
  report = {};
  report.frames_total = static_cast<int>(frames.count);
  for (std::size_t i = 0; i < frames.count; ++i) {
    LabeledFrame labelled = frames.load(i);
    PreparedFrame prepared = segmenter.prepare(std::move(labelled.frame), &labelled.labels);
    if (!prepared.ground) {
      report.dropped.push_back(labelled.name + ": no ground plane found");
    } else {
      const GroundMethod method = prepared.ground->method;
      SegmentedFrame segmented = segmenter.oversegment(std::move(prepared));
      FrameSample sample;
      sample.name = labelled.name;
      sample.source_index = i;
      sample.width = segmented.segmentation.width;
      sample.height = segmented.segmentation.height;
      sample.features = segmenter.features(segmented);
      sample.segment_labels = segmentMajorityLabels(segmented.segmentation, labelled.labels);
      sample.segment_pixels.reserve(segmented.segmentation.segments.size());
      for (const auto& pixels : segmented.segmentation.segments) {
        sample.segment_pixels.push_back(static_cast<std::uint32_t>(pixels.size()));
      }
      sample.edges = std::move(segmented.segmentation.edges);
      sample.pixel_segment = std::move(segmented.segmentation.pixel_segment);
      sample.ground_truth = std::move(labelled.labels);
      sample.ground_method = method;
      report.ground_methods.emplace_back(sample.name, groundMethodName(method));
      samples.push_back(std::move(sample));
      ++report.frames_used;
    }
    if (progress) progress(static_cast<int>(i + 1), report.frames_total);
  }
  return samples;
}

TrainingSet makeTrainingSet(const std::vector<FrameSample>& samples,
                            const std::vector<std::size_t>& frame_indices) {
  std::vector<const FrameSample*> frames;
  for (std::size_t f : frame_indices) frames.push_back(&samples.at(f));
  return makeTrainingSet(frames);
}

TrainingSet makeTrainingSet(const std::vector<const FrameSample*>& frames) {
  TrainingSet set;
  const bool regions = !frames.empty() && !frames.front()->features.regions.empty();
  if (regions) set.extra_names.assign(kRegionFeatureNames.begin(), kRegionFeatureNames.end());
  for (const FrameSample* s : frames) {
    if (s->features.regions.empty() == regions && !s->features.features.empty()) {
      throw Error("makeTrainingSet: frame " + s->name + (regions ? " lacks" : " has") +
                  " region features unlike the first frame");
    }
    for (std::size_t k = 0; k < s->segment_labels.size(); ++k) {
      if (s->segment_labels[k] >= kNumLabels) continue;
      set.features.push_back(s->features.features[k]);
      if (regions) {
        const auto begin = s->features.regions.begin() +
                           static_cast<std::ptrdiff_t>(k * kRegionFeatureDim);
        set.extra.insert(set.extra.end(), begin, begin + kRegionFeatureDim);
      }
      set.labels.push_back(s->segment_labels[k]);
    }
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

RandomForest trainModel(const std::vector<const FrameSample*>& frames,
                        const SegmenterConfig& config,
                        const std::function<void(int, int)>& progress) {
  const int folds = config.context.enabled && config.context.cross_fit_folds >= 2
                        ? std::min<int>(config.context.cross_fit_folds,
                                        static_cast<int>(frames.size()))
                        : 0;
  const int total = config.context.enabled ? 2 + (folds >= 2 ? folds : 0) : 1;
  int done = 0;
  auto tick = [&] {
    if (progress) progress(++done, total);
  };
  RandomForest first = RandomForest::train(makeTrainingSet(frames), config.forest);
  tick();
  if (!config.context.enabled) return first;

  // First-stage distributions of every training frame, each from a forest
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
      const TrainingSet set = makeTrainingSet(train);
      if (set.labels.empty()) throw Error("trainModel: cross-fitting group " + std::to_string(g) +
                                          " leaves no labelled segment to train on");
      const RandomForest forest = RandomForest::train(set, params);
      for (std::size_t k = 0; k < held_out.size(); ++k)
        probs[held_index[k]] = predictSample(forest, *held_out[k], first_only);
      tick();
    }
  } else {
    for (std::size_t i = 0; i < n; ++i) probs[i] = predictSample(first, *frames[i], first_only);
  }

  // Context-stage rows: first-stage rows, then context columns.
  TrainingSet set;
  if (!frames.empty() && !frames.front()->features.regions.empty())
    set.extra_names.assign(kRegionFeatureNames.begin(), kRegionFeatureNames.end());
  for (const auto& name : contextFeatureNames()) set.extra_names.push_back(name);
  const std::size_t first_extra = set.extra_names.size() - kContextFeatureDim;
  for (std::size_t i = 0; i < n; ++i) {
    const FrameSample& s = *frames[i];
    const std::vector<float> ctx =
        computeContextFeatures(probs[i], s.features.centroids, segmentWeights(s), config.context);
    for (std::size_t k = 0; k < s.segment_labels.size(); ++k) {
      if (s.segment_labels[k] >= kNumLabels) continue;
      set.features.push_back(s.features.features[k]);
      if (first_extra > 0) {
        const auto begin = s.features.regions.begin() + static_cast<std::ptrdiff_t>(k * first_extra);
        set.extra.insert(set.extra.end(), begin, begin + static_cast<std::ptrdiff_t>(first_extra));
      }
      const auto begin = ctx.begin() + static_cast<std::ptrdiff_t>(k * kContextFeatureDim);
      set.extra.insert(set.extra.end(), begin, begin + kContextFeatureDim);
      set.labels.push_back(s.segment_labels[k]);
    }
  }
  ForestParams params = config.forest;
  params.seed += 500;
  RandomForest second = RandomForest::train(set, params);
  tick();
  first.setContextStage(std::move(second));
  return first;
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

}  // namespace findmug
