// findmug-eval's evaluation protocol on the 46 shared NYU frames
// (nyuv2_labeled + nyuv2_labeled_extra, two --data folders): scene folds that
// never split a scene, the paper's features plus regions and scene well above the
// majority baseline, searchable tables reported, a small learning curve written,
// and the shipped settings (daemon/findmugd.yaml: NYU-13 classes, object
// features, 16 trees) above the configurations shipped before them (issue 35).
//
// Bars (docs/measurements/eval-protocol.md, 5-fold scene CV, forest seeds 42 / 1042 /
// 2042; this test runs the default seed 42): see kClassAverageMargin and kGlobalMargin.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "eval_json.hpp"
#include "findmug/settings/config.hpp"
#include "findmug/settings/settings.hpp"
#include "findmug_cli.hpp"
#include "run_command.hpp"
#include "shipped_model.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;

// Measured with scene folds from NYU's split (docs/measurements/eval-protocol.md):
// forest+MRF class average 0.487 / 0.487 / 0.492 for forest seeds 42 / 1042 /
// 2042 against the majority baseline's 0.125 (8 classes present), global
// 0.578 / 0.580 / 0.582 against 0.447 (every pixel "wall"). The bars ask for
// baseline + 0.30 and + 0.08: about 0.05 below the figures, ten times their
// spread over seeds, so a change that loses 0.05 (a broken feature, forest or
// training split) fails, not a seed.
constexpr double kClassAverageMargin = 0.30;
constexpr double kGlobalMargin = 0.08;

using test::readFile;
using test::RunResult;

RunResult run(const std::string& command) { return test::runCommand(command); }

double number(const std::string& text, const std::string& key, std::size_t from = 0) {
  std::smatch m;
  const std::regex re("\"" + key + "\": ([0-9.eE+-]+|null)");
  const std::string rest = text.substr(from);
  if (!std::regex_search(rest, m, re) || m[1] == "null") return -1.0;
  return std::stod(m[1]);
}

TEST(EvalProtocol, SceneFoldsOverBothSharedFoldersBeatTheBaselineWidely) {
  FINDMUG_REQUIRE_DATA(labeled, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(extra, "nyuv2_labeled_extra");
  FINDMUG_REQUIRE_DATA(rotations, "nyuv2_meta/camera_rotations_NYU.txt");
  FINDMUG_REQUIRE_DATA(split, "nyuv2_meta/split_test_indices.txt");
  test::TempDir tmp;
  const auto result = run(
      std::string(FINDMUG_EVAL_EXE) + " --data " + labeled.string() + " --data " +
      extra.string() + " --folds 5 --set ground.source=gravity --nyu-rotations " +
      rotations.string() + " --nyu-split " + split.string() +
      " --set features.regions=true --set features.scene=true --json " +
      tmp.str("eval.json") + " --learning-curve " + tmp.str("curve") +
      " --curve-sizes 5,10 --curve-seeds 1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_THAT(result.output, HasSubstr("searchable tables"));
  const std::string json = readFile(tmp.path() / "eval.json");
  EXPECT_EQ(number(json, "frames_used"), 46.0);
  EXPECT_THAT(json, HasSubstr("\"folds\": {\"rule\": \"scenes\", \"nyu_scenes\": \"runs of NYU's "
                              "train/test split"));

  // Every test frame once, every scene in exactly one fold.
  const std::regex fold_re(R"re(\{"fold": (\d+), "train_frames": (\d+), "test": \[([^\]]*)\])re");
  const std::regex entry_re(R"re(\{"frame": "([^"]+)", "scene": "([^"]+)"\})re");
  std::map<std::string, std::set<int>> folds_of_scene;
  std::map<std::string, std::string> scene_of;
  std::map<std::string, int> fold_of;
  int folds = 0;
  for (std::sregex_iterator f(json.begin(), json.end(), fold_re), end; f != end; ++f) {
    ++folds;
    const int fold = std::stoi((*f)[1]);
    const int train = std::stoi((*f)[2]);
    const std::string tests = (*f)[3];
    int test_count = 0;
    for (std::sregex_iterator e(tests.begin(), tests.end(), entry_re); e != end; ++e) {
      ++test_count;
      EXPECT_EQ(fold_of.count((*e)[1]), 0u) << (*e)[1] << " tested twice";
      fold_of[(*e)[1]] = fold;
      scene_of[(*e)[1]] = (*e)[2];
      folds_of_scene[(*e)[2]].insert(fold);
    }
    EXPECT_EQ(train + test_count, 46) << "fold " << fold;
  }
  EXPECT_EQ(folds, 5);
  EXPECT_EQ(fold_of.size(), 46u);
  for (const auto& [scene, in] : folds_of_scene) EXPECT_EQ(in.size(), 1u) << "scene " << scene;
  // NYU 28 (nyuv2_labeled) and 29 (nyuv2_labeled_extra) are one scene across the folders;
  // 1 and 2 one scene; 433 its own.
  EXPECT_EQ(scene_of["0028"], scene_of["0029"]);
  EXPECT_EQ(fold_of["0028"], fold_of["0029"]);
  EXPECT_EQ(scene_of["0001"], scene_of["0002"]);
  EXPECT_NE(scene_of["0433"], scene_of["0125"]);
  // 58 is an NYU train index: 56-57 and 59-63 are two rooms; 60 and 63 one.
  EXPECT_NE(scene_of["0057"], scene_of["0059"]);
  EXPECT_EQ(scene_of["0060"], scene_of["0063"]);

  // Accuracy against the majority baseline from the confusion's rows.
  const auto mrf_at = json.find("\"mrf\": {");
  ASSERT_NE(mrf_at, std::string::npos);
  const double class_average = number(json, "class_average", mrf_at);
  const double global = number(json, "global", mrf_at);
  const std::vector<double> totals = test::mrfClassTotals(json);
  ASSERT_EQ(totals.size(), 8u);
  const test::MajorityBaseline baseline = test::majorityBaseline(totals);
  std::printf("scene CV: class avg %.3f (baseline %.3f), global %.3f (baseline %.3f)\n",
              class_average, baseline.class_average, global, baseline.global);
  EXPECT_GT(class_average, baseline.class_average + kClassAverageMargin);
  EXPECT_GT(global, baseline.global + kGlobalMargin);

  // Searchable tables: the 46 frames hold some; the figures are reported.
  const auto searchable_at = json.find("\"searchable_tables\": {");
  ASSERT_NE(searchable_at, std::string::npos);
  EXPECT_EQ(number(json, "frames", searchable_at), 46.0);
  EXPECT_GT(number(json, "truth", searchable_at), 5.0);
  EXPECT_GE(number(json, "false_table_frame_share", searchable_at), 0.0);

  // The learning curve: one row per size, N as asked, a trend per figure, the plot.
  const std::string csv = readFile(tmp.path() / "curve" / "learning_curve.csv");
  std::vector<std::string> lines;
  std::stringstream in(csv);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 3u) << csv;
  EXPECT_EQ(lines[1].rfind("5,5.000000,0,42,", 0), 0u) << lines[1];
  EXPECT_EQ(lines[2].rfind("10,10.000000,0,42,", 0), 0u) << lines[2];
  const std::string trend = readFile(tmp.path() / "curve" / "learning_curve_trend.csv");
  EXPECT_THAT(trend, HasSubstr("class_average,"));
  const std::string svg = readFile(tmp.path() / "curve" / "learning_curve.svg");
  EXPECT_THAT(svg, HasSubstr("ln N"));
}

TEST(EvalProtocol, AFrameNameInTwoFoldersIsRefusedNamingIt) {
  FINDMUG_REQUIRE_DATA(labeled, "nyuv2_labeled");
  const auto result = run(std::string(FINDMUG_EVAL_EXE) + " --data " + labeled.string() +
                          " --data " + labeled.string() + " --folds 5");
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_THAT(result.output, HasSubstr("frame name(s) in more than one input"));
  EXPECT_THAT(result.output, HasSubstr("0001 (" + labeled.string()));
  const auto train = run(std::string(FINDMUG_TRAIN_EXE) + " --data " + labeled.string() +
                         " --data " + labeled.string() + " --out /dev/null");
  EXPECT_EQ(train.exit_code, 1) << train.output;
  EXPECT_THAT(train.output, HasSubstr("0028 (" + labeled.string()));
}

// Issue 35: the settings daemon/findmugd.yaml ships (what models/findmug.fmf is
// trained with) beat the configurations shipped before them on the same scene
// folds. Measured (forest seeds 42 / 1042 / 2042, forest+MRF):
//   before issue 35 (regions + scene, 8 labels, 8 trees; docs/measurements/
//           shipped-nyu13-objects.md): class average 0.487 / 0.487 / 0.492,
//           chair 0.109 / 0.132 / 0.198 (mean 0.146), global 0.578 / 0.580 / 0.582;
//   NYU-13 classes + object features, 8 trees (shipped until h-depth35):
//           class average 0.499 / 0.498 / 0.497, chair 0.177 / 0.212 / 0.203,
//           global 0.580 / 0.575 / 0.577;
//   shipped, the same with 16 trees (docs/measurements/forest-size.md): class average
//           0.511 / 0.511 / 0.521 (mean 0.514, spread 0.010), chair 0.162 /
//           0.157 / 0.163 (mean 0.160, spread 0.006), global 0.592 / 0.592 /
//           0.608 (mean 0.597, spread 0.016);
//   shipped, the same with mrf.object_consistency 0.5 (docs/measurements/
//           object-stage.md): class average 0.516 / 0.517 / 0.523, chair 0.157 /
//           0.148 / 0.162, global 0.592 / 0.596 / 0.609 (higher class average on
//           12 of 12 seeds than without it, by 0.001-0.008: below any bar's resolution,
//           so the bars below stay those of 16 trees);
//   shipped, the same with features.objects_columns relations and forest.shrinkage 20
//           (BENCHMARKS.md section 1): class average 0.517 / 0.520 / 0.525, chair
//           0.163 / 0.244 / 0.278, global 0.593 / 0.589 / 0.592 (over 24 seeds
//           class average +0.015, higher on 23, chair +0.088 on all 24, global
//           -0.005; seed 42 gains least, so the bars stay);
//   shipped, the same with cloud.fill_depth_max_run_px 40: class average 0.530 /
//           0.505 / 0.509, chair 0.180 / 0.176 / 0.202, global 0.600 / 0.582 / 0.585
//           (over 24 seeds class average -0.005 on the filled frames, table pixels
//           +0.115 on the raw-like copies; seed 42 stays above every bar);
//   shipped, the same with mrf.pairwise context (BENCHMARKS.md section 1): class average
//           0.530 / 0.503 / 0.517, chair 0.156 / 0.167 / 0.203, global 0.605 / 0.585 /
//           0.593 (over 12 seeds class average +0.004, higher on 10, global +0.005
//           on all 12).
// Bars: the 16-tree mean minus its seed spread. The class-average bar is above
// every seed of both earlier configurations and the global bar above both their
// means, so either of them fails here (seed 42); the chair bar is above the
// first's mean only (16 trees lose 3.7 points of chair against 8: no bar guards
// the 8-tree chair figure). Table pixels (0.521 mean, spread 0.067) get no bar.
// One seed (42), the full forest: about 30 s wall.
constexpr double kShippedClassAverageBar = 0.514 - 0.010;
constexpr double kShippedChairBar = 0.160 - 0.006;
constexpr double kShippedGlobalBar = 0.597 - 0.016;
const char* const kShippedSettings[] = {"features.regions=true",
                                        "features.scene=true",
                                        "learner.classes=nyu13",
                                        "features.objects=true",
                                        "features.objects_columns=relations",
                                        "forest.num_trees=16",
                                        "forest.shrinkage=20",
                                        "mrf.object_consistency=0.5",
                                        "mrf.pairwise=context",
                                        "cloud.fill_depth_max_run_px=40"};

// The settings the next test evaluates are the shipped file's with the settings the
// shipped model records (which the file leaves to the model): applying them to it changes
// nothing, and they are all it changes from the built-in defaults.
TEST(EvalProtocol, ShippedSettingsAreTheShippedFiles) {
  // Read as findmug-eval reads it: the segmenter's sections bound, the others checked.
  const std::string path = (test::sourceDir() / "daemon" / "findmugd.yaml").string();
  cli::ConfigFlags flags;
  flags.config_path = path;
  Config shipped = cli::configFrom(flags);
  shipped.segmenter = configForModel(shipped.segmenter, *test::shippedModel());
  Config again = shipped;
  for (const char* setting : kShippedSettings) applyOverride(again, setting);
  EXPECT_EQ(dumpConfig(again), dumpConfig(shipped))
      << path << " does not hold the settings this test evaluates";
  Config defaults_and_settings;
  for (const char* setting : kShippedSettings) applyOverride(defaults_and_settings, setting);
  // A stream setting: a camera's ground is fitted again every 30 frames. The evaluation's
  // frames are separate scenes, each fitted on its own, so it cannot move a figure.
  applyOverride(defaults_and_settings, "ground.reestimate_every_frames=30");
  EXPECT_EQ(dumpConfig(defaults_and_settings), dumpConfig(shipped))
      << path << " changes a setting this test does not evaluate";
  Config before = shipped;
  applyOverride(before, "learner.classes=labels");
  EXPECT_NE(dumpConfig(before), dumpConfig(shipped));  // the comparison can see a difference
  Config eight_trees = shipped;
  applyOverride(eight_trees, "forest.num_trees=8");
  EXPECT_NE(dumpConfig(eight_trees), dumpConfig(shipped));
  Config paper_unaries = shipped;
  applyOverride(paper_unaries, "mrf.object_consistency=0");
  EXPECT_NE(dumpConfig(paper_unaries), dumpConfig(shipped));
  Config raw_gaps = shipped;
  applyOverride(raw_gaps, "cloud.fill_depth_max_run_px=0");
  EXPECT_NE(dumpConfig(raw_gaps), dumpConfig(shipped));
  Config paper_leaves = shipped;
  applyOverride(paper_leaves, "forest.shrinkage=0");
  EXPECT_NE(dumpConfig(paper_leaves), dumpConfig(shipped));
  Config paper_pairwise = shipped;
  applyOverride(paper_pairwise, "mrf.pairwise=potts");
  EXPECT_NE(dumpConfig(paper_pairwise), dumpConfig(shipped));
}

// Issue 35's bound for raw-like depth: at most 5 points below the filled frames.
constexpr double kRawDepthMaxLoss = 0.05;
// Table pixels on the raw-like copies with the short depth gaps filled
// (cloud.fill_depth_max_run_px 40; docs/measurements/depth-holes.md): seed 42
// 0.604, without the fill 0.474; over 24 seeds 0.487-0.707 with it, 0.344-0.572
// (22 of 24 below this bar) without.
constexpr double kRawDepthTableBar = 0.55;

TEST(EvalProtocol, ShippedSettingsBeatTheEarlierConfigurationOnSceneFolds) {
  FINDMUG_REQUIRE_DATA(labeled, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(extra, "nyuv2_labeled_extra");
  FINDMUG_REQUIRE_DATA(rotations, "nyuv2_meta/camera_rotations_NYU.txt");
  FINDMUG_REQUIRE_DATA(split, "nyuv2_meta/split_test_indices.txt");
  test::TempDir tmp;
  std::string settings;
  for (const char* setting : kShippedSettings) settings += std::string(" --set ") + setting;
  // Scene CV of the shipped settings, seed 42, with `flags`: the report's text.
  const auto evaluate = [&](const std::string& flags, const std::string& name) {
    const auto result =
        run(std::string(FINDMUG_EVAL_EXE) + " --data " + labeled.string() + " --data " +
            extra.string() + " --folds 5 --set ground.source=gravity --nyu-rotations " +
            rotations.string() + " --nyu-split " + split.string() + settings +
            " --set forest.seed=42" + flags + " --json " + tmp.str(name));
    EXPECT_EQ(result.exit_code, 0) << result.output;
    return readFile(tmp.path() / name);
  };
  const std::string json = evaluate("", "eval.json");
  EXPECT_EQ(number(json, "frames_used"), 46.0);
  const auto mrf_at = json.find("\"mrf\": {");
  ASSERT_NE(mrf_at, std::string::npos);
  const double class_average = number(json, "class_average", mrf_at);
  const double global = number(json, "global", mrf_at);
  const auto per_class_at = json.find("\"per_class\": {", mrf_at);
  ASSERT_NE(per_class_at, std::string::npos);
  const double chair = number(json, "chair", per_class_at);
  std::printf("shipped settings, scene CV, seed 42: class avg %.3f (bar %.3f), chair %.3f "
              "(bar %.3f), global %.3f (bar %.3f)\n",
              class_average, kShippedClassAverageBar, chair, kShippedChairBar, global,
              kShippedGlobalBar);
  EXPECT_GE(class_average, kShippedClassAverageBar);
  EXPECT_GE(chair, kShippedChairBar);
  EXPECT_GE(global, kShippedGlobalBar);

  // The same frames as a raw Kinect gives them (--degrade): within the issue's
  // 5 points, since the holes take their neighbours' labels (labels.fill_holes;
  // docs/measurements/label-holes.md: 0.7 / 0.1 lower for seed 42, 6.0 / 6.0
  // without the fill).
  const std::string raw_json = evaluate(" --degrade", "raw.json");
  const auto raw_mrf_at = raw_json.find("\"mrf\": {");
  ASSERT_NE(raw_mrf_at, std::string::npos);
  const double raw_class_average = number(raw_json, "class_average", raw_mrf_at);
  const double raw_global = number(raw_json, "global", raw_mrf_at);
  const auto raw_per_class_at = raw_json.find("\"per_class\": {", raw_mrf_at);
  ASSERT_NE(raw_per_class_at, std::string::npos);
  const double raw_table = number(raw_json, "table", raw_per_class_at);
  std::printf("raw-like copies: class avg %.3f, global %.3f, table %.3f (bar %.3f)\n",
              raw_class_average, raw_global, raw_table, kRawDepthTableBar);
  EXPECT_GE(raw_table, kRawDepthTableBar);
  EXPECT_GE(raw_class_average, class_average - kRawDepthMaxLoss);
  EXPECT_GE(raw_global, global - kRawDepthMaxLoss);
}

}  // namespace
}  // namespace findmug
