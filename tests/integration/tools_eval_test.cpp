// findmug-eval and findmug-train on the 31 real NYU Depth V2 frames.
//
// The accuracy bar: forest+MRF must beat the majority-class baseline (label
// every pixel "wall") by a wide margin. Measured with the defaults (organized
// oversegmenter) on the 14 frames that have a floor plane (BENCHMARKS.md):
// class average 0.478 against the baseline's 0.125, global 0.584 against 0.43
// (PCL supervoxels: 0.473 / 0.545). Class average is the
// metric a majority guess cannot fake, so its bar is high (baseline + 0.25,
// i.e. three times the baseline); global accuracy is dominated by walls, so
// its bar only asks for a clear gain (+0.05). Both leave about 0.06 of
// headroom for run-to-run differences of the randomized forest.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <regex>
#include <sstream>

#include "eval_json.hpp"
#include "run_command.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;

using test::readFile;
using test::RunResult;

RunResult run(const std::string& command) { return test::runCommand(command); }

// The object `"name": {...}` of the report, as text (objects are not nested
// beyond per_class/confusion, which come after the numbers we read).
std::string section(const std::string& json, const std::string& name) {
  const auto at = json.find("\"" + name + "\": {");
  if (at == std::string::npos) return "";
  return json.substr(at, json.find("\"confusion\"", at) - at);
}

double number(const std::string& text, const std::string& key) {
  std::smatch m;
  const std::regex re("\"" + key + "\": ([0-9.eE+-]+|null)");
  if (!std::regex_search(text, m, re) || m[1] == "null") return -1.0;
  return std::stod(m[1]);
}

std::vector<double> classTotals(const std::string& json) { return test::mrfClassTotals(json); }

TEST(ToolsEval, CrossValidationBeatsMajorityBaselineWidely) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  test::TempDir tmp;
  const auto result =
      run(std::string(FINDMUG_EVAL_EXE) + " --data " + nyu.string() +
          " --folds 5 --folds-by blocks --set ground.source=floor_labels --json " + tmp.str("eval.json") +
          " --out " + tmp.str("pictures"));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_THAT(result.output, HasSubstr("class avg"));

  const std::string json = readFile(tmp.path() / "eval.json");
  const std::string forest = section(json, "forest");
  const std::string mrf = section(json, "mrf");
  ASSERT_FALSE(forest.empty()) << json;
  ASSERT_FALSE(mrf.empty()) << json;
  const double mrf_class_avg = number(mrf, "class_average");
  const double mrf_global = number(mrf, "global");
  const double forest_class_avg = number(forest, "class_average");

  const auto totals = classTotals(json);
  ASSERT_EQ(totals.size(), 8u);
  const test::MajorityBaseline baseline = test::majorityBaseline(totals);
  const double baseline_global = baseline.global;            // everything labelled "wall"
  const double baseline_class_avg = baseline.class_average;  // one class right, the rest wrong
  RecordProperty("mrf_class_average", std::to_string(mrf_class_avg));
  RecordProperty("mrf_global", std::to_string(mrf_global));
  std::printf("baseline: class avg %.3f global %.3f; forest class avg %.3f; mrf %.3f / %.3f\n",
              baseline_class_avg, baseline_global, forest_class_avg, mrf_class_avg, mrf_global);
  EXPECT_GT(mrf_class_avg, baseline_class_avg + 0.25);
  EXPECT_GT(mrf_global, baseline_global + 0.05);
  EXPECT_GT(forest_class_avg, baseline_class_avg + 0.20);

  // The pictures a person looks at.
  EXPECT_TRUE(std::filesystem::exists(tmp.path() / "pictures" / "confusion_mrf.svg"));
  EXPECT_TRUE(std::filesystem::exists(tmp.path() / "pictures" / "confusion_forest.svg"));
  int overlays = 0;
  for (const auto& e : std::filesystem::directory_iterator(tmp.path() / "pictures" / "overlays")) {
    overlays += e.path().extension() == ".png";
  }
  const int used = static_cast<int>(number(json, "frames_used"));
  // The paper's protocol drops frames with too little floor: 14 of 31 remain.
  EXPECT_GE(used, 12);
  EXPECT_EQ(overlays, used);
}

// Issue 10: on all 31 frames (ground.source=gravity), the region features of
// the default model must beat today's 14-D pipeline on the same folds.
// Measured (perf-log §1d, commit of this test): 14-D forest+MRF class
// average 0.461, global 0.575; with features.regions 0.477 and 0.590, i.e.
// +0.016 and +0.015. The bars ask for +0.005 each: a third of the measured
// gain, so a broken region stage (no gain, or a loss) fails, while the
// randomized forest (deterministic per seed, but sensitive to any change of
// the features' floating point) keeps about a point of headroom.
TEST(ToolsEval, RegionFeaturesBeatTheFourteenDimensionalPipelineOnAllFrames) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(meta, "nyuv2_meta");
  test::TempDir tmp;
  // Features are compared under the argmax decision they were measured with
  // (tables.table_weight=1): the table weight (perf-log §1f) lifts the
  // 14-D pipeline's class average by a point and the regions' by none.
  const std::string common = std::string(FINDMUG_EVAL_EXE) + " --data " + nyu.string() +
                             " --folds 5 --folds-by blocks --set ground.source=gravity --set tables.table_weight=1" +
                             " --nyu-rotations " + (meta / "camera_rotations_NYU.txt").string();
  const auto base = run(common + " --set features.regions=false --json " + tmp.str("base.json"));
  ASSERT_EQ(base.exit_code, 0) << base.output;
  const auto regions = run(common + " --set features.regions=true --json " + tmp.str("regions.json"));
  ASSERT_EQ(regions.exit_code, 0) << regions.output;
  EXPECT_THAT(regions.output, HasSubstr("frames used 31 of 31"));
  const std::string base_mrf = section(readFile(tmp.path() / "base.json"), "mrf");
  const std::string regions_mrf = section(readFile(tmp.path() / "regions.json"), "mrf");
  const double base_class_avg = number(base_mrf, "class_average");
  const double base_global = number(base_mrf, "global");
  const double class_avg = number(regions_mrf, "class_average");
  const double global = number(regions_mrf, "global");
  std::printf("14-D: class avg %.3f global %.3f; +regions: class avg %.3f global %.3f\n",
              base_class_avg, base_global, class_avg, global);
  ASSERT_GT(base_class_avg, 0.0) << base_mrf;
  EXPECT_GT(class_avg, base_class_avg + 0.005);
  EXPECT_GT(global, base_global + 0.005);
}

// Issue 10, the configuration it shipped (daemon/findmugd.yaml then: regions and
// scene features): on all 31 frames it must beat region features alone on
// the same folds, and the oversegmentation's oracle must stay far above both.
// Measured (perf-log §1g, commit of this test), forest+MRF at the default
// seed: regions class average 0.477, global 0.590; + scene 0.478 and 0.627
// (+0.037 global). Over six forest seeds the global gain was 0.026 to 0.062
// and the class-average gain -0.001 to +0.036 (mean +0.019). So the bars:
// global +0.02 (a broken scene stage gives no gain), and class average not
// more than 0.01 below regions alone (no class traded for walls). Oracle:
// 0.952 / 0.960; a patch label or pixel mapping bug drops it.
TEST(ToolsEval, SceneFeaturesBeatRegionFeaturesOnAllFrames) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(meta, "nyuv2_meta");
  test::TempDir tmp;
  const std::string common = std::string(FINDMUG_EVAL_EXE) + " --data " + nyu.string() +
                             " --folds 5 --folds-by blocks --set ground.source=gravity --nyu-rotations " +
                             (meta / "camera_rotations_NYU.txt").string() +
                             " --set features.regions=true";
  const auto regions =
      run(common + " --set features.scene=false --json " + tmp.str("regions.json"));
  ASSERT_EQ(regions.exit_code, 0) << regions.output;
  const auto scene = run(common + " --set features.scene=true --json " + tmp.str("scene.json"));
  ASSERT_EQ(scene.exit_code, 0) << scene.output;
  EXPECT_THAT(scene.output, HasSubstr("frames used 31 of 31"));
  EXPECT_THAT(scene.output, HasSubstr("+MRF confusion"));
  const std::string regions_json = readFile(tmp.path() / "regions.json");
  const std::string scene_json = readFile(tmp.path() / "scene.json");
  const std::string regions_mrf = section(regions_json, "mrf");
  const std::string scene_mrf = section(scene_json, "mrf");
  const double base_class_avg = number(regions_mrf, "class_average");
  const double base_global = number(regions_mrf, "global");
  const double class_avg = number(scene_mrf, "class_average");
  const double global = number(scene_mrf, "global");
  std::printf("regions: class avg %.3f global %.3f; +scene: class avg %.3f global %.3f\n",
              base_class_avg, base_global, class_avg, global);
  ASSERT_GT(base_global, 0.0) << regions_mrf;
  EXPECT_GT(global, base_global + 0.02);
  EXPECT_GT(class_avg, base_class_avg - 0.01);

  // The oracle does not depend on the forest: the same in both runs.
  const std::string oracle = section(scene_json, "oracle");
  EXPECT_EQ(oracle, section(regions_json, "oracle"));
  EXPECT_GT(number(oracle, "class_average"), 0.9) << oracle;
  EXPECT_GT(number(oracle, "global"), 0.9) << oracle;
  EXPECT_GT(number(oracle, "global"), global + 0.2);
}

TEST(ToolsEval, TrainThenEvaluateModel) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  test::TempDir tmp;
  const auto model = tmp.str("nyu.fmf");
  const auto trained = run(std::string(FINDMUG_TRAIN_EXE) + " --data " + nyu.string() +
                           " --set ground.source=floor_labels --out " + model);
  ASSERT_EQ(trained.exit_code, 0) << trained.output;
  EXPECT_THAT(trained.output, HasSubstr("training patches"));
  ASSERT_TRUE(std::filesystem::exists(model));

  const auto evaluated =
      run(std::string(FINDMUG_EVAL_EXE) + " --data " + nyu.string() + " --model " + model +
          " --set ground.source=floor_labels --json " + tmp.str("eval.json"));
  ASSERT_EQ(evaluated.exit_code, 0) << evaluated.output;
  const std::string json = readFile(tmp.path() / "eval.json");
  // Evaluated on its own training frames it must fit them well.
  EXPECT_GT(number(section(json, "mrf"), "global"), 0.75) << json;
}

// ground.source=gravity with NYU's rotations: all 31 frames are used, each
// with the way its ground was obtained, and tables are measured as objects.
TEST(ToolsEval, GravityGroundUsesEveryFrameAndTablesAreMeasured) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(rotations, "nyuv2_meta/camera_rotations_NYU.txt");
  test::TempDir tmp;
  const auto result = run(std::string(FINDMUG_EVAL_EXE) + " --data " + nyu.string() +
                          " --folds 5 --folds-by blocks --set ground.source=gravity --nyu-rotations " +
                          rotations.string() + " --json " + tmp.str("eval.json"));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_THAT(result.output, HasSubstr("frames used 31 of 31"));
  EXPECT_THAT(result.output, HasSubstr("ground gravity+floor_labels: 0001"));
  EXPECT_THAT(result.output, HasSubstr("table instances"));
  const std::string json = readFile(tmp.path() / "eval.json");
  EXPECT_EQ(number(json, "frames_used"), 31);
  // One "ground" entry per frame; the labelled floor wherever it is large.
  const std::regex entry(R"re(\{"frame": "(\d+)", "method": "([a-z_+]+)"\})re");
  int entries = 0, from_floor = 0;
  for (std::sregex_iterator it(json.begin(), json.end(), entry), end; it != end; ++it) {
    ++entries;
    from_floor += (*it)[2] == "gravity+floor_labels";
    EXPECT_THAT((*it)[2].str(), ::testing::StartsWith("gravity+")) << (*it)[1];
  }
  EXPECT_EQ(entries, 31);
  EXPECT_GE(from_floor, 12);
  // Table instances: the 31 frames hold ground-truth tables; the report
  // counts them and gives precision and recall as numbers.
  const auto at = json.find("\"table_instances\": {");
  ASSERT_NE(at, std::string::npos) << json;
  const std::string tables = json.substr(at, json.find('[', at) - at);
  EXPECT_GE(number(tables, "truth"), 10) << tables;
  EXPECT_GE(number(tables, "detected"), 1) << tables;
  EXPECT_GE(number(tables, "precision"), 0.0) << tables;
  EXPECT_GE(number(tables, "recall"), 0.0) << tables;
  EXPECT_LE(number(tables, "recall"), 1.0) << tables;
  // The table-top candidates on the detected tables, and the labels with their table
  // pixels relabelled Object: only Table pixels become Object, so the object class can
  // only gain and the table class only lose.
  const std::string relabel = section(json, "table_objects_relabel");
  ASSERT_FALSE(relabel.empty()) << json;
  EXPECT_EQ(number(relabel, "frames"), 31) << relabel;
  EXPECT_GE(number(relabel, "candidates"), 1) << relabel;
  EXPECT_GE(number(relabel, "pixels_changed"), 1) << relabel;
  const auto pair = [&](const std::string& key) {
    std::smatch m;
    const std::regex re("\"" + key + "\": \\[([0-9.eE+-]+), ([0-9.eE+-]+)\\]");
    if (!std::regex_search(relabel, m, re)) return std::make_pair(-1.0, -1.0);
    return std::make_pair(std::stod(m[1]), std::stod(m[2]));
  };
  const auto object = pair("object"), table = pair("table");
  EXPECT_GT(object.first, 0.0) << relabel;
  EXPECT_GT(object.second, object.first) << relabel;
  EXPECT_LE(table.second, table.first) << relabel;
  EXPECT_GE(table.second, 0.0) << relabel;
  // What becomes "table", by true NYU-40 class (label40/): every frame has its label40
  // image, and the NYU-40 class "table" is among the classes labelled table.
  const auto by_class = json.find("\"table_by_nyu40\": {");
  ASSERT_NE(by_class, std::string::npos) << json;
  const std::string nyu40 = json.substr(by_class, json.find(']', by_class) - by_class);
  EXPECT_EQ(number(nyu40, "frames"), 31) << nyu40;
  std::smatch m;
  const std::regex table_entry(
      R"re(\{"class": "table", "pixels": (\d+), "labelled_table": (\d+)\})re");
  ASSERT_TRUE(std::regex_search(nyu40, m, table_entry)) << nyu40;
  EXPECT_GT(std::stoull(m[2]), 0u) << nyu40;
  EXPECT_LE(std::stoull(m[2]), std::stoull(m[1])) << nyu40;
  EXPECT_THAT(result.output, HasSubstr("pixels labelled table, by true NYU-40 class"));
}

// Issue 10, tables as objects (perf-log §1f): on all 31 frames with the
// shipped model's settings (region features), today's table decisions
// (tables.table_weight=1: argmax of the MRF; no visible-top or horizontal
// filter) against the defaults (table_weight 1.5, min_top_area_m2 0.15,
// min_horizontal_share 0.2), same folds and forests. Measured at the commit
// of this test: table pixel accuracy 0.358 -> 0.512, table instances 34
// detected / 3 matched (precision 0.088, recall 0.125) -> 13 / 4 (0.308,
// 0.167). One match moves recall by 0.042, so the bars are: table accuracy
// +0.08 and precision +0.1 (about half of each gain), recall not lower.
// Without the weight table accuracy stays 0.358; without the filters
// precision is 0.075.
TEST(ToolsEval, TableDecisionsBeatArgmaxTablesOnAllFrames) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(meta, "nyuv2_meta");
  test::TempDir tmp;
  const std::string common = std::string(FINDMUG_EVAL_EXE) + " --data " + nyu.string() +
                             " --folds 5 --folds-by blocks --set ground.source=gravity --set features.regions=true" +
                             " --nyu-rotations " + (meta / "camera_rotations_NYU.txt").string();
  const auto before = run(common + " --set tables.table_weight=1 --set tables.min_top_area_m2=0" +
                          " --set tables.min_horizontal_share=0 --json " + tmp.str("before.json"));
  ASSERT_EQ(before.exit_code, 0) << before.output;
  const auto after = run(common + " --json " + tmp.str("after.json") + " --table-report " +
                         tmp.str("tables.txt"));
  ASSERT_EQ(after.exit_code, 0) << after.output;
  EXPECT_THAT(after.output, HasSubstr("at precision >= 80 %"));
  auto figures = [](const std::string& json) {
    const auto at = json.find("\"table_instances\": {");
    const std::string tables = json.substr(at, json.find('[', at) - at);
    const auto per_class = json.find("\"per_class\"", json.find("\"mrf\": {"));
    return std::array<double, 3>{number(json.substr(per_class), "table"),
                                 number(tables, "precision"), number(tables, "recall")};
  };
  const auto b = figures(readFile(tmp.path() / "before.json"));
  const auto a = figures(readFile(tmp.path() / "after.json"));
  std::printf("table accuracy %.3f -> %.3f, instance precision %.3f -> %.3f, recall %.3f -> %.3f\n",
              b[0], a[0], b[1], a[1], b[2], a[2]);
  ASSERT_GT(b[0], 0.0);
  EXPECT_GT(a[0], b[0] + 0.08);
  EXPECT_GT(a[1], b[1] + 0.1);
  EXPECT_GE(a[2], b[2]);
  // The diagnosis names a reason for every true instance and detection.
  const std::string report = readFile(tmp.path() / "tables.txt");
  EXPECT_THAT(report, HasSubstr("summary over all frames"));
  EXPECT_THAT(report, HasSubstr("frame 0039:"));
  EXPECT_THAT(report, HasSubstr("-> matched"));
  EXPECT_THAT(report, HasSubstr("-> labelled object"));
  // The JSON carries the precision/recall curve over the confidence threshold.
  const std::string json = readFile(tmp.path() / "after.json");
  EXPECT_THAT(json, HasSubstr("\"precision_recall\": [{\"min_confidence\": "));
  EXPECT_THAT(json, HasSubstr("\"operating_points\": [{\"min_precision\": 0.8"));
}

// A synthetic sequence with exact table truth: a model trained on it finds
// its tables, and the search positions are compared with the true tables'.
TEST(ToolsEval, SyntheticSearchPositionsAgainstTruth) {
  test::TempDir tmp;
  const auto synth = run(std::string(FINDMUG_SYNTH_EXE) + " --seed 11 --frames 8 --fps 1 --out " +
                         tmp.str("synth"));
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  const auto model = tmp.str("synth.fmf");
  const auto trained =
      run(std::string(FINDMUG_TRAIN_EXE) + " --data " + tmp.str("synth") + " --out " + model);
  ASSERT_EQ(trained.exit_code, 0) << trained.output;
  EXPECT_THAT(trained.output, HasSubstr("extrinsics"));  // how each frame's ground was obtained
  const auto evaluated = run(std::string(FINDMUG_EVAL_EXE) + " --data " + tmp.str("synth") +
                             " --model " + model + " --json " + tmp.str("eval.json"));
  ASSERT_EQ(evaluated.exit_code, 0) << evaluated.output;
  EXPECT_THAT(evaluated.output, HasSubstr("search positions vs true tables"));
  const std::string json = readFile(tmp.path() / "eval.json");
  const auto at = json.find("\"search_positions\": {");
  ASSERT_NE(at, std::string::npos) << json;
  const std::string search = json.substr(at, json.find('}', at) - at);
  EXPECT_GE(number(search, "predicted"), 4) << search;
  const double share = number(search, "reachable_share");
  EXPECT_GE(share, 0.0) << search;
  EXPECT_LE(share, 1.0) << search;
  // Evaluated on its own training frames the model labels tables well, so
  // its positions lie near the true ones.
  EXPECT_LT(number(search, "median_position_error_m"), 0.5) << search;
  const auto t = json.find("\"table_instances\": {");
  ASSERT_NE(t, std::string::npos);
  const std::string tables = json.substr(t, json.find('[', t) - t);
  EXPECT_GE(number(tables, "recall"), 0.5) << tables;
}

TEST(ToolsEval, BadInputIsNamed) {
  test::TempDir tmp;
  auto r = run(std::string(FINDMUG_EVAL_EXE) + " --data /nonexistent/dataset");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output, HasSubstr("/nonexistent/dataset"));

  r = run(std::string(FINDMUG_EVAL_EXE) + " --data /tmp --folds 1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output, HasSubstr("--folds"));

  r = run(std::string(FINDMUG_EVAL_EXE) + " --data /tmp --bogus 3");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output, HasSubstr("--bogus"));

  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  std::ofstream(tmp.str("corrupt.fmf")) << "FMUGFRST garbage that is no model";
  r = run(std::string(FINDMUG_EVAL_EXE) + " --data " + nyu.string() + " --model " +
          tmp.str("corrupt.fmf"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output, HasSubstr("corrupt.fmf"));

  r = run(std::string(FINDMUG_TRAIN_EXE) + " --data " + nyu.string() + " --out " +
          tmp.str("m.fmf") + " --set forest.num_trees=0");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.output, HasSubstr("forest.num_trees"));
}

}  // namespace
}  // namespace findmug

namespace findmug {
namespace {

// The true table instances do not depend on the tables.* settings being
// evaluated (they are clustered with the built-in ones): a finer cluster
// tolerance changes the detections only, so a sweep compares like with like.
TEST(ToolsEval, TableTruthDoesNotMoveWithTheEvaluatedTableSettings) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(rotations, "nyuv2_meta/camera_rotations_NYU.txt");
  test::TempDir tmp;
  const std::string common = " --data " + nyu.string() +
                             " --set ground.source=gravity --nyu-rotations " + rotations.string() +
                             " --folds 2 --set forest.num_trees=4";
  auto evaluate = [&](const std::string& flags, const std::string& json) {
    const auto r = run(std::string(FINDMUG_EVAL_EXE) + common + flags + " --json " + tmp.str(json));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return readFile(tmp.path() / json);
  };
  const std::string shipped = evaluate("", "shipped.json");
  const std::string fine = evaluate(" --set tables.cluster_tolerance_m=0.02", "fine.json");
  const double truth = number(section(shipped, "table_instances"), "truth");
  EXPECT_GT(truth, 10);
  EXPECT_EQ(number(section(fine, "table_instances"), "truth"), truth);
  EXPECT_EQ(number(section(fine, "searchable_tables"), "truth"),
            number(section(shipped, "searchable_tables"), "truth"));
  // ... while the detections do move (the comparison can see a difference).
  EXPECT_NE(number(section(fine, "table_instances"), "detected"),
            number(section(shipped, "table_instances"), "detected"));
}

// findmug-eval --degrade (issue 35, item 9): a model evaluated on raw-like
// copies of five NYU frames. The same ground-truth pixels are scored; with
// labels.fill_holes off the holes count as unlabelled, so global accuracy
// drops, and filling them from their neighbours (the default) wins part of
// that back; with --score-labelled-only the holes leave the count instead.
TEST(ToolsEval, DegradeEvaluatesRawLikeCopies) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  FINDMUG_REQUIRE_DATA(rotations, "nyuv2_meta/camera_rotations_NYU.txt");
  test::TempDir tmp;
  for (const char* sub : {"rgb", "depth", "label8"}) {
    std::filesystem::create_directories(tmp.path() / "data" / sub);
    for (const char* frame : {"0001", "0002", "0009", "0014", "0015"})
      std::filesystem::create_symlink(nyu / sub / (std::string(frame) + ".png"),
                                      tmp.path() / "data" / sub / (std::string(frame) + ".png"));
  }
  const std::string common = " --data " + tmp.str("data") +
                             " --set ground.source=gravity --nyu-rotations " +
                             rotations.string();
  const auto model = tmp.str("five.fmf");
  const auto trained = run(std::string(FINDMUG_TRAIN_EXE) + common + " --out " + model);
  ASSERT_EQ(trained.exit_code, 0) << trained.output;
  auto evaluate = [&](const std::string& flags, const std::string& json) {
    const auto r = run(std::string(FINDMUG_EVAL_EXE) + common + " --model " + model + flags +
                       " --json " + tmp.str(json));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return readFile(tmp.path() / json);
  };
  auto scored = [](const std::string& json) {
    double all = 0;
    for (double t : classTotals(json)) all += t;
    return all;
  };
  const std::string clean = evaluate("", "clean.json");
  const std::string raw = evaluate(" --degrade", "raw.json");
  const std::string raw_again = evaluate(" --degrade", "raw_again.json");
  const std::string measured = evaluate(" --degrade --score-labelled-only", "measured.json");
  const std::string other_seed = evaluate(" --degrade --degrade-seed 2", "other_seed.json");
  EXPECT_THAT(raw, HasSubstr("raw-like depth, seed 1"));
  EXPECT_EQ(number(raw, "frames_used"), 5);
  EXPECT_EQ(scored(raw), scored(clean));
  const std::string unfilled =
      evaluate(" --degrade --set labels.fill_holes=false", "unfilled.json");
  EXPECT_EQ(scored(unfilled), scored(clean));
  EXPECT_LT(number(section(unfilled, "mrf"), "global"),
            number(section(clean, "mrf"), "global") - 0.02);
  EXPECT_GT(number(section(raw, "mrf"), "global"),
            number(section(unfilled, "mrf"), "global") + 0.01);
  EXPECT_EQ(section(raw, "mrf"), section(raw_again, "mrf"));  // deterministic for a seed
  EXPECT_NE(section(raw, "mrf"), section(other_seed, "mrf"));
  EXPECT_LT(scored(measured), 0.97 * scored(raw));
  EXPECT_GT(number(section(measured, "mrf"), "global"), number(section(unfilled, "mrf"), "global"));
}

}  // namespace
}  // namespace findmug
