// Tests for label_image.hpp: painting segment labels onto pixels, and the
// palette overlay.
#include "findmug/label_image.hpp"

#include <gtest/gtest.h>

#include "findmug/error.hpp"

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
