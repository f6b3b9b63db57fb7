// The daemon's folder of taught objects (daemon/object_library.hpp): good
// files loaded, a corrupt one refused by name while the good ones stay, a
// changed file read again (and only it), a removed one dropped, two files
// with one object name, and snapshots that outlive a refresh.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "findmug/daemon/object_library.hpp"
#include "object_scenes.hpp"
#include "test_data.hpp"

namespace findmug::daemon {
namespace {

namespace fs = std::filesystem;

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// A changed file may keep its size; its modification time must differ for
// refresh() to see it, whatever the file system's clock granularity.
void touchLater(const std::string& path) {
  fs::last_write_time(path, fs::last_write_time(path) + std::chrono::seconds(2));
}

TEST(ObjectLibrary, LoadsGoodFilesAndRefusesACorruptOneByName) {
  test::TempDir dir;
  saveObjectModel(dir.str("mug.fmo"), test::sampleObjectModel("mug", 2));
  saveObjectModel(dir.str("cup.fmo"), test::sampleObjectModel("cup", 1));
  writeBytes(dir.str("broken.fmo"), "FMOBJECT\x01\x00");
  writeBytes(dir.str("notes.txt"), "not a model");
  ObjectLibrary library(dir.str());
  EXPECT_TRUE(library.models()->empty()) << "nothing is read before refresh()";
  const auto change = library.refresh();
  ASSERT_EQ(library.models()->size(), 2u);
  EXPECT_EQ((*library.models())[0].name, "cup");  // by name
  EXPECT_EQ((*library.models())[1].name, "mug");
  EXPECT_EQ((*library.models())[1].views.size(), 2u);
  EXPECT_EQ(change.loaded.size(), 2u);
  ASSERT_EQ(library.refusals().size(), 1u);
  EXPECT_EQ(library.refusals()[0].file, dir.str("broken.fmo"));
  EXPECT_NE(library.refusals()[0].reason.find("broken.fmo: truncated"), std::string::npos)
      << library.refusals()[0].reason;
  ASSERT_EQ(change.refused.size(), 1u);
  EXPECT_EQ(change.refused[0].file, dir.str("broken.fmo"));
  EXPECT_EQ(library.fileReads(), 3u) << "notes.txt is no model file";
}

TEST(ObjectLibrary, RefreshReadsOnlyWhatChangedAndDropsRemovedFiles) {
  test::TempDir dir;
  saveObjectModel(dir.str("mug.fmo"), test::sampleObjectModel("mug", 1));
  saveObjectModel(dir.str("cup.fmo"), test::sampleObjectModel("cup", 1));
  writeBytes(dir.str("broken.fmo"), "garbage");
  ObjectLibrary library(dir.str());
  library.refresh();
  const auto before = library.models();
  ASSERT_EQ(before->size(), 2u);
  EXPECT_EQ(library.fileReads(), 3u);

  // Nothing changed: nothing read, the same snapshot content, refusal kept.
  EXPECT_FALSE(library.refresh().changed());
  EXPECT_EQ(library.fileReads(), 3u);
  EXPECT_EQ(library.refusals().size(), 1u);

  // The mug taught again with 3 views: read again, alone.
  saveObjectModel(dir.str("mug.fmo"), test::sampleObjectModel("mug", 3));
  touchLater(dir.str("mug.fmo"));
  auto change = library.refresh();
  ASSERT_EQ(change.loaded.size(), 1u);
  EXPECT_EQ(change.loaded[0], dir.str("mug.fmo"));
  EXPECT_EQ(library.fileReads(), 4u);
  EXPECT_EQ(library.models()->at(1).views.size(), 3u);
  // A snapshot taken before stays as it was for whoever holds it.
  EXPECT_EQ(before->at(1).views.size(), 1u);

  // The cup removed, the broken file fixed.
  fs::remove(dir.str("cup.fmo"));
  saveObjectModel(dir.str("broken.fmo"), test::sampleObjectModel("bowl", 1));
  touchLater(dir.str("broken.fmo"));
  change = library.refresh();
  ASSERT_EQ(change.dropped.size(), 1u);
  EXPECT_EQ(change.dropped[0], dir.str("cup.fmo"));
  ASSERT_EQ(library.models()->size(), 2u);
  EXPECT_EQ(library.models()->at(0).name, "bowl");
  EXPECT_EQ(library.models()->at(1).name, "mug");
  EXPECT_TRUE(library.refusals().empty());

  // A good file made corrupt: refused, and its model no longer offered.
  writeBytes(dir.str("mug.fmo"), std::string("FMOBJECT\x07\x00\x00\x00", 12));
  touchLater(dir.str("mug.fmo"));
  change = library.refresh();
  ASSERT_EQ(change.refused.size(), 1u);
  EXPECT_NE(change.refused[0].reason.find("version = 7"), std::string::npos)
      << change.refused[0].reason;
  ASSERT_EQ(library.models()->size(), 1u);
  EXPECT_EQ(library.models()->at(0).name, "bowl");
}

TEST(ObjectLibrary, TwoFilesWithOneNameTakeTheFirstUntilItIsGone) {
  test::TempDir dir;
  saveObjectModel(dir.str("a_mug.fmo"), test::sampleObjectModel("mug", 1));
  saveObjectModel(dir.str("b_mug.fmo"), test::sampleObjectModel("mug", 2));
  ObjectLibrary library(dir.str());
  library.refresh();
  ASSERT_EQ(library.models()->size(), 1u);
  EXPECT_EQ(library.models()->at(0).views.size(), 1u);
  ASSERT_EQ(library.refusals().size(), 1u);
  EXPECT_EQ(library.refusals()[0].file, dir.str("b_mug.fmo"));
  EXPECT_NE(library.refusals()[0].reason.find("already taken by " + dir.str("a_mug.fmo")),
            std::string::npos);
  fs::remove(dir.str("a_mug.fmo"));
  library.refresh();
  ASSERT_EQ(library.models()->size(), 1u);
  EXPECT_EQ(library.models()->at(0).views.size(), 2u);
  EXPECT_EQ(library.fileReads(), 2u) << "the second file was not read again";
}

TEST(ObjectLibrary, AMissingFolderIsARefusalNotAnError) {
  test::TempDir dir;
  ObjectLibrary library(dir.str("nowhere"));
  EXPECT_NO_THROW(library.refresh());
  EXPECT_TRUE(library.models()->empty());
  ASSERT_EQ(library.refusals().size(), 1u);
  EXPECT_EQ(library.refusals()[0].file, dir.str("nowhere"));
  // Made later: picked up.
  fs::create_directories(dir.str("nowhere"));
  saveObjectModel(dir.str("nowhere/mug.fmo"), test::sampleObjectModel("mug", 1));
  library.refresh();
  EXPECT_EQ(library.models()->size(), 1u);
  EXPECT_TRUE(library.refusals().empty());
  ObjectLibrary off("");
  EXPECT_FALSE(off.refresh().changed());
  EXPECT_TRUE(off.models()->empty());
}

TEST(ObjectLibrary, SnapshotsAreSafeWhileAnotherThreadRefreshes) {
  test::TempDir dir;
  saveObjectModel(dir.str("mug.fmo"), test::sampleObjectModel("mug", 1));
  ObjectLibrary library(dir.str());
  library.refresh();
  std::thread refresher([&] {
    for (int i = 0; i < 20; ++i) {
      saveObjectModel(dir.str("mug.fmo"), test::sampleObjectModel("mug", 1 + i % 3, 20));
      touchLater(dir.str("mug.fmo"));
      library.refresh();
    }
  });
  for (int i = 0; i < 200; ++i) {
    const auto models = library.models();
    ASSERT_EQ(models->size(), 1u);
    const auto views = models->at(0).views.size();
    EXPECT_TRUE(views >= 1 && views <= 3);
  }
  refresher.join();
}

}  // namespace
}  // namespace findmug::daemon
