// findmug-web's Label tools in-process (label_tools.hpp): the draft file's round trip and
// the refusal of files that are not drafts, the run decoding, and a model whose settings
// are not the config's refused as findmugd refuses it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/learner/forest.hpp"
#include "label_tools.hpp"
#include "test_data.hpp"

namespace findmug::web {
namespace {

namespace fs = std::filesystem;

class DraftFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("findmug-draft-test-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& text) {
    const fs::path file = dir_ / "0001.json";
    std::ofstream(file) << text;
    return file;
  }
  // The message readDraft refuses `text` with ("" when it reads).
  std::string refusal(const std::string& text, int width = 4, int height = 2) {
    try {
      readDraft(write(text), "0001", width, height);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }
  static LabelDraft sample() {
    LabelDraft d;
    d.frame = "0001";
    d.width = 4;
    d.height = 2;
    d.labels = {1, 1, 255, 7, 7, 7, 0, 2};
    d.strokes = 3;
    d.author = "tester";
    d.base_mtime_ns = "1234567890123456789";
    d.updated_utc = "2026-11-28T17:00:00Z";
    return d;
  }
  fs::path dir_;
};

TEST_F(DraftFile, WritesAndReadsBackEveryField) {
  const fs::path file = dir_ / "0001.json";
  writeDraft(file, sample());
  const LabelDraft back = readDraft(file, "0001", 4, 2);
  EXPECT_EQ(back.labels, sample().labels);
  EXPECT_EQ(back.strokes, 3);
  EXPECT_EQ(back.author, "tester");
  EXPECT_EQ(back.base_mtime_ns, "1234567890123456789");
  EXPECT_EQ(back.updated_utc, "2026-11-28T17:00:00Z");
  EXPECT_FALSE(fs::exists(dir_ / ".0001.json.tmp"));  // renamed over its place
}

TEST_F(DraftFile, RefusesWhatIsNotADraftNamingTheFileAndWhy) {
  std::string text = draftJson(sample()).dump();
  const std::string file = (dir_ / "0001.json").string();
  EXPECT_EQ(refusal(text), "");
  const std::string garbage = refusal("garbage");
  EXPECT_NE(garbage.find(file + ": not a label draft of frame 0001"), std::string::npos) << garbage;
  EXPECT_NE(garbage.find("not JSON"), std::string::npos) << garbage;
  EXPECT_NE(refusal(text.substr(0, text.size() / 2)).find("not JSON"), std::string::npos);
  EXPECT_NE(refusal(R"({"format": "other"})").find("format"), std::string::npos);
  nlohmann::json j = draftJson(sample());
  j["version"] = 2;
  EXPECT_NE(refusal(j.dump()).find("version"), std::string::npos);
  j = draftJson(sample());
  j["frame"] = "0002";
  EXPECT_NE(refusal(j.dump()).find("draft of frame '0002'"), std::string::npos);
  EXPECT_NE(refusal(draftJson(sample()).dump(), 8, 2).find("it is 4x2, the frame 8x2"),
            std::string::npos);
  j = draftJson(sample());
  j["runs"] = nlohmann::json::array({{1, 5}});
  EXPECT_NE(refusal(j.dump()).find("runs cover 5 of 8 pixels"), std::string::npos);
  j["runs"] = nlohmann::json::array({{9, 8}});
  EXPECT_NE(refusal(j.dump()).find("label id 9"), std::string::npos);
  j = draftJson(sample());
  j.erase("strokes");
  EXPECT_NE(refusal(j.dump()).find("'strokes'"), std::string::npos);
}

TEST(LabelRuns, DecodeAndEncodeAndRefuseBadRuns) {
  const std::vector<std::uint8_t> labels = {3, 3, 3, 255, 0, 0};
  EXPECT_EQ(labelsFromRuns(runsOf(labels), labels.size()), labels);
  EXPECT_EQ(runsOf(labels).dump(), "[[3,3],[255,1],[0,2]]");
  EXPECT_THROW(labelsFromRuns(nlohmann::json::parse("[[3,7]]"), 6), Error);
  EXPECT_THROW(labelsFromRuns(nlohmann::json::parse("[[3,5]]"), 6), Error);
  EXPECT_THROW(labelsFromRuns(nlohmann::json::parse("[[8,6]]"), 6), Error);
  EXPECT_THROW(labelsFromRuns(nlohmann::json::parse("[[3]]"), 6), Error);
  EXPECT_THROW(labelsFromRuns(nlohmann::json::parse("{}"), 6), Error);
}

// The settings the model records are the defaults of its keys (configForModel): a config
// that states none of them takes the model's; one that states another value is refused,
// naming the key, both values and the model.
TEST(LabelFrames, TakesTheModelsSettingsAndRefusesOnesGivenOtherwise) {
  const fs::path model = test::sourceDir() / "models/findmug.fmf";
  auto forest = std::make_shared<const RandomForest>(RandomForest::load(model.string()));
  EXPECT_NO_THROW(LabelFrames(SegmenterConfig{}, forest, "findmug.fmf", std::nullopt));
  Config given;
  applyOverride(given, "features.objects_columns=context");  // the columns of the model before
  try {
    LabelFrames frames(given.segmenter, forest, "findmug.fmf", std::nullopt);
    FAIL() << "a model trained with other object columns was taken";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("features.objects_columns = context (--set) but model " +
                                         model.string() +
                                         " records features.objects_columns = relations"),
              std::string::npos)
        << e.what();
  }
  Config same;
  applyOverride(same, "features.objects_columns=relations");
  EXPECT_NO_THROW(LabelFrames(same.segmenter, forest, "findmug.fmf", std::nullopt));
}

}  // namespace
}  // namespace findmug::web
