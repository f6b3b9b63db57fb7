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
  TrainingSet set;
  for (std::size_t f : frame_indices) {
    const FrameSample& s = samples.at(f);
    for (std::size_t k = 0; k < s.segment_labels.size(); ++k) {
      if (s.segment_labels[k] >= kNumLabels) continue;
      set.features.push_back(s.features.features[k]);
      set.labels.push_back(s.segment_labels[k]);
    }
  }
  return set;
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
