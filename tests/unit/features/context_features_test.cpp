// Auto-context features on a hand-made arrangement of patches whose
// neighbourhood means can be worked out by hand.
#include "findmug/features/context_features.hpp"

#include <gtest/gtest.h>

#include "findmug/common/error.hpp"

namespace findmug {
namespace {

ClassProbabilities oneHot(Label label) {
  ClassProbabilities p{};
  p[static_cast<int>(label)] = 1.0f;
  return p;
}

float at(const std::vector<float>& ctx, std::size_t patch, int neighbourhood, Label label) {
  return ctx[patch * kContextFeatureDim + neighbourhood * kNumLabels + static_cast<int>(label)];
}

enum { kNear = 0, kFar = 1, kAbove = 2, kBelow = 3 };

TEST(ContextFeatures, NamesAreNeighbourhoodMajorLabelMinor) {
  const auto names = contextFeatureNames();
  ASSERT_EQ(names.size(), static_cast<std::size_t>(kContextFeatureDim));
  EXPECT_EQ(names[0], "ctx_near_unknown");
  EXPECT_EQ(names[kNumLabels + static_cast<int>(Label::Table)], "ctx_far_table");
  EXPECT_EQ(names[3 * kNumLabels + static_cast<int>(Label::Chair)], "ctx_below_chair");
}

TEST(ContextFeatures, SizeWeightedMeansOverNearFarAboveAndBelow) {
  // 0: table top at 0.7 m; 1: object beside it on the table (0.2 m away);
  // 2: wall 0.5 m above the table top; 3: floor 3 m away.
  const std::vector<ClassProbabilities> p = {oneHot(Label::Table), oneHot(Label::Object),
                                             oneHot(Label::Wall), oneHot(Label::Floor)};
  const std::vector<Eigen::Vector3f> c = {{0, 0, 0.7f}, {0.2f, 0, 0.7f}, {0, 0, 1.2f}, {3, 0, 0}};
  const std::vector<float> w = {1, 3, 2, 1};
  const ContextConfig config;  // 0.3 m, 1 m, column radius 0.5 m
  const auto ctx = computeContextFeatures(p, c, w, config);
  ASSERT_EQ(ctx.size(), 4u * kContextFeatureDim);

  // Table top: near = itself and the object (weights 1 and 3).
  EXPECT_FLOAT_EQ(at(ctx, 0, kNear, Label::Table), 0.25f);
  EXPECT_FLOAT_EQ(at(ctx, 0, kNear, Label::Object), 0.75f);
  EXPECT_FLOAT_EQ(at(ctx, 0, kNear, Label::Wall), 0.0f);
  // Far (1 m) adds the wall, 0.5 m away: 1 + 3 + 2 = 6.
  EXPECT_FLOAT_EQ(at(ctx, 0, kFar, Label::Wall), 2.0f / 6.0f);
  EXPECT_FLOAT_EQ(at(ctx, 0, kFar, Label::Floor), 0.0f);
  // Above: the wall only (the object is level with it, neither above nor below).
  EXPECT_FLOAT_EQ(at(ctx, 0, kAbove, Label::Wall), 1.0f);
  // Below: nothing, all zeros.
  for (int l = 0; l < kNumLabels; ++l) EXPECT_EQ(at(ctx, 0, kBelow, static_cast<Label>(l)), 0.0f);

  // The wall has the table top and the object below it (0.2 m < 0.5 m column).
  EXPECT_FLOAT_EQ(at(ctx, 2, kBelow, Label::Table), 0.25f);
  EXPECT_FLOAT_EQ(at(ctx, 2, kBelow, Label::Object), 0.75f);
  EXPECT_FLOAT_EQ(at(ctx, 2, kNear, Label::Wall), 1.0f);

  // The floor patch is alone: near and far are itself, nothing above or below.
  EXPECT_FLOAT_EQ(at(ctx, 3, kNear, Label::Floor), 1.0f);
  EXPECT_FLOAT_EQ(at(ctx, 3, kFar, Label::Floor), 1.0f);
  EXPECT_FLOAT_EQ(at(ctx, 3, kAbove, Label::Floor), 0.0f);

  // A narrower column leaves the object out of the wall's "below".
  ContextConfig narrow = config;
  narrow.column_radius_m = 0.1f;
  const auto ctx2 = computeContextFeatures(p, c, w, narrow);
  EXPECT_FLOAT_EQ(at(ctx2, 2, kBelow, Label::Table), 1.0f);
  EXPECT_FLOAT_EQ(at(ctx2, 2, kBelow, Label::Object), 0.0f);
}

TEST(ContextFeatures, RefusesInconsistentInput) {
  const std::vector<ClassProbabilities> p(2, oneHot(Label::Wall));
  const std::vector<Eigen::Vector3f> c = {{0, 0, 0}, {1, 0, 0}};
  EXPECT_THROW(computeContextFeatures(p, c, {1.0f}, ContextConfig{}), Error);
  EXPECT_THROW(computeContextFeatures(p, c, {1.0f, 0.0f}, ContextConfig{}), Error);
  EXPECT_NO_THROW(computeContextFeatures(p, c, {1.0f, 2.0f}, ContextConfig{}));
}

}  // namespace
}  // namespace findmug
