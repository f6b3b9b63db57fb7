// Tests for label_image.hpp: painting segment labels onto pixels, and the
// palette overlay.
#include "findmug/labels/label_image.hpp"

#include <gtest/gtest.h>

#include "findmug/common/error.hpp"

namespace findmug {
namespace {

// 4x2 image: segment 0 = left column pair, segment 1 = right, the middle
// pixels belong to no segment.
Oversegmentation twoSegments() {
  Oversegmentation seg;
  seg.width = 4;
  seg.height = 2;
  seg.pixel_segment = {0, -1, -1, 1, 0, -1, -1, 1};
  seg.segments = {{0, 4}, {3, 7}};
  seg.edges = {};
  return seg;
}

TEST(ProjectLabels, PaintsSegmentsAndLeavesTheRestVoid) {
  const LabelImage img = projectLabels(
      twoSegments(), {static_cast<std::uint8_t>(Label::Table), kVoidLabel}, {0.8f, 0.9f});
  ASSERT_EQ(img.width, 4);
  ASSERT_EQ(img.height, 2);
  const std::vector<std::uint8_t> expected_labels = {4, 255, 255, 255, 4, 255, 255, 255};
  EXPECT_EQ(img.labels, expected_labels);
  const std::vector<float> expected_conf = {0.8f, 0, 0, 0, 0.8f, 0, 0, 0};
  EXPECT_EQ(img.confidence, expected_conf);  // a void segment has no confidence

  const LabelImage floor = projectLabels(twoSegments(), {1, 2}, {0.5f, 1.0f});
  EXPECT_EQ(floor.labels[3], 2);
  EXPECT_EQ(floor.labels[7], 2);
  EXPECT_FLOAT_EQ(floor.confidence[7], 1.0f);
}

// projectLabelsInto writes every pixel of a recycled image, in runs of one
// segment: checked against a pixel-by-pixel painting on a segment image with
// runs of every length from 1 to 40 (and unsegmented runs), into an image
// that still holds another frame's labels and confidences.
TEST(ProjectLabels, IntoARecycledImageEveryPixelIsWritten) {
  Oversegmentation seg;
  seg.width = 97;
  seg.height = 23;
  const std::size_t pixels = static_cast<std::size_t>(seg.width) * seg.height;
  int next_segment = 0;
  for (int run = 1; seg.pixel_segment.size() < pixels; run = run % 40 + 1) {
    const int id = run % 7 == 3 ? -1 : next_segment++;
    for (int k = 0; k < run && seg.pixel_segment.size() < pixels; ++k) {
      seg.pixel_segment.push_back(id);
    }
  }
  seg.segments.resize(static_cast<std::size_t>(next_segment));
  std::vector<std::uint8_t> labels;
  std::vector<float> confidence;
  for (int s = 0; s < next_segment; ++s) {
    labels.push_back(s % 9 == 8 ? kVoidLabel : static_cast<std::uint8_t>(s % kNumLabels));
    confidence.push_back(static_cast<float>(s % 11) / 10.0f);
  }
  LabelImage out;
  out.labels.assign(pixels + 50, 7);
  out.confidence.assign(pixels + 50, 0.25f);
  projectLabelsInto(seg, labels, confidence, out);
  ASSERT_EQ(out.labels.size(), pixels);
  ASSERT_EQ(out.confidence.size(), pixels);
  for (std::size_t i = 0; i < pixels; ++i) {
    const int s = seg.pixel_segment[i];
    const std::uint8_t want = s < 0 ? kVoidLabel : labels[static_cast<std::size_t>(s)];
    const float want_confidence =
        want == kVoidLabel ? 0.0f : confidence[static_cast<std::size_t>(s)];
    ASSERT_EQ(out.labels[i], want) << "pixel " << i;
    ASSERT_EQ(out.confidence[i], want_confidence) << "pixel " << i;
  }
}

TEST(ProjectLabels, RejectsInconsistentInput) {
  EXPECT_THROW(projectLabels(twoSegments(), {1}, {0.5f}), Error);
  EXPECT_THROW(projectLabels(twoSegments(), {1, 2}, {0.5f}), Error);
  EXPECT_THROW(projectLabels(twoSegments(), {1, 8}, {0.5f, 0.5f}), Error);  // no class 8
  EXPECT_THROW(projectLabels(twoSegments(), {1, 2}, {0.5f, 1.5f}), Error);
  Oversegmentation bad = twoSegments();
  bad.pixel_segment[1] = 2;
  EXPECT_THROW(projectLabels(bad, {1, 2}, {0.5f, 0.5f}), Error);
  bad = twoSegments();
  bad.pixel_segment.pop_back();
  EXPECT_THROW(projectLabels(bad, {1, 2}, {0.5f, 0.5f}), Error);
}

TEST(ColorizeLabels, BlendsPaletteWithImage) {
  LabelImage img;
  img.width = 3;
  img.height = 1;
  img.labels = {static_cast<std::uint8_t>(Label::Floor), static_cast<std::uint8_t>(Label::Wall),
                kVoidLabel};
  img.confidence = {1, 1, 0};
  const std::vector<Rgb8> rgb = {{100, 100, 100}, {0, 0, 0}, {200, 100, 50}};

  const auto pure = colorizeLabels(img, rgb, 1.0f);
  EXPECT_EQ(pure[0], kLabelColors[1]);
  EXPECT_EQ(pure[1], kLabelColors[2]);
  EXPECT_EQ(pure[2], kVoidColor);

  EXPECT_EQ(colorizeLabels(img, rgb, 0.0f), rgb);

  const auto mixed = colorizeLabels(img, rgb);  // alpha 0.6
  // floor red (220, 30, 30) over grey 100: 0.6*220 + 0.4*100 = 172, 0.6*30 + 40 = 58
  EXPECT_EQ(mixed[0], (Rgb8{172, 58, 58}));
  // wall blue (40, 70, 220) over black
  EXPECT_EQ(mixed[1], (Rgb8{24, 42, 132}));
  // void darkens the image
  EXPECT_EQ(mixed[2], (Rgb8{80, 40, 20}));
}

TEST(ColorizeLabels, RejectsBadInput) {
  LabelImage img;
  img.width = 2;
  img.height = 1;
  img.labels = {1, 2};
  img.confidence = {1, 1};
  const std::vector<Rgb8> rgb(2);
  EXPECT_THROW(colorizeLabels(img, std::vector<Rgb8>(3)), Error);
  EXPECT_THROW(colorizeLabels(img, rgb, 1.5f), Error);
  EXPECT_THROW(colorizeLabels(img, rgb, -0.1f), Error);
  img.labels[1] = 9;
  EXPECT_THROW(colorizeLabels(img, rgb), Error);
}

}  // namespace
}  // namespace findmug
