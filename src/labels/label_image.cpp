// label_image.cpp — segment labels painted back onto the pixel grid, and the
// colour overlay used by the viewer, the tools and the paper-style figures.
#include "findmug/labels/label_image.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "findmug/common/error.hpp"

namespace findmug {

LabelImage projectLabels(const Oversegmentation& segmentation,
                         const std::vector<std::uint8_t>& segment_labels,
                         const std::vector<float>& segment_confidence) {
  LabelImage out;
  projectLabelsInto(segmentation, segment_labels, segment_confidence, out);
  return out;
}

void projectLabelsInto(const Oversegmentation& segmentation,
                       const std::vector<std::uint8_t>& segment_labels,
                       const std::vector<float>& segment_confidence, LabelImage& out) {
  const std::size_t segments = segmentation.segments.size();
  const std::size_t pixels = static_cast<std::size_t>(std::max(segmentation.width, 0)) *
                             static_cast<std::size_t>(std::max(segmentation.height, 0));
  if (segmentation.width <= 0 || segmentation.height <= 0 ||
      segmentation.pixel_segment.size() != pixels) {
    std::ostringstream msg;
    msg << "projectLabels: segmentation is " << segmentation.width << "x" << segmentation.height
        << " but has " << segmentation.pixel_segment.size() << " pixel entries";
    throw Error(msg.str());
  }
  if (segment_labels.size() != segments || segment_confidence.size() != segments) {
    std::ostringstream msg;
    msg << "projectLabels: " << segments << " segments but " << segment_labels.size()
        << " labels and " << segment_confidence.size() << " confidences";
    throw Error(msg.str());
  }
  for (std::size_t s = 0; s < segments; ++s) {
    const std::uint8_t id = segment_labels[s];
    if (id >= kNumLabels && id != kVoidLabel) {
      throw Error("projectLabels: segment " + std::to_string(s) + " has label id " +
                  std::to_string(id) + " (valid: 0.." + std::to_string(kNumLabels - 1) + " or " +
                  std::to_string(kVoidLabel) + ")");
    }
    const float c = segment_confidence[s];
    if (!std::isfinite(c) || c < 0.0f || c > 1.0f) {
      throw Error("projectLabels: segment " + std::to_string(s) + " has confidence " +
                  std::to_string(c) + " (must be in 0..1)");
    }
  }

  out.width = segmentation.width;
  out.height = segmentation.height;
  // Every pixel is written below (a recycled image is not cleared first),
  // through a table of each segment's label and confidence (entry 0: no
  // segment), without a branch per pixel: segments cross a row in runs of a
  // few pixels on a cluttered view, where a run at a time lost more on the
  // runs' ends than it saved. A segment id out of range is found by the
  // same pass and reported afterwards.
  out.labels.resize(pixels);
  out.confidence.resize(pixels);
  thread_local std::vector<std::uint8_t> label_of_tls;
  thread_local std::vector<float> confidence_of_tls;
  std::vector<std::uint8_t>& label_of = label_of_tls;
  std::vector<float>& confidence_of = confidence_of_tls;
  label_of.resize(segments + 1);
  confidence_of.resize(segments + 1);
  label_of[0] = kVoidLabel;
  confidence_of[0] = 0.0f;
  for (std::size_t s = 0; s < segments; ++s) {
    label_of[s + 1] = segment_labels[s];
    confidence_of[s + 1] = segment_labels[s] == kVoidLabel ? 0.0f : segment_confidence[s];
  }
  const int* pixel_segment = segmentation.pixel_segment.data();
  std::uint8_t* labels = out.labels.data();
  float* confidence = out.confidence.data();
  const std::uint8_t* label_table = label_of.data();
  const float* confidence_table = confidence_of.data();
  bool any_bad = false;
  for (std::size_t i = 0; i < pixels; ++i) {
    // A negative id (no segment) -> entry 0, segment s -> s + 1.
    const int s = pixel_segment[i];
    const bool bad = s >= 0 && static_cast<std::size_t>(s) >= segments;
    any_bad |= bad;
    const std::size_t entry = s < 0 || bad ? 0 : static_cast<std::size_t>(s) + 1;
    labels[i] = label_table[entry];
    confidence[i] = confidence_table[entry];
  }
  if (any_bad) {
    for (std::size_t i = 0; i < pixels; ++i) {
      const int s = pixel_segment[i];
      if (s >= 0 && static_cast<std::size_t>(s) >= segments) {
        throw Error("projectLabels: pixel " + std::to_string(i) + " belongs to segment " +
                    std::to_string(s) + " but there are only " + std::to_string(segments));
      }
    }
  }
}

std::vector<Rgb8> colorizeLabels(const LabelImage& labels, const std::vector<Rgb8>& rgb,
                                 float alpha) {
  const std::size_t pixels = static_cast<std::size_t>(std::max(labels.width, 0)) *
                             static_cast<std::size_t>(std::max(labels.height, 0));
  if (labels.labels.size() != pixels || rgb.size() != pixels) {
    std::ostringstream msg;
    msg << "colorizeLabels: label image " << labels.width << "x" << labels.height << " has "
        << labels.labels.size() << " labels and the colour image " << rgb.size()
        << " pixels (expected " << pixels << ")";
    throw Error(msg.str());
  }
  if (!(alpha >= 0.0f && alpha <= 1.0f)) {
    throw Error("colorizeLabels: alpha " + std::to_string(alpha) + " is outside 0..1");
  }
  // Void pixels blend with kVoidColor (black) too, so that alpha = 1 gives
  // the plain palette image and the overlay darkens what was not labelled.
  auto blend = [alpha](std::uint8_t label_c, std::uint8_t image_c) {
    const float v = alpha * label_c + (1.0f - alpha) * image_c;
    return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
  };
  std::vector<Rgb8> out(pixels);
  for (std::size_t i = 0; i < pixels; ++i) {
    const std::uint8_t id = labels.labels[i];
    if (id >= kNumLabels && id != kVoidLabel) {
      throw Error("colorizeLabels: pixel " + std::to_string(i) + " has label id " +
                  std::to_string(id) + " (valid: 0.." + std::to_string(kNumLabels - 1) + " or " +
                  std::to_string(kVoidLabel) + ")");
    }
    const Rgb8 c = id < kNumLabels ? kLabelColors[id] : kVoidColor;
    out[i] = {blend(c.r, rgb[i].r), blend(c.g, rgb[i].g), blend(c.b, rgb[i].b)};
  }
  return out;
}

}  // namespace findmug
