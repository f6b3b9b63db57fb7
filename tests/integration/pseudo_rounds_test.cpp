// findmug-train and findmug-eval with --unlabelled DIR (semi-supervised
// rounds, pseudo_labels.hpp) on the shared NYU frames: inside each fold of
// findmug-eval only unlabelled frames are pseudo-labelled, never a test frame;
// a frame given both as labelled and as unlabelled is refused; an unlabelled
// folder with a corrupt depth image is refused with the file's name.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>

#include "run_command.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

std::set<std::string> stringsIn(const std::string& list) {
  std::set<std::string> out;
  const std::regex item_re("\"([^\"]+)\"");
  for (std::sregex_iterator it(list.begin(), list.end(), item_re), end; it != end; ++it)
    out.insert((*it)[1]);
  return out;
}

TEST(PseudoRounds, EvalPseudoLabelsOnlyUnlabelledFramesInEveryFold) {
  FINDMUG_REQUIRE_DATA(extra, "nyuv2_labeled_extra");
  FINDMUG_REQUIRE_DATA(unlabelled, "nyuv2_unlabeled_train");
  FINDMUG_REQUIRE_DATA(rotations, "nyuv2_meta/camera_rotations_NYU.txt");
  test::TempDir tmp;
  const auto result = test::runCommand(
      std::string(FINDMUG_EVAL_EXE) + " --data " + extra.string() + " --folds 3 --unlabelled " +
      unlabelled.string() + " --nyu-rotations " + rotations.string() +
      " --set ground.source=gravity --set features.regions=true --set training.pseudo_rounds=1"
      " --set training.pseudo_min_confidence=0.5 --json " + tmp.str("eval.json"));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  // Every unlabelled frame got its ground from NYU's gravity.
  EXPECT_THAT(result.output, HasSubstr("unlabelled 0003 ground gravity+"));
  const std::string json = test::readFile(tmp.path() / "eval.json");
  const std::set<std::string> unlabelled_names = {"0003", "0004", "0005", "0006", "0007",
                                                  "0008", "0010", "0011", "0012", "0013"};
  const std::regex fold_re(
      R"re(\{"fold": (\d+), "train_frames": \d+, "test": \[([^\]]*)\], "train": \[([^\]]*)\], )re"
      R"re("pseudo_pool": \[([^\]]*)\], "pseudo_rounds": \[\{"round": 1, "patches": (\d+), )re"
      R"re("frames": \[([^\]]*)\]\}\]\})re");
  std::set<std::string> tested;
  int folds = 0;
  for (std::sregex_iterator f(json.begin(), json.end(), fold_re), end; f != end; ++f) {
    ++folds;
    SCOPED_TRACE("fold " + (*f)[1].str());
    std::set<std::string> test_frames;
    const std::string test_list = (*f)[2];
    const std::regex frame_re(R"re("frame": "([^"]+)")re");
    for (std::sregex_iterator e(test_list.begin(), test_list.end(), frame_re); e != end; ++e)
      test_frames.insert((*e)[1]);
    tested.insert(test_frames.begin(), test_frames.end());
    const std::set<std::string> pool = stringsIn((*f)[4]);
    const std::set<std::string> used = stringsIn((*f)[6]);
    EXPECT_EQ(pool, unlabelled_names);
    EXPECT_GT(std::stoi((*f)[5]), 0);
    EXPECT_FALSE(used.empty());
    for (const auto& name : used) {
      EXPECT_EQ(unlabelled_names.count(name), 1u) << name << " pseudo-labelled";
      EXPECT_EQ(test_frames.count(name), 0u) << "test frame " << name << " pseudo-labelled";
    }
    for (const auto& name : stringsIn((*f)[3]))
      EXPECT_EQ(pool.count(name), 0u) << "training frame " << name << " in the pseudo pool";
  }
  EXPECT_EQ(folds, 3) << json.substr(0, 2000);
  EXPECT_EQ(tested.size(), 15u);
  for (const auto& name : tested) EXPECT_EQ(unlabelled_names.count(name), 0u) << name;
  // The rounds side by side: round 0 (labelled frames only) and round 1.
  EXPECT_THAT(json, HasSubstr("\"pseudo_rounds\": [\n    {\"round\": 0, \"class_average\": "));
  EXPECT_THAT(json, HasSubstr("{\"round\": 1, \"class_average\": "));
}

// A labelled frame offered as unlabelled too would be pseudo-labelled by a
// fold that tests it: refused before any training, naming the frame.
TEST(PseudoRounds, AFrameBothLabelledAndUnlabelledIsRefused) {
  FINDMUG_REQUIRE_DATA(extra, "nyuv2_labeled_extra");
  test::TempDir tmp;
  fs::create_directories(tmp.path() / "unl" / "rgb");
  fs::create_directories(tmp.path() / "unl" / "depth");
  fs::create_symlink(extra / "rgb" / "0029.png", tmp.path() / "unl" / "rgb" / "0029.png");
  fs::create_symlink(extra / "depth" / "0029.png", tmp.path() / "unl" / "depth" / "0029.png");
  const auto result = test::runCommand(std::string(FINDMUG_EVAL_EXE) + " --data " +
                                       extra.string() + " --folds 3 --unlabelled " +
                                       tmp.str("unl") + " --set training.pseudo_rounds=1");
  EXPECT_NE(result.exit_code, 0);
  EXPECT_THAT(result.output, HasSubstr("frame 0029 is also in " + extra.string()));
}

TEST(PseudoRounds, AnUnlabelledFolderWithACorruptDepthImageIsRefusedNamingTheFile) {
  FINDMUG_REQUIRE_DATA(extra, "nyuv2_labeled_extra");
  FINDMUG_REQUIRE_DATA(unlabelled, "nyuv2_unlabeled_train");
  test::TempDir tmp;
  const fs::path dir = tmp.path() / "unl";
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  for (const std::string name : {"0003", "0004"}) {
    fs::create_symlink(unlabelled / "rgb" / (name + ".png"), dir / "rgb" / (name + ".png"));
  }
  fs::create_symlink(unlabelled / "depth" / "0003.png", dir / "depth" / "0003.png");
  {
    // The first bytes of a real PNG, then the file ends.
    std::ifstream in(unlabelled / "depth" / "0004.png", std::ios::binary);
    std::string head(64, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    std::ofstream(dir / "depth" / "0004.png", std::ios::binary) << head;
  }
  const auto result = test::runCommand(
      std::string(FINDMUG_TRAIN_EXE) + " --data " + extra.string() + " --unlabelled " +
      dir.string() + " --set training.pseudo_rounds=1 --out " + tmp.str("model.fmf"));
  EXPECT_NE(result.exit_code, 0) << result.output;
  EXPECT_THAT(result.output, HasSubstr((dir / "depth" / "0004.png").string()));
  EXPECT_FALSE(fs::exists(tmp.path() / "model.fmf"));
}

}  // namespace
}  // namespace findmug
