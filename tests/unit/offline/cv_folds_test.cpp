// Tests for cv_folds.hpp: frames.csv listings, NYU index-run scenes, folds
// that never split a scene, reproducible training subsets, the a + b ln N fit.
#include "findmug/offline/cv_folds.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "findmug/common/error.hpp"

namespace findmug {
namespace {

// The NYU indices of the 46 shared labelled frames (nyuv2_labeled + _extra).
const std::vector<long> kShared46 = {1,  2,  9,  14, 15, 16, 17, 18, 21, 28, 30, 31, 32, 35, 36,
                                     37, 38, 39, 42, 43, 46, 47, 57, 60, 63, 78, 88, 90, 118, 125,
                                     433, 29, 33, 40, 56, 59, 62, 76, 79, 84, 85, 86, 87, 89, 91,
                                     117};

TEST(CvFolds, FrameListingReadsIndexAndScene) {
  const auto listing = parseFrameListing(
      "frame,nyu_index,split,scene\n0001,1,test,kitchen_a\n0433,433,test,billiard\n", "f.csv");
  ASSERT_EQ(listing.size(), 2u);
  EXPECT_EQ(listing.at("0433").nyu_index, 433);
  EXPECT_EQ(listing.at("0001").scene, "kitchen_a");
  const auto no_scene = parseFrameListing("frame,nyu_index\n0009,9\n", "g.csv");
  EXPECT_EQ(no_scene.at("0009").scene, "");
  EXPECT_THROW(parseFrameListing("name,nyu_index\n0001,1\n", "h.csv"), Error);
  EXPECT_THROW(parseFrameListing("frame,nyu_index\n0001,x1\n", "h.csv"), Error);
  EXPECT_THROW(parseFrameListing("frame,nyu_index\n0001,1,2\n", "h.csv"), Error);
  EXPECT_THROW(parseFrameListing("frame,nyu_index\n0001,1\n0001,1\n", "h.csv"), Error);
  try {
    parseFrameListing("frame,nyu_index\n0001,1\n0002,0\n", "h.csv");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("h.csv: line 3"), std::string::npos) << e.what();
  }
}

TEST(CvFolds, IndexRunsFormScenesWithinTheGap) {
  const std::vector<long> indices = {9, 1, 2, 59, 60, 62, 63, 57};
  const auto gap2 = nyuIndexRunScenes(indices, 2);
  EXPECT_EQ(gap2, (std::vector<std::string>{"nyu9", "nyu1", "nyu1", "nyu57", "nyu57", "nyu57",
                                            "nyu57", "nyu57"}));
  const auto gap1 = nyuIndexRunScenes(indices, 1);
  EXPECT_EQ(gap1[3], "nyu59");
  EXPECT_EQ(gap1[5], "nyu62");  // 60 -> 62 is more than 1 apart
  EXPECT_EQ(gap1[7], "nyu57");
  EXPECT_THROW(nyuIndexRunScenes(indices, -1), Error);
  // The shared 46 frames with gap 2: 12 scenes, the largest (NYU 28..43) 14 frames.
  const auto shared = nyuIndexRunScenes(kShared46, 2);
  std::map<std::string, int> sizes;
  for (const auto& s : shared) ++sizes[s];
  EXPECT_EQ(sizes.size(), 12u);
  EXPECT_EQ(sizes.at("nyu28"), 14);
  EXPECT_EQ(sizes.at("nyu84"), 8);
  EXPECT_EQ(sizes.at("nyu433"), 1);
}

// Official test indices around the shared frames (split_test_indices.txt, 1..130).
const std::vector<long> kTestIndicesTo130 = {
    1,  2,  9,  14, 15, 16, 17, 18, 21, 28, 29, 30, 31, 32, 33, 34, 35, 36, 37, 38, 39, 40,
    41, 42, 43, 46, 47, 56, 57, 59, 60, 61, 62, 63, 76, 77, 78, 79, 84, 85, 86, 87, 88, 89,
    90, 91, 117, 118, 119, 125, 126, 127, 128, 129};

TEST(CvFolds, SplitRunsNeverSplitARoomWhateverFramesArePresent) {
  // The 46 shared frames: 13 scenes; 56-57 and 59-63 apart (58 is a train index).
  std::vector<long> tests = kTestIndicesTo130;
  tests.push_back(433);
  const auto shared = nyuSplitRunScenes(kShared46, tests);
  std::map<std::string, int> sizes;
  for (const auto& s : shared) ++sizes[s];
  EXPECT_EQ(sizes.size(), 13u);
  EXPECT_EQ(sizes.at("nyu28"), 14);
  EXPECT_EQ(sizes.at("nyu56"), 2);
  EXPECT_EQ(sizes.at("nyu59"), 4);
  EXPECT_EQ(sizes.at("nyu433"), 1);
  // One folder alone: 60 and 63 (one bedroom) stay together, which gap 2 splits.
  const std::vector<long> alone = {57, 60, 63, 29, 33};
  const auto runs = nyuSplitRunScenes(alone, tests);
  EXPECT_EQ(runs[1], runs[2]);
  EXPECT_NE(runs[0], runs[1]);
  EXPECT_EQ(runs[3], runs[4]);
  const auto gaps = nyuIndexRunScenes(alone, 2);
  EXPECT_NE(gaps[1], gaps[2]);
  // Train frames (3..8) form their own run between test runs.
  const auto train = nyuSplitRunScenes({3, 8, 2, 9}, tests);
  EXPECT_EQ(train[0], train[1]);
  EXPECT_NE(train[0], train[2]);
  EXPECT_NE(train[1], train[3]);
  EXPECT_THROW(nyuSplitRunScenes({0}, tests), Error);
  EXPECT_EQ(parseNyuTestIndices("1\n2\n 9\n", "t.txt"), (std::vector<long>{1, 2, 9}));
  EXPECT_THROW(parseNyuTestIndices("1\nx2\n", "t.txt"), Error);
  EXPECT_THROW(parseNyuTestIndices("", "t.txt"), Error);
}

// Every scene's frames are in one fold, so no fold's training set (the
// other folds) holds a frame of a scene in its test set.
void expectNoSceneSplit(const std::vector<std::string>& scenes, const std::vector<int>& fold,
                        int folds) {
  ASSERT_EQ(fold.size(), scenes.size());
  for (int k = 0; k < folds; ++k) {
    std::set<std::string> test, train;
    for (std::size_t i = 0; i < scenes.size(); ++i) {
      ASSERT_GE(fold[i], 0);
      ASSERT_LT(fold[i], folds);
      (fold[i] == k ? test : train).insert(scenes[i]);
    }
    for (const auto& s : test) EXPECT_EQ(train.count(s), 0u) << "scene " << s << " fold " << k;
  }
}

TEST(CvFolds, SceneFoldsNeverSplitAScene) {
  const auto scenes = nyuIndexRunScenes(kShared46, 2);
  for (int folds = 2; folds <= 8; ++folds) {
    expectNoSceneSplit(scenes, sceneFolds(scenes, folds), folds);
  }
  // Balanced by frame count: 14 (the largest scene alone), then 8 8 8 8.
  const auto fold = sceneFolds(scenes, 5);
  std::vector<int> count(5, 0);
  for (int f : fold) ++count[static_cast<std::size_t>(f)];
  EXPECT_EQ(count, (std::vector<int>{14, 8, 8, 8, 8}));
  EXPECT_EQ(fold, sceneFolds(scenes, 5));  // deterministic

  // Scenes interleaved in frame order, many random layouts: still whole.
  for (std::uint64_t trial = 0; trial < 50; ++trial) {
    std::vector<std::string> mixed;
    for (std::size_t i = 0; i < 40; ++i) {
      mixed.push_back("s" + std::to_string((i * 7 + trial * 13 + i * i * trial) % (3 + trial % 9)));
    }
    expectNoSceneSplit(mixed, sceneFolds(mixed, 5), 5);
  }
  // One frame per scene: folds as even as blocks.
  std::vector<std::string> singles;
  for (int i = 0; i < 10; ++i) singles.push_back(std::to_string(i));
  const auto single_folds = sceneFolds(singles, 5);
  std::vector<int> single_count(5, 0);
  for (int f : single_folds) ++single_count[static_cast<std::size_t>(f)];
  EXPECT_EQ(single_count, (std::vector<int>(5, 2)));
  EXPECT_THROW(sceneFolds(singles, 0), Error);
}

TEST(CvFolds, BlockFoldsAreContiguous) {
  EXPECT_EQ(blockFolds(7, 3), (std::vector<int>{0, 0, 0, 1, 1, 2, 2}));
  // Blocks split the shared frames' NYU 28..43 run across folds: the reason for scene folds.
  const auto scenes = nyuIndexRunScenes(kShared46, 2);
  const auto blocks = blockFolds(kShared46.size(), 5);
  std::set<int> folds_of_28;
  for (std::size_t i = 0; i < scenes.size(); ++i)
    if (scenes[i] == "nyu28") folds_of_28.insert(blocks[i]);
  EXPECT_GT(folds_of_28.size(), 1u);
}

TEST(CvFolds, TrainingSubsetIsReproducibleAndTakesWholeScenes) {
  // Scenes a (4 frames), b (3), c (2), d (1): frames 0..9.
  const std::vector<std::string> scenes = {"a", "a", "a", "a", "b", "b", "b", "c", "c", "d"};
  std::vector<std::size_t> all(scenes.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    for (int n = 1; n <= 10; ++n) {
      const auto chosen = chooseTrainingSubset(all, scenes, n, seed);
      ASSERT_EQ(chosen.size(), static_cast<std::size_t>(n));
      EXPECT_TRUE(std::is_sorted(chosen.begin(), chosen.end()));
      EXPECT_EQ(chosen, chooseTrainingSubset(all, scenes, n, seed));
      EXPECT_EQ(std::set<std::size_t>(chosen.begin(), chosen.end()).size(), chosen.size());
      // At most one scene is taken in part.
      std::map<std::string, int> taken;
      for (std::size_t i : chosen) ++taken[scenes[i]];
      int partial = 0;
      for (const auto& [scene, k] : taken) {
        const int size = static_cast<int>(std::count(scenes.begin(), scenes.end(), scene));
        partial += k < size ? 1 : 0;
      }
      EXPECT_LE(partial, 1) << "seed " << seed << " n " << n;
    }
  }
  // n = 3 can always be made of whole scenes (b, or c + d).
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    const auto chosen = chooseTrainingSubset(all, scenes, 3, seed);
    std::map<std::string, int> taken;
    for (std::size_t i : chosen) ++taken[scenes[i]];
    for (const auto& [scene, k] : taken) {
      EXPECT_EQ(k, std::count(scenes.begin(), scenes.end(), scene)) << "seed " << seed;
    }
  }
  // Different seeds choose differently (not always the same scenes).
  std::set<std::vector<std::size_t>> distinct;
  for (std::uint64_t seed = 0; seed < 20; ++seed)
    distinct.insert(chooseTrainingSubset(all, scenes, 4, seed));
  EXPECT_GT(distinct.size(), 1u);
  // Only candidates are chosen; all of them when n is large.
  const std::vector<std::size_t> some = {9, 0, 4, 5};
  const auto chosen = chooseTrainingSubset(some, scenes, 2, 3);
  for (std::size_t i : chosen) EXPECT_NE(std::find(some.begin(), some.end(), i), some.end());
  EXPECT_EQ(chooseTrainingSubset(some, scenes, 99, 3), (std::vector<std::size_t>{0, 4, 5, 9}));
  EXPECT_THROW(chooseTrainingSubset(some, scenes, 0, 3), Error);
}

TEST(CvFolds, LogTrendRecoversAKnownCurve) {
  const std::vector<double> x = {5, 10, 20, 30, 36};
  std::vector<double> y;
  for (double v : x) y.push_back(0.2 + 0.1 * std::log(v));
  const LogTrend fit = fitLogTrend(x, y);
  EXPECT_NEAR(fit.a, 0.2, 1e-12);
  EXPECT_NEAR(fit.b, 0.1, 1e-12);
  EXPECT_NEAR(fit.r2, 1.0, 1e-12);
  EXPECT_EQ(fit.points, 5);
  EXPECT_NEAR(fit.at(100), 0.2 + 0.1 * std::log(100.0), 1e-12);
  // Noise symmetric about the curve at each x leaves the fit unchanged; NaN skipped.
  std::vector<double> x2, y2;
  for (double v : x) {
    x2.insert(x2.end(), {v, v, v});
    y2.insert(y2.end(), {0.2 + 0.1 * std::log(v) + 0.03, 0.2 + 0.1 * std::log(v) - 0.03, NAN});
  }
  const LogTrend noisy = fitLogTrend(x2, y2);
  EXPECT_NEAR(noisy.a, 0.2, 1e-12);
  EXPECT_NEAR(noisy.b, 0.1, 1e-12);
  EXPECT_EQ(noisy.points, 10);
  EXPECT_LT(noisy.r2, 1.0);
  EXPECT_THROW(fitLogTrend({5, 5}, {0.1, 0.2}), Error);
  EXPECT_THROW(fitLogTrend({0, 5}, {0.1, 0.2}), Error);
  EXPECT_THROW(fitLogTrend({5}, {0.1, 0.2}), Error);
}

}  // namespace
}  // namespace findmug
