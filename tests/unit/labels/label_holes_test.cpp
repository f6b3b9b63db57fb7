// Tests for label_holes.hpp: the pixels without depth take the labels beside them.
#include "findmug/labels/label_holes.hpp"

#include <gtest/gtest.h>

#include <string>

#include "findmug/common/error.hpp"

namespace findmug {
namespace {

constexpr std::uint8_t V = kVoidLabel;
constexpr auto kWall = static_cast<std::uint8_t>(Label::Wall);
constexpr auto kChair = static_cast<std::uint8_t>(Label::Chair);
constexpr auto kFloor = static_cast<std::uint8_t>(Label::Floor);

// An image of `labels` (row-major, `width` wide) with confidence 0.9 where labelled.
LabelImage imageOf(int width, std::vector<std::uint8_t> labels) {
  LabelImage image;
  image.width = width;
  image.height = static_cast<int>(labels.size()) / width;
  image.confidence.resize(labels.size());
  for (std::size_t i = 0; i < labels.size(); ++i)
    image.confidence[i] = labels[i] == V ? 0.0f : 0.9f;
  image.labels = std::move(labels);
  return image;
}

// Depth 0 where the label is void, else `mm`.
std::vector<std::uint16_t> depthOf(const LabelImage& image, std::uint16_t mm) {
  std::vector<std::uint16_t> depth(image.labels.size(), mm);
  for (std::size_t i = 0; i < depth.size(); ++i)
    if (image.labels[i] == V) depth[i] = 0;
  return depth;
}

TEST(FillLabelHoles, ARunBetweenTwoEqualLabelsTakesThatLabelWithNoConfidence) {
  LabelImage image = imageOf(6, {kWall, V, V, V, kWall, kWall});
  const std::size_t filled = fillLabelHoles(depthOf(image, 2000), {}, image);
  EXPECT_EQ(filled, 3u);
  EXPECT_EQ(image.labels, std::vector<std::uint8_t>(6, kWall));
  EXPECT_EQ(image.confidence, (std::vector<float>{0.9f, 0, 0, 0, 0.9f, 0.9f}));
}

TEST(FillLabelHoles, BetweenTwoLabelsTheFartherSideWins) {
  // A chair at 1.2 m casts a shadow on the wall at 3 m behind it: the run
  // between them is the wall's, whichever side the chair is on.
  LabelImage right_shadow = imageOf(7, {kChair, kChair, V, V, V, kWall, kWall});
  std::vector<std::uint16_t> depth = {1200, 1200, 0, 0, 0, 3000, 3000};
  fillLabelHoles(depth, {}, right_shadow);
  EXPECT_EQ(right_shadow.labels,
            (std::vector<std::uint8_t>{kChair, kChair, kWall, kWall, kWall, kWall, kWall}));

  LabelImage left_shadow = imageOf(7, {kWall, kWall, V, V, V, kChair, kChair});
  depth = {3000, 3000, 0, 0, 0, 1200, 1200};
  fillLabelHoles(depth, {}, left_shadow);
  EXPECT_EQ(left_shadow.labels,
            (std::vector<std::uint8_t>{kWall, kWall, kWall, kWall, kWall, kChair, kChair}));
}

TEST(FillLabelHoles, ARunAtTheBorderTakesItsOneSide) {
  LabelImage image = imageOf(5, {V, V, kFloor, kWall, V});
  fillLabelHoles(depthOf(image, 1500), {}, image);
  EXPECT_EQ(image.labels, (std::vector<std::uint8_t>{kFloor, kFloor, kFloor, kWall, kWall}));
}

TEST(FillLabelHoles, RunsLongerThanTheLimitStayVoid) {
  // 1 x 8: a run of 5 with a limit of 4 stays void, a run of 2 is filled.
  LabelImage image = imageOf(8, {kWall, V, V, V, V, V, kWall, V});
  LabelHoleFillConfig config;
  config.max_run_px = 4;
  const std::size_t filled = fillLabelHoles(depthOf(image, 2000), config, image);
  EXPECT_EQ(filled, 1u);
  EXPECT_EQ(image.labels, (std::vector<std::uint8_t>{kWall, V, V, V, V, V, kWall, kWall}));
}

TEST(FillLabelHoles, WhatTheRowsCannotFillTheColumnsDo) {
  // 3 x 3: the middle row has no label at all (a run across the whole row);
  // each of its pixels takes its column's labels, the farther one where
  // they differ (top row at 4 m, bottom at 1 m except the middle column).
  LabelImage image = imageOf(3, {kWall, kWall, kWall,  //
                                 V, V, V,              //
                                 kFloor, kWall, kFloor});
  const std::vector<std::uint16_t> depth = {4000, 4000, 4000, 0, 0, 0, 1000, 4000, 1000};
  LabelHoleFillConfig config;
  config.max_run_px = 2;  // the row run (3) is too long, the column runs (1) are not
  EXPECT_EQ(fillLabelHoles(depth, config, image), 3u);
  EXPECT_EQ(image.labels, (std::vector<std::uint8_t>{kWall, kWall, kWall, kWall, kWall, kWall,
                                                     kFloor, kWall, kFloor}));
  EXPECT_EQ(image.confidence[4], 0.0f);
}

TEST(FillLabelHoles, WithoutDepthOnASideTheGapIsSplitBetweenItsSides) {
  // One column of 4 rows, wall above floor: the two void rows have no side
  // along their row, so the column fills them. With depth on both sides the
  // farther (wall) wins; without depth on one side (it was filled itself)
  // each half takes its nearer side.
  LabelImage image = imageOf(1, {kWall, V, V, kFloor});
  const std::vector<std::uint16_t> depth = {3000, 0, 0, 1000};
  EXPECT_EQ(fillLabelHoles(depth, {}, image), 2u);
  EXPECT_EQ(image.labels, (std::vector<std::uint8_t>{kWall, kWall, kWall, kFloor}));

  LabelImage no_depth = imageOf(1, {kWall, V, V, kFloor});
  EXPECT_EQ(fillLabelHoles({0, 0, 0, 1000}, {}, no_depth), 2u);
  EXPECT_EQ(no_depth.labels, (std::vector<std::uint8_t>{kWall, kWall, kFloor, kFloor}));
}

TEST(FillLabelHoles, DisabledOrAllVoidChangesNothing) {
  LabelImage image = imageOf(4, {kWall, V, V, kWall});
  const LabelImage before = image;
  LabelHoleFillConfig off;
  off.enabled = false;
  EXPECT_EQ(fillLabelHoles(depthOf(image, 2000), off, image), 0u);
  EXPECT_EQ(image.labels, before.labels);

  LabelImage empty = imageOf(2, {V, V, V, V});
  EXPECT_EQ(fillLabelHoles(depthOf(empty, 2000), {}, empty), 0u);
  EXPECT_EQ(empty.labels, std::vector<std::uint8_t>(4, V));
}

TEST(FillLabelHoles, SizesThatDisagreeAreRefusedNamingThem) {
  LabelImage image = imageOf(4, {kWall, V, V, kWall});
  try {
    fillLabelHoles(std::vector<std::uint16_t>(3, 1000), {}, image);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("depth has 3 pixels"), std::string::npos) << e.what();
  }
  LabelHoleFillConfig bad;
  bad.max_run_px = 0;
  EXPECT_THROW(fillLabelHoles(depthOf(image, 1000), bad, image), Error);
}

}  // namespace
}  // namespace findmug
