// The Segmenter with mrf.object_consistency on real NYU frames and the shipped
// model: every patch knows its object candidate, weight 1 gives the patches of
// a candidate one label when the pairwise term is switched off (sigma tiny),
// the shipped weight reaches the labels, and the published forest answer stays
// the forest's.
#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <set>

#include "findmug/frame/dataset.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "findmug/settings/config.hpp"
#include "shipped_model.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

// The shipped model's settings with mrf.object_consistency = `consistency`.
Config shippedConfig(const std::string& consistency) {
  Config config = test::shippedModelConfig();
  applyOverride(config, "mrf.object_consistency=" + consistency);
  return config;
}

// Candidates whose patches carry more than one of `labels`.
int mixedCandidates(const std::vector<int>& object_group, const std::vector<std::uint8_t>& labels) {
  std::map<int, std::set<std::uint8_t>> labels_of;
  for (std::size_t k = 0; k < object_group.size(); ++k)
    if (object_group[k] >= 0) labels_of[object_group[k]].insert(labels[k]);
  int mixed = 0;
  for (const auto& [group, set] : labels_of) mixed += set.size() > 1;
  return mixed;
}

TEST(SegmenterObjects, ObjectConsistencyGivesACandidateOneOpinion) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const auto forest = test::shippedModel();
  const DatasetFolder dataset = test::framesOf(nyu.string());
  Config no_pairwise_off = shippedConfig("0"), no_pairwise_on = shippedConfig("1");
  for (Config* c : {&no_pairwise_off, &no_pairwise_on}) applyOverride(*c, "mrf.sigma=0.0001");
  const Segmenter off(no_pairwise_off.segmenter, forest), on(no_pairwise_on.segmenter, forest);
  const Segmenter plain(shippedConfig("0").segmenter, forest);
  const Segmenter shipped(shippedConfig("0.5").segmenter, forest);
  int frames = 0, mixed_without = 0, frames_changed = 0;
  for (std::size_t i = 0; i < 4 && i < dataset.size(); ++i) {
    const RgbdFrame frame = dataset.load(i).frame;
    const LabelledFrame a = off.process(frame);
    if (a.mrf.labels.empty()) continue;  // no ground plane
    ++frames;
    const LabelledFrame b = on.process(frame);
    const std::vector<int>& groups = b.features.object_group;
    ASSERT_EQ(groups.size(), b.mrf.labels.size()) << "frame " << i;
    EXPECT_EQ(groups, a.features.object_group);
    std::set<int> candidates;
    int planes = 0;
    for (const int g : groups) (g >= 0 ? (void)candidates.insert(g) : (void)++planes);
    EXPECT_GT(candidates.size(), 1u) << "frame " << i;
    EXPECT_GT(planes, 0) << "frame " << i;  // floor and walls are not object candidates
    EXPECT_EQ(mixedCandidates(groups, b.mrf.labels), 0) << "frame " << i;
    mixed_without += mixedCandidates(groups, a.mrf.labels);
    EXPECT_EQ(a.forest_probabilities, b.forest_probabilities) << "frame " << i;
    if (shipped.process(frame).mrf.labels != plain.process(frame).mrf.labels) ++frames_changed;
  }
  ASSERT_GT(frames, 0);
  EXPECT_GT(mixed_without, 0);  // without it the forest splits some candidates
  EXPECT_GT(frames_changed, 0);
}

}  // namespace
}  // namespace findmug
