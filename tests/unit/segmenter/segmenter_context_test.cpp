// The Segmenter with mrf.pairwise = context: the learned term travels with
// the model (format 5), a model without one is refused naming the setting,
// and the term reaches the labels of a real NYU frame as a per-edge scale of
// the paper's Potts weight.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <memory>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/mrf/context_pairwise.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/settings/config.hpp"
#include "shipped_model.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;

Config contextConfig() {
  Config config = test::shippedModelConfig();
  applyOverride(config, "mrf.pairwise=context");
  return config;
}

TEST(SegmenterContext, ShippedModelCarriesTheTermAndAModelWithoutOneIsRefused) {
  const auto shipped = test::shippedModel();
  ASSERT_NE(shipped->pairwiseContext(), nullptr)
      << "models/findmug.fmf was trained without mrf.pairwise=context (models/README.md)";
  EXPECT_GT(shipped->pairwiseContext()->training_edges, 10000u);
  EXPECT_NO_THROW(Segmenter(contextConfig().segmenter, shipped));

  // The same forest without its term, as a format-4 model would load.
  auto plain = std::make_shared<RandomForest>(*shipped);
  plain->setPairwiseContext(std::nullopt);
  try {
    Segmenter segmenter(contextConfig().segmenter, plain);
    FAIL() << "mrf.pairwise=context was accepted with a model that has no term";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("mrf.pairwise = context"));
    EXPECT_THAT(e.what(), HasSubstr(plain->id()));
  }
  // Feature extraction (training) needs no model; Potts needs no term; no MRF, no term.
  EXPECT_NO_THROW(Segmenter(contextConfig().segmenter, nullptr));
  EXPECT_NO_THROW(Segmenter(test::shippedModelConfig().segmenter, plain));
  Config no_mrf = contextConfig();
  applyOverride(no_mrf, "mrf.enabled=false");
  EXPECT_NO_THROW(Segmenter(no_mrf.segmenter, plain));
  Config bad = contextConfig();
  EXPECT_THROW(applyOverride(bad, "mrf.pairwise=crf"), Error);
}

// On real frames the learned term changes some patch labels from Potts'; a
// term that says the same for every pair (all weights 0, its cost as the
// mean) scales every edge by exactly 1 and gives Potts' labels bit for bit:
// the term acts through the edge scales and nowhere else.
TEST(SegmenterContext, ReachesTheLabelsOfRealFramesAsAnEdgeScale) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const auto shipped = test::shippedModel();
  auto flat = std::make_shared<RandomForest>(*shipped);
  PairwiseContext flat_term = *shipped->pairwiseContext();
  flat_term.weights = {0.0, 0.0, 0.0, 0.0};
  flat_term.mean_cost = contextPartingCost(sameLabelProbability(flat_term, {1, 2, 0.1f, 0.3f}));
  flat->setPairwiseContext(flat_term);

  const DatasetFolder dataset = test::framesOf(nyu.string());
  const Segmenter potts(test::shippedModelConfig().segmenter, shipped);
  const Segmenter learned(contextConfig().segmenter, shipped);
  const Segmenter unit_scales(contextConfig().segmenter, flat);
  int frames_with_mrf = 0, frames_changed = 0;
  for (std::size_t i = 0; i < 4 && i < dataset.size(); ++i) {
    const RgbdFrame frame = dataset.load(i).frame;
    const LabelledFrame base = potts.process(frame);
    if (base.mrf.labels.empty()) continue;  // no ground plane
    ++frames_with_mrf;
    const LabelledFrame with_term = learned.process(frame);
    ASSERT_EQ(with_term.mrf.labels.size(), base.mrf.labels.size());
    if (with_term.mrf.labels != base.mrf.labels) ++frames_changed;
    EXPECT_EQ(with_term.forest_labels, base.forest_labels) << "frame " << i;  // unaries unchanged
    const LabelledFrame ones = unit_scales.process(frame);
    EXPECT_EQ(ones.mrf.labels, base.mrf.labels) << "frame " << i;
    EXPECT_EQ(ones.labels.labels, base.labels.labels) << "frame " << i;
  }
  ASSERT_GT(frames_with_mrf, 0);
  EXPECT_GT(frames_changed, 0);
}

}  // namespace
}  // namespace findmug
