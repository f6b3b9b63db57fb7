// Tests of the object-candidate mean mixed into the MRF's unaries
// (mrf.object_consistency): the pixel-weighted mean, planes left alone, the
// limiting weights, and input validation.
#include "findmug/mrf/object_consistency.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "findmug/common/error.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;

ClassProbabilities onlyLabel(Label label) {
  ClassProbabilities p{};
  p[static_cast<int>(label)] = 1.0f;
  return p;
}

float at(const ClassProbabilities& p, Label label) { return p[static_cast<int>(label)]; }

// Three patches of one candidate (a table top of 300 pixels the forest calls
// table, a 100-pixel piece it calls object, one of 0 pixels it calls chair) and a
// wall plane patch.
struct Frame {
  std::vector<ClassProbabilities> p = {onlyLabel(Label::Table), onlyLabel(Label::Object),
                                       onlyLabel(Label::Chair), onlyLabel(Label::Wall)};
  std::vector<int> group = {0, 0, 0, -1};
  std::vector<float> weights = {300.0f, 100.0f, 0.0f, 500.0f};
};

TEST(ObjectConsistency, MixesThePixelWeightedMeanOfTheCandidateIntoItsPatches) {
  Frame f;
  ObjectMeanScratch scratch;
  mixObjectMeansInPlace(f.p, f.group, f.weights, 0.5f, scratch);
  // The candidate's mean: table 0.75, object 0.25 (the weightless chair patch adds nothing).
  EXPECT_FLOAT_EQ(at(f.p[0], Label::Table), 0.5f + 0.5f * 0.75f);
  EXPECT_FLOAT_EQ(at(f.p[0], Label::Object), 0.5f * 0.25f);
  EXPECT_FLOAT_EQ(at(f.p[1], Label::Table), 0.5f * 0.75f);
  EXPECT_FLOAT_EQ(at(f.p[1], Label::Object), 0.5f + 0.5f * 0.25f);
  EXPECT_FLOAT_EQ(at(f.p[2], Label::Chair), 0.5f);
  EXPECT_FLOAT_EQ(at(f.p[2], Label::Table), 0.5f * 0.75f);
  for (const ClassProbabilities& p : f.p) {
    float sum = 0;
    for (const float v : p) sum += v;
    EXPECT_NEAR(sum, 1.0f, 1e-6f);
  }
  // The wall plane keeps its own.
  EXPECT_EQ(f.p[3], onlyLabel(Label::Wall));
}

TEST(ObjectConsistency, WeightOneGivesEveryPatchOfACandidateTheSameDistribution) {
  Frame f;
  f.group = {1, 1, 0, -1};  // two candidates: ids need not be dense or ordered
  ObjectMeanScratch scratch;
  mixObjectMeansInPlace(f.p, f.group, f.weights, 1.0f, scratch);
  EXPECT_EQ(f.p[0], f.p[1]);
  EXPECT_FLOAT_EQ(at(f.p[0], Label::Table), 0.75f);
  // Candidate 0 has only the weightless patch: no mean, it keeps its own.
  EXPECT_EQ(f.p[2], onlyLabel(Label::Chair));
  EXPECT_EQ(f.p[3], onlyLabel(Label::Wall));
}

TEST(ObjectConsistency, WeightZeroOrNoObjectFeaturesLeaveTheDistributions) {
  const Frame original;
  Frame f;
  ObjectMeanScratch scratch;
  mixObjectMeansInPlace(f.p, f.group, f.weights, 0.0f, scratch);
  EXPECT_EQ(f.p, original.p);
  mixObjectMeansInPlace(f.p, {}, f.weights, 0.5f, scratch);
  EXPECT_EQ(f.p, original.p);
}

TEST(ObjectConsistency, RefusesMismatchedInputsAndWeightsOutOfRange) {
  ObjectMeanScratch scratch;
  const auto message = [&](Frame f, float weight) {
    try {
      mixObjectMeansInPlace(f.p, f.group, f.weights, weight, scratch);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(message(Frame{}, 1.5f), HasSubstr("outside [0, 1]"));
  EXPECT_THAT(message(Frame{}, -0.1f), HasSubstr("outside [0, 1]"));
  Frame short_groups;
  short_groups.group.pop_back();
  EXPECT_THAT(message(short_groups, 0.5f), HasSubstr("4 distributions, 3 object groups"));
  Frame bad_weight;
  bad_weight.weights[1] = -1.0f;
  EXPECT_THAT(message(bad_weight, 0.5f), HasSubstr("segment 1 has weight"));
}

}  // namespace
}  // namespace findmug
