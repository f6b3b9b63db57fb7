// The learned pairwise term (mrf/context_pairwise.hpp, learned by
// offline/mrf_context.hpp): learned on hand-made graphs where a colour step
// means a label change, it lets a weak patch follow its look-alike neighbour
// where the paper's Potts term does not. The Segmenter's use of it:
// tests/unit/segmenter/segmenter_context_test.cpp.
#include "findmug/offline/mrf_context.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "findmug/common/error.hpp"
#include "findmug/mrf/mrf.hpp"

namespace findmug {
namespace {

// A patch with lightness L at height h (m); the other features are neutral.
FeatureVector patch(float lightness, float height = 1.0f) {
  FeatureVector f{};
  f[3] = height;     // centroid_height
  f[6] = 1.5f;       // normal_angle (rad): vertical surfaces
  f[8] = lightness;  // lab_l_mean
  return f;
}

// Training graphs: chains of patches in runs of one label; inside a run
// lightness wanders by 0..3, across a label change it jumps by 25..40.
std::vector<LabelledGraph> trainingGraphs(std::vector<std::vector<FeatureVector>>& features,
                                          std::vector<std::vector<std::pair<int, int>>>& edges,
                                          std::vector<std::vector<std::uint8_t>>& labels) {
  features.assign(4, {});
  edges.assign(4, {});
  labels.assign(4, {});
  std::vector<LabelledGraph> graphs;
  for (int g = 0; g < 4; ++g) {
    float lightness = 20.0f;
    std::uint8_t label = static_cast<std::uint8_t>(Label::Wall);
    for (int i = 0; i < 60; ++i) {
      if (i > 0 && i % 5 == 0) {
        label = label == static_cast<std::uint8_t>(Label::Wall)
                    ? static_cast<std::uint8_t>(Label::Cabinet)
                    : static_cast<std::uint8_t>(Label::Wall);
        lightness += (i * 7 + g * 3) % 2 ? 25.0f + static_cast<float>((i + g) % 16)
                                         : -25.0f - static_cast<float>((i + g) % 16);
      } else {
        lightness += static_cast<float>((i * 13 + g) % 7) * 0.5f - 1.5f;
      }
      features[g].push_back(patch(lightness));
      labels[g].push_back(label);
      if (i > 0) edges[g].emplace_back(i - 1, i);
    }
    labels[g][30] = kVoidLabel;  // unlabelled patches' edges are not used
    graphs.push_back({&features[g], &edges[g], &labels[g]});
  }
  return graphs;
}

TEST(MrfContext, LearnsThatAColourStepMeansALabelChange) {
  std::vector<std::vector<FeatureVector>> f;
  std::vector<std::vector<std::pair<int, int>>> e;
  std::vector<std::vector<std::uint8_t>> l;
  const PairwiseContext model = learnPairwiseContext(trainingGraphs(f, e, l));
  EXPECT_EQ(model.training_edges, 4u * (59 - 2));
  EXPECT_LT(model.weights[0], 0.0);  // more lightness difference, less likely the same label
  const double alike = sameLabelProbability(model, pairFeatures(patch(50), patch(51)));
  const double unlike = sameLabelProbability(model, pairFeatures(patch(50), patch(82)));
  EXPECT_GT(alike, 0.9);
  EXPECT_LT(unlike, 0.1);
  // The scales average 1 over the training edges.
  double scale_sum = 0;
  std::size_t scale_count = 0;
  for (std::size_t g = 0; g < f.size(); ++g) {
    std::vector<std::pair<int, int>> labelled;
    for (const auto& [a, b] : e[g])
      if (l[g][a] < kNumLabels && l[g][b] < kNumLabels) labelled.emplace_back(a, b);
    for (float v : pairwiseContextScales(model, f[g], labelled)) {
      scale_sum += v;
      ++scale_count;
    }
  }
  EXPECT_NEAR(scale_sum / scale_count, 1.0, 1e-4);
  const auto scales =
      pairwiseContextScales(model, {patch(50), patch(51), patch(82)}, {{0, 1}, {1, 2}});
  ASSERT_EQ(scales.size(), 2u);
  EXPECT_GT(scales[0], 1.0f);
  EXPECT_LT(scales[1], 0.2f);
}

// A - B - C at equal distances: A surely wall, C surely cabinet, B leans
// cabinet a little but looks like A. Potts leaves B to its unary; the
// learned term holds B to its look-alike A and lets it part from C.
TEST(MrfContext, WeakPatchFollowsItsLookAlikeNeighbour) {
  std::vector<std::vector<FeatureVector>> f;
  std::vector<std::vector<std::pair<int, int>>> e;
  std::vector<std::vector<std::uint8_t>> l;
  const PairwiseContext model = learnPairwiseContext(trainingGraphs(f, e, l));
  const std::vector<FeatureVector> features = {patch(50), patch(51), patch(85)};
  const std::vector<std::pair<int, int>> edges = {{0, 1}, {1, 2}};
  const std::vector<Eigen::Vector3f> centroids = {
      {0.0f, 0.0f, 1.0f}, {0.07f, 0.0f, 1.0f}, {0.14f, 0.0f, 1.0f}};
  auto probabilities = [](float wall, float cabinet) {
    ClassProbabilities p{};
    const float rest = (1.0f - wall - cabinet) / (kNumLabels - 2);
    for (auto& v : p) v = rest;
    p[static_cast<int>(Label::Wall)] = wall;
    p[static_cast<int>(Label::Cabinet)] = cabinet;
    return p;
  };
  const std::vector<ClassProbabilities> unaries = {
      probabilities(0.9f, 0.05f), probabilities(0.4f, 0.45f), probabilities(0.05f, 0.9f)};
  MrfParams params;
  const MrfResult potts = solveMrf(unaries, centroids, edges, params);
  EXPECT_EQ(potts.labels[1], static_cast<std::uint8_t>(Label::Cabinet));
  const MrfResult context = solveMrfScaled(unaries, centroids, edges,
                                           pairwiseContextScales(model, features, edges), params);
  EXPECT_EQ(context.labels[0], static_cast<std::uint8_t>(Label::Wall));
  EXPECT_EQ(context.labels[1], static_cast<std::uint8_t>(Label::Wall));
  EXPECT_EQ(context.labels[2], static_cast<std::uint8_t>(Label::Cabinet));
  // Scales of 1 are the paper's term exactly.
  const MrfResult ones = solveMrfScaled(unaries, centroids, edges, {1.0f, 1.0f}, params);
  EXPECT_EQ(ones.labels, potts.labels);
  EXPECT_EQ(ones.confidence, potts.confidence);
  EXPECT_THROW(solveMrfScaled(unaries, centroids, edges, {1.0f}, params), Error);
  EXPECT_THROW(solveMrfScaled(unaries, centroids, edges, {1.0f, -1.0f}, params), Error);
}

TEST(MrfContext, BadGraphsAreNamed) {
  const std::vector<FeatureVector> features = {patch(1), patch(2)};
  const std::vector<std::pair<int, int>> edges = {{0, 2}};
  const std::vector<std::uint8_t> labels = {1, 1};
  EXPECT_THROW(learnPairwiseContext({{&features, &edges, &labels}}), Error);
  const std::vector<std::pair<int, int>> fine = {{0, 1}};
  const std::vector<std::uint8_t> void_labels = {kVoidLabel, 1};
  EXPECT_THROW(learnPairwiseContext({{&features, &fine, &void_labels}}), Error);
  EXPECT_THROW(pairwiseContextScales(PairwiseContext{}, features, edges), Error);
}

}  // namespace
}  // namespace findmug
