// findmug-learn-layout on real NYU label maps: a few of the 654 test maps,
// the maps of the evaluation frames' scenes left out, and a prior that the
// MRF can load.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "findmug/mrf/layout_prior.hpp"
#include "run_command.hpp"
#include "test_data.hpp"

namespace fs = std::filesystem;

namespace findmug {
namespace {

test::RunResult run(const std::string& args) {
  return test::runCommand(std::string(FINDMUG_LEARN_LAYOUT_EXE) + " " + args);
}

TEST(LearnLayout, CountsRealLabelMapsOutsideTheEvaluationScenes) {
  FINDMUG_REQUIRE_DATA(labels, "nyuv2_test_labels654/label40");
  FINDMUG_REQUIRE_DATA(split, "nyuv2_meta/split_test_indices.txt");
  FINDMUG_REQUIRE_DATA(labelled, "nyuv2_labeled");
  test::TempDir dir;
  // Maps 0001, 0002 (the scene of evaluation frames 0001, 0002 of
  // nyuv2_labeled), 0131 and 0153 (test scenes without an evaluation frame).
  fs::create_directories(dir.path() / "label40");
  for (const char* name : {"0001.png", "0002.png", "0131.png", "0153.png"})
    fs::create_symlink(labels / name, dir.path() / "label40" / name);
  const std::string out = dir.str("prior.csv");
  const std::string common = "--labels " + dir.str("label40") + " --nyu-split " + split.string() +
                             " --out " + out;
  test::RunResult r = run(common + " --exclude-scenes-of " + labelled.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 of 4 label maps counted"), std::string::npos) << r.output;
  const LayoutCounts counts = loadLayoutCounts(out);
  EXPECT_EQ(counts.frames, 2);
  EXPECT_EQ(counts.offset_px, 10);
  double vertical = 0;
  for (double v : counts.vertical) vertical += v;
  EXPECT_GT(vertical, 1000);  // real rooms have boundaries
  // Walls stand on floors: wall above floor far more often than below it.
  const auto at = [](Label a, Label b) { return static_cast<int>(a) * kNumLabels + static_cast<int>(b); };
  EXPECT_GT(counts.vertical[at(Label::Wall, Label::Floor)],
            counts.vertical[at(Label::Floor, Label::Wall)]);
  EXPECT_NO_THROW(loadLayoutPrior(out));

  // Without exclusion all four are counted.
  r = run(common);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("4 of 4 label maps counted"), std::string::npos) << r.output;

  // A label id outside the mapping is refused with the file named.
  std::ofstream(dir.str("map.csv")) << "source_id,findmug_label\n0,void\n";
  r = run(common + " --mapping " + dir.str("map.csv"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find(".png: label id"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace findmug
