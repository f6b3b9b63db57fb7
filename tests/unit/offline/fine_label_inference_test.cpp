// inferMissingFineLabels (training.hpp): patches of frames labelled with the
// 8 labels only get the finer class most of their nearest finely labelled
// patches of the same label hold, in feature columns scaled by their spread;
// a label no finely labelled patch has is refused by name.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "findmug/common/error.hpp"
#include "findmug/offline/training.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;

constexpr auto kWall = static_cast<std::uint8_t>(Label::Wall);
constexpr auto kTable = static_cast<std::uint8_t>(Label::Table);
constexpr auto kChair = static_cast<std::uint8_t>(Label::Chair);
constexpr std::uint8_t kNyu13Wall = 12, kNyu13Window = 13, kNyu13Table = 10;

// A sample whose first feature is `x`, second `y` (the others 0), with one
// extra column `extra`.
void add(TrainingSet& set, std::uint8_t label, std::uint8_t fine, float x, float y, float extra) {
  FeatureVector f{};
  f[0] = x;
  f[1] = y;
  set.features.push_back(f);
  set.extra.push_back(extra);
  set.labels.push_back(label);
  set.split_labels.push_back(fine);
}

TrainingSet wallsAndWindows() {
  TrainingSet set;
  set.extra_names = {"column"};
  set.split_classes = kNyu13Classes + 1;
  for (int i = 0; i < 6; ++i) {
    // Walls are grey (x near 0), windows bright (x near 10); y is noise on a
    // scale 1000 times larger, which the spread scaling must not let dominate.
    add(set, kWall, kNyu13Wall, 0.1f * static_cast<float>(i), 1000.0f * static_cast<float>(i % 3), 0);
    add(set, kWall, kNyu13Window, 10.0f - 0.1f * static_cast<float>(i),
        1000.0f * static_cast<float>((i + 1) % 3), 0);
    add(set, kTable, kNyu13Table, 10.0f, 0.0f, 0);  // a table that looks like a window
  }
  return set;
}

TEST(FineLabelInference, EachPatchTakesTheFineClassOfItsNeighboursOfTheSameLabel) {
  TrainingSet set = wallsAndWindows();
  const std::size_t first_missing = set.labels.size();
  add(set, kWall, kMissingFineLabel, 9.6f, 500.0f, 0);   // bright: a window
  add(set, kWall, kMissingFineLabel, 0.4f, 1500.0f, 0);  // grey: a wall
  add(set, kTable, kMissingFineLabel, 0.0f, 0.0f, 0);    // grey, but only tables are tables
  inferMissingFineLabels(set);
  EXPECT_EQ(set.split_labels[first_missing], kNyu13Window);
  EXPECT_EQ(set.split_labels[first_missing + 1], kNyu13Wall);
  EXPECT_EQ(set.split_labels[first_missing + 2], kNyu13Table);
  // The finely labelled samples are untouched.
  const TrainingSet before = wallsAndWindows();
  for (std::size_t i = 0; i < first_missing; ++i) EXPECT_EQ(set.split_labels[i], before.split_labels[i]);
}

TEST(FineLabelInference, ExtraColumnsTakePartInTheDistance) {
  TrainingSet set;
  set.extra_names = {"height"};
  for (int i = 0; i < 5; ++i) {
    add(set, kWall, kNyu13Wall, 0, 0, 0.0f);
    add(set, kWall, kNyu13Window, 0, 0, 2.0f);
  }
  add(set, kWall, kMissingFineLabel, 0, 0, 1.9f);
  inferMissingFineLabels(set);
  EXPECT_EQ(set.split_labels.back(), kNyu13Window);
}

TEST(FineLabelInference, ALabelWithoutFinelyLabelledPatchesIsRefusedByName) {
  TrainingSet set = wallsAndWindows();
  add(set, kChair, kMissingFineLabel, 1.0f, 0.0f, 0);
  try {
    inferMissingFineLabels(set);
    FAIL() << "expected the chair patch to be refused";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("label 'chair'"));
  }
}

TEST(FineLabelInference, NothingMissingChangesNothing) {
  TrainingSet set = wallsAndWindows();
  const std::vector<std::uint8_t> before = set.split_labels;
  inferMissingFineLabels(set);
  EXPECT_EQ(set.split_labels, before);
}

}  // namespace
}  // namespace findmug
