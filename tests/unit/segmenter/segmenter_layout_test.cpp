// The Segmenter with mrf.pairwise = layout: it loads the prior file when it
// is built (a bad file is refused, naming it), and the term reaches the
// labels of a real NYU frame.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <memory>

#include "findmug/common/error.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/settings/config.hpp"
#include "shipped_model.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

const std::string kCommittedPrior =
    (test::sourceDir() / "models" / "nyu-layout-prior.csv").string();


TEST(SegmenterLayout, LoadsThePriorAndRefusesABadOne) {
  const auto forest = test::shippedModel();
  Config config = test::shippedModelConfig();
  applyOverride(config, "mrf.pairwise=layout");
  test::TempDir dir;
  const std::string bad = dir.str("prior.csv");
  std::ofstream(bad) << "findmug-layout-prior,1\nsmoothing,1\noffset_px,10\nframes,1\n"
                        "vertical,floor,table,lots\n";
  applyOverride(config, "mrf.layout_prior_path=" + bad);
  try {
    Segmenter segmenter(config.segmenter, forest);
    FAIL() << "a corrupt layout prior was accepted";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr(bad + ": line 5: count 'lots'"));
  }
  applyOverride(config, "mrf.layout_prior_path=" + dir.str("absent.csv"));
  EXPECT_THROW(Segmenter(config.segmenter, forest), Error);
  EXPECT_NO_THROW(Segmenter(config.segmenter, nullptr));  // feature extraction needs no prior
  applyOverride(config, "mrf.layout_prior_path=" + kCommittedPrior);
  EXPECT_NO_THROW(Segmenter(config.segmenter, forest));
  EXPECT_THROW(applyOverride(config, "mrf.layout_direction=sideways"), Error);
  EXPECT_THROW(applyOverride(config, "mrf.layout_weight=-1"), Error);
  EXPECT_THROW(applyOverride(config, "mrf.layout_prior_path="), Error);
}

// A strong prior changes some patch labels of a real frame, a zero weight
// none: the term is used by the Segmenter, and weight 0 is Potts.
TEST(SegmenterLayout, ReachesTheLabelsOfARealFrame) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const auto forest = test::shippedModel();
  const DatasetFolder dataset = test::framesOf(nyu.string());
  const Config potts = test::shippedModelConfig();
  const Segmenter potts_segmenter(potts.segmenter, forest);
  int frames_changed = 0, frames_with_mrf = 0;
  for (std::size_t i = 0; i < 3 && i < dataset.size(); ++i) {
    const RgbdFrame frame = dataset.load(i).frame;
    const LabelledFrame base = potts_segmenter.process(frame);
    if (base.mrf.labels.empty()) continue;  // no ground plane
    ++frames_with_mrf;
    for (const char* weight : {"0", "50"}) {
      Config layout = potts;
      applyOverride(layout, "mrf.pairwise=layout");
      applyOverride(layout, "mrf.layout_prior_path=" + kCommittedPrior);
      applyOverride(layout, std::string("mrf.layout_weight=") + weight);
      const LabelledFrame out = Segmenter(layout.segmenter, forest).process(frame);
      if (std::string(weight) == "0") {
        EXPECT_EQ(out.mrf.labels, base.mrf.labels) << "frame " << i;
      } else if (out.mrf.labels != base.mrf.labels) {
        ++frames_changed;
      }
    }
  }
  ASSERT_GT(frames_with_mrf, 0);
  EXPECT_GT(frames_changed, 0);
}

}  // namespace
}  // namespace findmug
