// Tests of counting the label-layout prior on label maps (layout_counts.hpp):
// hand-made maps whose boundary pairs are known, void skipped, and which NYU
// label maps share a scene with the evaluation frames.
#include "findmug/offline/layout_counts.hpp"

#include <gtest/gtest.h>

#include "findmug/common/error.hpp"

namespace findmug {
namespace {

constexpr int L = kNumLabels;
constexpr std::uint8_t F = static_cast<std::uint8_t>(Label::Floor);
constexpr std::uint8_t W = static_cast<std::uint8_t>(Label::Wall);
constexpr std::uint8_t T = static_cast<std::uint8_t>(Label::Table);
constexpr std::uint8_t V = kVoidLabel;

Image<std::uint8_t> image(int w, int h, std::vector<std::uint8_t> pixels) {
  return Image<std::uint8_t>{w, h, std::move(pixels)};
}

double total(const LayoutPairCounts& c) {
  double s = 0;
  for (double v : c) s += v;
  return s;
}

TEST(LayoutCounts, WallAboveTableAboveFloor) {
  // 2 columns, rows: wall, table, floor.
  const auto map = image(2, 3, {W, W, T, T, F, F});
  LayoutCounts c;
  addLayoutPairs(map, 1, c);
  EXPECT_EQ(c.frames, 1);
  EXPECT_EQ(c.vertical[W * L + T], 2);  // each column once
  EXPECT_EQ(c.vertical[T * L + F], 2);
  EXPECT_EQ(c.vertical[T * L + W], 0);  // direction kept
  EXPECT_EQ(c.vertical[F * L + T], 0);
  EXPECT_EQ(total(c.vertical), 4);
  EXPECT_EQ(total(c.horizontal), 0);  // rows are uniform
  // Offset 2: wall over floor only.
  LayoutCounts c2;
  addLayoutPairs(map, 2, c2);
  EXPECT_EQ(c2.vertical[W * L + F], 2);
  EXPECT_EQ(total(c2.vertical), 2);
}

TEST(LayoutCounts, HorizontalIsSymmetricAndVoidSkipped) {
  // One row: wall, table, void, floor.
  const auto map = image(4, 1, {W, T, V, F});
  LayoutCounts c;
  addLayoutPairs(map, 1, c);
  EXPECT_EQ(c.horizontal[W * L + T], 1);
  EXPECT_EQ(c.horizontal[T * L + W], 1);
  EXPECT_EQ(total(c.horizontal), 2);  // table|void and void|floor skipped
  LayoutCounts c2;
  addLayoutPairs(map, 2, c2);  // wall..void skipped, table..floor counted
  EXPECT_EQ(c2.horizontal[T * L + F], 1);
  EXPECT_EQ(c2.horizontal[F * L + T], 1);
  EXPECT_EQ(total(c2.horizontal), 2);
  EXPECT_THROW(addLayoutPairs(map, 0, c), Error);
  EXPECT_THROW(addLayoutPairs(image(3, 3, {W}), 1, c), Error);
}

TEST(LayoutCounts, MapsOfEvaluationScenesAreLeftOut) {
  // Test split 1..3, 7..9; 4..6 are train: scenes {1,2,3}, {7,8,9}.
  const std::vector<long> test = {1, 2, 3, 7, 8, 9, 12};
  const std::vector<long> candidates = {1, 2, 3, 7, 8, 9, 12};
  EXPECT_EQ(indicesOutsideScenes(candidates, {2}, test), (std::vector<long>{7, 8, 9, 12}));
  EXPECT_EQ(indicesOutsideScenes(candidates, {2, 9}, test), (std::vector<long>{12}));
  EXPECT_EQ(indicesOutsideScenes(candidates, {}, test), candidates);
}

}  // namespace
}  // namespace findmug
