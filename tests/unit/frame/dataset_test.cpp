// Tests for findmug/frame/dataset.hpp: the label mappings, the folder reader on the
// real NYU frames, every bad-input case on small folders written here, and
// the writer's round trip.
#include "findmug/frame/dataset.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "findmug/common/error.hpp"
#include "findmug/frame/image_io.hpp"
#include "expect_error.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

namespace fs = std::filesystem;
using test::errorOf;
using test::TempDir;

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A small frame with distinct values per pixel and plausible millimetres.
LabeledFrame makeFrame(const std::string& name, int w, int h) {
  LabeledFrame f;
  f.name = name;
  f.frame.width = w;
  f.frame.height = h;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      f.frame.rgb.push_back({static_cast<std::uint8_t>(x), static_cast<std::uint8_t>(y),
                             static_cast<std::uint8_t>(x + y)});
      f.frame.depth_mm.push_back(static_cast<std::uint16_t>(1000 + 10 * x + y));
      f.labels.push_back(static_cast<std::uint8_t>((x + y) % kNumLabels));
    }
  }
  f.labels[0] = kVoidLabel;
  f.frame.intrinsics = CameraIntrinsics{300.0, 301.5, w / 2.0, h / 2.0};
  return f;
}

DatasetOptions noBorder() {
  DatasetOptions o;
  o.mask_nyu_border = false;
  return o;
}

// Writes rgb/, depth/ and a label folder of raw PNGs for one frame.
struct RawFolder {
  fs::path root;
  explicit RawFolder(const fs::path& r, const std::string& label_dir = "label40") : root(r) {
    for (const char* sub : {"rgb", "depth"}) fs::create_directories(root / sub);
    fs::create_directories(root / label_dir);
  }
  void rgb(const std::string& name, int w, int h) {
    writePngRgb((root / "rgb" / (name + ".png")).string(),
                Image<Rgb8>{w, h, std::vector<Rgb8>(static_cast<std::size_t>(w) * h, {1, 2, 3})});
  }
  void depth16(const std::string& name, int w, int h, std::uint16_t value) {
    writePng16((root / "depth" / (name + ".png")).string(),
               Image<std::uint16_t>{
                   w, h, std::vector<std::uint16_t>(static_cast<std::size_t>(w) * h, value)});
  }
  void depth8(const std::string& name, int w, int h) {
    writePng8(
        (root / "depth" / (name + ".png")).string(),
        Image<std::uint8_t>{w, h, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h, 200)});
  }
  void labels(const std::string& dir, const std::string& name, int w, int h, std::uint8_t value) {
    writePng8((root / dir / (name + ".png")).string(),
              Image<std::uint8_t>{
                  w, h, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h, value)});
  }
  // A consistent 8x6 frame with label40 id 1 (wall).
  void good(const std::string& name) {
    rgb(name, 8, 6);
    depth16(name, 8, 6, 1500);
    labels("label40", name, 8, 6, 1);
  }
};

// --------------------------------------------------------------------------
// Mappings

TEST(LabelMapping, DefaultNyu40MappingFollowsTheClassNames) {
  FINDMUG_REQUIRE_DATA(classes, "nyuv2_meta/nyu40_classes.csv");
  // Read NYU's own id -> name table so that a wrong id in our CSV (not just a
  // wrong decision) is caught.
  std::map<std::string, int> id_of;
  std::ifstream in(classes);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    const auto c1 = line.find(',');
    const auto c2 = line.find(',', c1 + 1);
    id_of[line.substr(c1 + 1, c2 - c1 - 1)] = std::stoi(line.substr(0, c1));
  }
  ASSERT_EQ(id_of.size(), 40u);
  const std::map<std::string, std::vector<std::string>> expected = {
      {"floor", {"floor", "floor mat"}},
      {"wall", {"wall", "door", "window", "blinds", "curtain", "picture", "whiteboard", "mirror"}},
      {"ceiling", {"ceiling"}},
      {"table", {"table", "desk", "counter"}},
      {"chair", {"chair"}},
      {"cabinet", {"cabinet", "bookshelf", "shelves", "dresser", "night stand", "refridgerator"}},
      {"object",
       {"books", "box", "paper", "bag", "lamp", "television", "pillow", "clothes", "towel",
        "otherprop"}},
      {"unknown",
       {"bed", "sofa", "otherfurniture", "otherstructure", "person", "toilet", "sink", "bathtub",
        "shower curtain"}},
  };
  const auto& m = defaultNyu40Mapping();
  std::size_t checked = 0;
  for (const auto& [label, names] : expected) {
    for (const auto& name : names) {
      ASSERT_TRUE(id_of.count(name)) << name;
      EXPECT_EQ(labelName(static_cast<std::uint8_t>(m.to_findmug[id_of[name]])), label) << name;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 40u);
  EXPECT_EQ(m.to_findmug[0], kVoidLabel);
  for (int id = 41; id < 256; ++id) EXPECT_EQ(m.to_findmug[id], -1) << id;
  EXPECT_CONTAINS(m.source, "nyu40_to_findmug8.csv");
}

TEST(LabelMapping, CompiledInMappingEqualsTheShippedFile) {
  const auto from_file =
      loadLabelMapping((test::sourceDir() / "models" / "nyu40_to_findmug8.csv").string());
  EXPECT_EQ(from_file.to_findmug, defaultNyu40Mapping().to_findmug);
}

TEST(LabelMapping, ParsesCommentsBlankLinesAndCrlf) {
  const auto m = parseLabelMapping(
      "# comment\r\n\r\nsource_id,findmug_label\r\n 3 , chair \r\n# x\n0,void\n255,object\n",
      "inline");
  EXPECT_EQ(m.to_findmug[3], 5);
  EXPECT_EQ(m.to_findmug[0], kVoidLabel);
  EXPECT_EQ(m.to_findmug[255], 7);
  EXPECT_EQ(m.to_findmug[1], -1);
  EXPECT_EQ(m.source, "inline");
}

TEST(LabelMapping, RejectsBadFilesWithLineNumbers) {
  const std::string h = "source_id,findmug_label\n";
  auto msg = errorOf([&] { parseLabelMapping(h + "1,wall\n2,sofa\n", "m.csv"); });
  EXPECT_CONTAINS(msg, "m.csv:3");
  EXPECT_CONTAINS(msg, "unknown findmug_label 'sofa'");
  msg = errorOf([&] { parseLabelMapping(h + "1,wall\n1,floor\n", "m.csv"); });
  EXPECT_CONTAINS(msg, "m.csv:3: duplicate source_id 1");
  msg = errorOf([&] { parseLabelMapping(h + "256,wall\n", "m.csv"); });
  EXPECT_CONTAINS(msg, "source_id '256'");
  msg = errorOf([&] { parseLabelMapping(h + "-1,wall\n", "m.csv"); });
  EXPECT_CONTAINS(msg, "source_id '-1'");
  msg = errorOf([&] { parseLabelMapping(h + "1x,wall\n", "m.csv"); });
  EXPECT_CONTAINS(msg, "source_id '1x'");
  msg = errorOf([&] { parseLabelMapping(h + "1,wall,extra\n", "m.csv"); });
  EXPECT_CONTAINS(msg, "expected 2 fields, found 3");
  msg = errorOf([&] { parseLabelMapping("id,label\n1,wall\n", "m.csv"); });
  EXPECT_CONTAINS(msg, "m.csv:1: expected header");
  msg = errorOf([&] { parseLabelMapping("# only comments\n", "m.csv"); });
  EXPECT_CONTAINS(msg, "m.csv: empty (expected header 'source_id,findmug_label')");
  msg = errorOf([&] { parseLabelMapping(h, "m.csv"); });
  EXPECT_CONTAINS(msg, "no entries");
  msg = errorOf([&] { loadLabelMapping("/nonexistent/m.csv"); });
  EXPECT_CONTAINS(msg, "/nonexistent/m.csv");
}

// --------------------------------------------------------------------------
// Real NYU frames

TEST(DatasetFolder, RealNyuFolderUsesLabel8AndNyuCalibration) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  DatasetFolder folder(nyu.string());
  ASSERT_EQ(folder.size(), 31u);
  EXPECT_EQ(folder.names().front(), "0001");
  EXPECT_TRUE(std::is_sorted(folder.names().begin(), folder.names().end()));
  const auto f = folder.load(0);
  EXPECT_EQ(f.name, "0001");
  EXPECT_EQ(f.frame.width, 640);
  EXPECT_EQ(f.frame.height, 480);
  EXPECT_DOUBLE_EQ(f.frame.intrinsics.fx, kNyuIntrinsics.fx);
  EXPECT_DOUBLE_EQ(f.frame.intrinsics.cy, kNyuIntrinsics.cy);
  EXPECT_FALSE(f.frame.extrinsics.has_value());
  // Every label is a findmug id or void, and all of the common classes occur
  // somewhere in the first frames.
  std::array<std::size_t, 256> counts{};
  for (std::size_t i = 0; i < 3; ++i) {
    for (auto l : folder.load(i).labels) ++counts[l];
  }
  for (int id = kNumLabels; id < 255; ++id) EXPECT_EQ(counts[id], 0u) << id;
  EXPECT_GT(counts[1], 0u);  // floor
  EXPECT_GT(counts[2], 0u);  // wall
  EXPECT_GT(counts[7], 0u);  // object
}

// The shipped label40 mapped by our CSV must reproduce the shipped label8 on
// every pixel inside the NYU valid region; outside it both are void.
TEST(DatasetFolder, Label40MappedByOurCsvEqualsShippedLabel8) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  TempDir view;  // rgb/ depth/ label40/ only, as symlinks (no data copied)
  for (const char* sub : {"rgb", "depth", "label40"}) {
    fs::create_directory_symlink(nyu / sub, view.path() / sub);
  }
  DatasetFolder from8(nyu.string());
  DatasetFolder from40(view.str());
  ASSERT_EQ(from40.names(), from8.names());
  for (const std::string name : {"0001", "0433", "0125", "0060"}) {
    const auto it = std::find(from8.names().begin(), from8.names().end(), name);
    ASSERT_NE(it, from8.names().end()) << name;
    const auto i = static_cast<std::size_t>(it - from8.names().begin());
    const auto a = from8.load(i);
    const auto b = from40.load(i);
    ASSERT_EQ(a.labels.size(), b.labels.size());
    const auto raw8 = readPng8((nyu / "label8" / (name + ".png")).string());
    const auto raw_depth = readPng16((nyu / "depth" / (name + ".png")).string());
    std::size_t inside = 0, mismatches = 0, labelled = 0, changed_inside = 0;
    for (int y = 0; y < 480; ++y) {
      for (int x = 0; x < 640; ++x) {
        const auto p = static_cast<std::size_t>(y) * 640 + x;
        const bool in_region = y >= 44 && y <= 470 && x >= 40 && x <= 600;
        if (in_region) {
          ++inside;
          if (a.labels[p] != b.labels[p]) ++mismatches;
          if (b.labels[p] != kVoidLabel) ++labelled;
          if (a.labels[p] != raw8.pixels[p]) ++changed_inside;
          if (b.frame.depth_mm[p] != raw_depth.pixels[p]) ++changed_inside;
        } else {
          ASSERT_EQ(a.labels[p], kVoidLabel) << name << " (" << x << "," << y << ")";
          ASSERT_EQ(b.labels[p], kVoidLabel) << name << " (" << x << "," << y << ")";
          ASSERT_EQ(b.frame.depth_mm[p], 0) << name << " (" << x << "," << y << ")";
        }
      }
    }
    EXPECT_EQ(inside, 427u * 561u);
    EXPECT_EQ(mismatches, 0u) << name;
    EXPECT_EQ(changed_inside, 0u) << name;    // the mask touches only the border
    EXPECT_GT(labelled, inside / 2) << name;  // not trivially all-void
    EXPECT_EQ(a.frame.rgb, b.frame.rgb);
  }
}

// training.split_labels = nyu40 reads label40/ beside label8/: every labelled
// pixel's NYU-40 class maps to its findmug label, void pixels (the border
// included) have class 0.
TEST(DatasetFolder, FineLabelsComeFromLabel40AndAgreeWithTheLabels) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  DatasetOptions options;
  options.fine_labels_folder = "label40";
  DatasetFolder folder(nyu.string(), options);
  EXPECT_TRUE(DatasetFolder(nyu.string()).load(0).fine_labels.empty());  // only when asked
  const auto& to8 = defaultNyu40Mapping().to_findmug;
  for (std::size_t i : {0u, 7u, 30u}) {
    const auto f = folder.load(i);
    ASSERT_EQ(f.fine_labels.size(), f.labels.size()) << f.name;
    std::size_t labelled = 0;
    std::array<std::size_t, kNyu40Classes + 1> seen{};
    for (std::size_t p = 0; p < f.labels.size(); ++p) {
      ASSERT_LE(f.fine_labels[p], kNyu40Classes);
      if (f.labels[p] == kVoidLabel) {
        ASSERT_EQ(f.fine_labels[p], 0) << f.name << " pixel " << p;
      } else {
        ASSERT_EQ(to8[f.fine_labels[p]], f.labels[p]) << f.name << " pixel " << p;
        ++labelled;
        ++seen[f.fine_labels[p]];
      }
    }
    EXPECT_GT(labelled, f.labels.size() / 3) << f.name;
    // Finer than the 8 classes: more NYU-40 classes than findmug labels occur.
    EXPECT_GT(std::count_if(seen.begin(), seen.end(), [](std::size_t c) { return c > 0; }), 4)
        << f.name;
    EXPECT_EQ(f.fine_labels[0], 0) << f.name;  // the NYU border
  }
}

// training.split_labels = nyu13 reads label13/: 1..13 where the frame is
// labelled, 0 where it is void.
TEST(DatasetFolder, FineLabelsFromLabel13CoverEveryLabelledPixel) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  DatasetOptions options;
  options.fine_labels_folder = "label13";
  DatasetFolder folder(nyu.string(), options);
  for (std::size_t i = 0; i < folder.size(); ++i) {
    const auto f = folder.load(i);
    ASSERT_EQ(f.fine_labels.size(), f.labels.size()) << f.name;
    std::size_t unlabelled_fine = 0;
    for (std::size_t p = 0; p < f.labels.size(); ++p) {
      ASSERT_LE(f.fine_labels[p], kNyu13Classes);
      if (f.labels[p] == kVoidLabel) ASSERT_EQ(f.fine_labels[p], 0);
      else unlabelled_fine += f.fine_labels[p] == 0;
    }
    EXPECT_EQ(unlabelled_fine, 0u) << f.name;
  }
}

TEST(DatasetFolder, FineLabelsNeedAValidLabel40Folder) {
  TempDir dir;
  RawFolder raw(dir.path() / "a", "label8");
  raw.rgb("x", 8, 6);
  raw.depth16("x", 8, 6, 1500);
  raw.labels("label8", "x", 8, 6, 1);
  DatasetOptions options = noBorder();
  options.fine_labels_folder = "label40";
  EXPECT_CONTAINS(errorOf([&] { DatasetFolder(dir.str("a"), options); }), "no label40/ folder");
  // The error names the setting that asked for the finer labels.
  options.fine_labels_asked_by = "learner.classes = nyu40";
  EXPECT_CONTAINS(errorOf([&] { DatasetFolder(dir.str("a"), options); }),
                  "asked for (learner.classes = nyu40)");
  // Optional (internal classes infer them): the folder reads with the 8 labels only.
  options.fine_labels_optional = true;
  EXPECT_TRUE(DatasetFolder(dir.str("a"), options).load(0).fine_labels.empty());
  options.fine_labels_optional = false;
  options.fine_labels_folder = "label12";
  EXPECT_CONTAINS(errorOf([&] { DatasetFolder(dir.str("a"), options); }),
                  "expected label40 or label13");
  options.fine_labels_folder = "label40";
  fs::create_directories(dir.path() / "a" / "label40");
  raw.labels("label40", "x", 8, 6, 41);
  const DatasetFolder folder(dir.str("a"), options);
  const std::string msg = errorOf([&] { folder.load(0); });
  EXPECT_CONTAINS(msg, "label40/x.png");
  EXPECT_CONTAINS(msg, "label 41");
  raw.labels("label40", "x", 4, 6, 1);
  EXPECT_CONTAINS(errorOf([&] { folder.load(0); }), "is 4x6");
  // label13/ holds ids 0..13 only.
  fs::create_directories(dir.path() / "a" / "label13");
  raw.labels("label13", "x", 8, 6, 14);
  options.fine_labels_folder = "label13";
  const DatasetFolder folder13(dir.str("a"), options);
  EXPECT_CONTAINS(errorOf([&] { folder13.load(0); }), "not an NYU-13 id (0..13)");
  raw.labels("label13", "x", 8, 6, 13);
  EXPECT_EQ(folder13.load(0).fine_labels, std::vector<std::uint8_t>(48, 13));
}

TEST(DatasetFolder, BorderMaskCanBeSwitchedOff) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  DatasetFolder folder(nyu.string(), noBorder());
  const auto f = folder.load(0);
  const auto raw_depth = readPng16((nyu / "depth" / "0001.png").string());
  const auto raw8 = readPng8((nyu / "label8" / "0001.png").string());
  EXPECT_EQ(f.frame.depth_mm, raw_depth.pixels);
  EXPECT_EQ(f.labels, raw8.pixels);
}

// --------------------------------------------------------------------------
// Bad input

TEST(DatasetFolder, MissingOrEmptyFoldersAreErrors) {
  TempDir dir;
  auto msg = errorOf([&] { DatasetFolder(dir.str("nope")); });
  EXPECT_CONTAINS(msg, dir.str("nope"));
  EXPECT_CONTAINS(msg, "does not exist");

  fs::create_directories(dir.path() / "a" / "rgb");
  msg = errorOf([&] { DatasetFolder(dir.str("a")); });
  EXPECT_CONTAINS(msg, "missing sub-folder 'depth/'");

  fs::create_directories(dir.path() / "a" / "depth");
  msg = errorOf([&] { DatasetFolder(dir.str("a")); });
  EXPECT_CONTAINS(msg, "neither label8/ nor label40/");

  fs::create_directories(dir.path() / "a" / "label8");
  msg = errorOf([&] { DatasetFolder(dir.str("a")); });
  EXPECT_CONTAINS(msg, "rgb: no PNG files");

  // Files present but no name in all three folders.
  RawFolder raw(dir.path() / "a", "label8");
  raw.rgb("x", 4, 4);
  raw.depth16("y", 4, 4, 1000);
  raw.labels("label8", "x", 4, 4, 1);
  msg = errorOf([&] { DatasetFolder(dir.str("a")); });
  EXPECT_CONTAINS(msg, "no frame has all of");
}

TEST(DatasetFolder, ListsOnlyNamesPresentEverywhereAndPrefersLabel8) {
  TempDir dir;
  RawFolder raw(dir.path());
  raw.good("b");
  raw.good("a");
  raw.rgb("only_rgb", 8, 6);
  raw.depth16("only_depth", 8, 6, 1000);
  writeText(dir.path() / "rgb" / "notes.txt", "not an image");
  DatasetFolder folder(dir.str(), noBorder());
  EXPECT_EQ(folder.names(), (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(folder.load(0).labels.front(), 2);  // NYU-40 wall -> findmug wall

  // With label8/ present it wins: its ids are used as they are.
  fs::create_directories(dir.path() / "label8");
  raw.labels("label8", "a", 8, 6, 4);
  DatasetFolder folder8(dir.str(), noBorder());
  EXPECT_EQ(folder8.names(), (std::vector<std::string>{"a"}));
  EXPECT_EQ(folder8.load(0).labels.front(), 4);
  EXPECT_CONTAINS(errorOf([&] { folder8.load(1); }), "out of range");
}

TEST(DatasetFolder, UnlabelledFolderReplaysOnlyWhenLabelsAreNotRequired) {
  TempDir dir;
  RawFolder raw(dir.path(), "label40");
  fs::remove_all(dir.path() / "label40");
  raw.rgb("b", 8, 6);
  raw.depth16("b", 8, 6, 1500);
  raw.rgb("a", 8, 6);
  raw.depth16("a", 8, 6, 1200);
  raw.rgb("only_rgb", 8, 6);
  // Training and evaluation (the default) still insist on ground truth.
  EXPECT_CONTAINS(errorOf([&] { DatasetFolder(dir.str(), noBorder()); }),
                  "neither label8/ nor label40/");

  DatasetOptions replay = noBorder();
  replay.require_labels = false;
  DatasetFolder folder(dir.str(), replay);
  EXPECT_FALSE(folder.hasLabels());
  EXPECT_EQ(folder.names(), (std::vector<std::string>{"a", "b"}));
  const LabeledFrame a = folder.load(0);
  EXPECT_EQ(a.frame.depth_mm, std::vector<std::uint16_t>(48, 1200));
  EXPECT_EQ(a.frame.rgb.front(), (Rgb8{1, 2, 3}));
  EXPECT_EQ(a.labels, std::vector<std::uint8_t>(48, kVoidLabel));
  // Depth units are still checked without labels.
  raw.depth16("a", 8, 6, 20);
  EXPECT_CONTAINS(errorOf([&] { folder.load(0); }), "does not look like millimetres");

  // A labelled folder keeps its labels with require_labels = false.
  fs::create_directories(dir.path() / "label8");
  raw.labels("label8", "b", 8, 6, 4);
  DatasetFolder labelled(dir.str(), replay);
  EXPECT_TRUE(labelled.hasLabels());
  EXPECT_EQ(labelled.names(), (std::vector<std::string>{"b"}));
  EXPECT_EQ(labelled.load(0).labels.front(), 4);

  // Nothing in both rgb/ and depth/.
  TempDir empty;
  RawFolder lone(empty.path(), "label40");
  fs::remove_all(empty.path() / "label40");
  lone.rgb("x", 4, 4);
  lone.depth16("y", 4, 4, 1000);
  EXPECT_CONTAINS(errorOf([&] { DatasetFolder(empty.str(), replay); }),
                  "no frame has both rgb/NAME.png and depth/NAME.png");
}

TEST(DatasetFolder, SizeMismatchNamesBothFilesAndSizes) {
  TempDir dir;
  RawFolder raw(dir.path());
  raw.rgb("f", 8, 6);
  raw.depth16("f", 8, 5, 1500);
  raw.labels("label40", "f", 8, 6, 1);
  DatasetFolder folder(dir.str(), noBorder());
  auto msg = errorOf([&] { folder.load(0); });
  EXPECT_CONTAINS(msg, "depth/f.png is 8x5");
  EXPECT_CONTAINS(msg, "rgb/f.png is 8x6");

  raw.depth16("f", 8, 6, 1500);
  raw.labels("label40", "f", 7, 6, 1);
  msg = errorOf([&] { folder.load(0); });
  EXPECT_CONTAINS(msg, "label40/f.png is 7x6");
  EXPECT_CONTAINS(msg, "rgb/f.png is 8x6");
}

TEST(DatasetFolder, EightBitDepthIsRejected) {
  TempDir dir;
  RawFolder raw(dir.path());
  raw.rgb("f", 8, 6);
  raw.depth8("f", 8, 6);
  raw.labels("label40", "f", 8, 6, 1);
  const auto msg = errorOf([&] { DatasetFolder(dir.str(), noBorder()).load(0); });
  EXPECT_CONTAINS(msg, "depth not uint16 millimetres");
  EXPECT_CONTAINS(msg, "depth/f.png");
  EXPECT_CONTAINS(msg, "found 8-bit grey");
}

TEST(DatasetFolder, DepthInWrongUnitsIsRejected) {
  TempDir dir;
  RawFolder raw(dir.path());
  raw.rgb("f", 8, 6);
  raw.labels("label40", "f", 8, 6, 1);
  raw.depth16("f", 8, 6, 1500);
  DatasetFolder folder(dir.str(), noBorder());
  EXPECT_NO_THROW(folder.load(0));

  raw.depth16("f", 8, 6, 2);  // metres stored as integers
  auto msg = errorOf([&] { folder.load(0); });
  EXPECT_CONTAINS(msg, "depth/f.png: depth does not look like millimetres (median 2");

  raw.depth16("f", 8, 6, 25000);  // e.g. 1/5000 m units
  msg = errorOf([&] { folder.load(0); });
  EXPECT_CONTAINS(msg, "(median 25000");

  raw.depth16("f", 8, 6, 0);
  msg = errorOf([&] { folder.load(0); });
  EXPECT_CONTAINS(msg, "no valid depth");

  // Plausible millimetres with a third missing (raw Kinect) are fine.
  Image<std::uint16_t> partial{8, 6, std::vector<std::uint16_t>(48, 2500)};
  std::fill(partial.pixels.begin(), partial.pixels.begin() + 16, 0);
  writePng16((dir.path() / "depth" / "f.png").string(), partial);
  EXPECT_EQ(folder.load(0).frame.depth_mm, partial.pixels);
}

TEST(DatasetFolder, LabelIdsOutsideTheMappingNameFileIdAndCount) {
  TempDir dir;
  RawFolder raw(dir.path());
  raw.rgb("f", 8, 6);
  raw.depth16("f", 8, 6, 1500);
  Image<std::uint8_t> labels{8, 6, std::vector<std::uint8_t>(48, 1)};
  std::fill(labels.pixels.begin(), labels.pixels.begin() + 5, 99);
  writePng8((dir.path() / "label40" / "f.png").string(), labels);
  auto msg = errorOf([&] { DatasetFolder(dir.str(), noBorder()).load(0); });
  EXPECT_CONTAINS(msg, "label40/f.png");
  EXPECT_CONTAINS(msg, "id 99 (5 pixels)");
  EXPECT_CONTAINS(msg, "nyu40_to_findmug8.csv");

  // label8 accepts 0..7 and 255 only.
  TempDir dir8;
  RawFolder raw8(dir8.path(), "label8");
  raw8.rgb("f", 8, 6);
  raw8.depth16("f", 8, 6, 1500);
  raw8.labels("label8", "f", 8, 6, 8);
  msg = errorOf([&] { DatasetFolder(dir8.str(), noBorder()).load(0); });
  EXPECT_CONTAINS(msg, "label8/f.png");
  EXPECT_CONTAINS(msg, "id 8 (48 pixels)");
}

TEST(DatasetFolder, CustomMappingCsvIsUsed) {
  TempDir dir;
  RawFolder raw(dir.path());
  raw.rgb("f", 8, 6);
  raw.depth16("f", 8, 6, 1500);
  raw.labels("label40", "f", 8, 6, 99);
  writeText(dir.path() / "map.csv", "source_id,findmug_label\n99,chair\n");
  DatasetOptions options = noBorder();
  options.mapping_csv = dir.str("map.csv");
  const auto f = DatasetFolder(dir.str(), options).load(0);
  EXPECT_TRUE(std::all_of(f.labels.begin(), f.labels.end(), [](auto l) { return l == 5; }));
}

TEST(DatasetFolder, IntrinsicsYamlIsReadAndValidated) {
  TempDir dir;
  RawFolder raw(dir.path());
  raw.good("f");
  writeText(dir.path() / "intrinsics.yaml", "fx: 500.5\nfy: 501\ncx: 3.5\ncy: 2.5\n");
  auto k = DatasetFolder(dir.str(), noBorder()).load(0).frame.intrinsics;
  EXPECT_DOUBLE_EQ(k.fx, 500.5);
  EXPECT_DOUBLE_EQ(k.fy, 501);
  EXPECT_DOUBLE_EQ(k.cx, 3.5);
  EXPECT_DOUBLE_EQ(k.cy, 2.5);

  DatasetOptions options = noBorder();
  options.intrinsics = CameraIntrinsics{1, 2, 3, 4};
  EXPECT_DOUBLE_EQ(DatasetFolder(dir.str(), options).load(0).frame.intrinsics.fy, 2);

  writeText(dir.path() / "intrinsics.yaml", "fx: 500\ncx: 3\ncy: 2\n");
  auto msg = errorOf([&] { DatasetFolder(dir.str(), noBorder()); });
  EXPECT_CONTAINS(msg, "intrinsics.yaml: missing key 'fy'");
  writeText(dir.path() / "intrinsics.yaml", "fx: abc\nfy: 1\ncx: 3\ncy: 2\n");
  msg = errorOf([&] { DatasetFolder(dir.str(), noBorder()); });
  EXPECT_CONTAINS(msg, "'fx' is not a number");
  writeText(dir.path() / "intrinsics.yaml", "fx: -5\nfy: 1\ncx: 3\ncy: 2\n");
  msg = errorOf([&] { DatasetFolder(dir.str(), noBorder()); });
  EXPECT_CONTAINS(msg, "must be positive");
  writeText(dir.path() / "intrinsics.yaml", "fx: [1,\n");
  msg = errorOf([&] { DatasetFolder(dir.str(), noBorder()); });
  EXPECT_CONTAINS(msg, "cannot parse YAML");
}

TEST(DatasetFolder, ExtrinsicsCsvIsOptionalPerFrameAndValidated) {
  TempDir dir;
  RawFolder raw(dir.path());
  raw.good("a");
  raw.good("b");
  writeText(dir.path() / "extrinsics.csv",
            "name,height_m,pitch_rad,roll_rad\nb,1.2,0.5,-0.01\nghost,1,0,0\n");
  DatasetFolder folder(dir.str(), noBorder());
  EXPECT_FALSE(folder.load(0).frame.extrinsics.has_value());
  const auto e = folder.load(1).frame.extrinsics;
  ASSERT_TRUE(e.has_value());
  EXPECT_DOUBLE_EQ(e->height_m, 1.2);
  EXPECT_DOUBLE_EQ(e->pitch_rad, 0.5);
  EXPECT_DOUBLE_EQ(e->roll_rad, -0.01);

  writeText(dir.path() / "extrinsics.csv", "name,height_m,pitch_rad,roll_rad\nb,1.2,x,0\n");
  auto msg = errorOf([&] { DatasetFolder(dir.str(), noBorder()); });
  EXPECT_CONTAINS(msg, "extrinsics.csv:2: pitch_rad 'x' is not a finite number");
  writeText(dir.path() / "extrinsics.csv", "name,height_m,pitch_rad,roll_rad\nb,1,0,0\nb,1,0,0\n");
  msg = errorOf([&] { DatasetFolder(dir.str(), noBorder()); });
  EXPECT_CONTAINS(msg, "duplicate frame 'b'");
  writeText(dir.path() / "extrinsics.csv", "name,height,pitch\n");
  msg = errorOf([&] { DatasetFolder(dir.str(), noBorder()); });
  EXPECT_CONTAINS(msg, "expected header");
  // Absurd values are caught by validateFrame when the frame is loaded.
  writeText(dir.path() / "extrinsics.csv", "name,height_m,pitch_rad,roll_rad\nb,40,0,0\n");
  msg = errorOf([&] { DatasetFolder(dir.str(), noBorder()).load(1); });
  EXPECT_CONTAINS(msg, "invalid extrinsics height_m=40");
}

// --------------------------------------------------------------------------
// Per-frame gravity

constexpr const char* kTwoRotations =
    "1 0 0\n0 1 0\n0 0 1\n\n"
    "1 0 0\n0 0.6 0.8\n0 -0.8 0.6\n\n";

TEST(NyuRotations, ReadsMatricesAndGivesUpAsMinusRowOne) {
  const NyuRotations r = parseNyuRotations(kTwoRotations, "rot.txt");
  ASSERT_EQ(r.rotations.size(), 2u);
  // Identity: the camera is level, up is camera -y.
  EXPECT_EQ(r.upForIndex(1), (std::array<double, 3>{-0.0, -1.0, -0.0}));
  // Row 1 of the second matrix is (0, 0.6, 0.8): up = (0, -0.6, -0.8).
  const auto up = r.upForIndex(2);
  EXPECT_DOUBLE_EQ(up[1], -0.6);
  EXPECT_DOUBLE_EQ(up[2], -0.8);
  // Without a trailing blank line, with CRLF and extra blank lines too.
  EXPECT_EQ(parseNyuRotations("\r\n1 0 0\r\n0 1 0\r\n0 0 1", "x").rotations.size(), 1u);
}

TEST(NyuRotations, ErrorsNameFileAndLine) {
  auto msg = errorOf([] { parseNyuRotations("1 0 0\n0 1 zero\n0 0 1\n", "rot.txt"); });
  EXPECT_CONTAINS(msg, "rot.txt:2: 'zero' is not a finite number");
  msg = errorOf([] { parseNyuRotations("1 0 0\n0 1\n0 0 1\n", "rot.txt"); });
  EXPECT_CONTAINS(msg, "rot.txt:2: expected 3 numbers in a matrix row, found 2");
  msg = errorOf([] { parseNyuRotations("1 0 0\n0 1 0\n0 0 1\n\n1 0 0\n0 1 0\n", "rot.txt"); });
  EXPECT_CONTAINS(msg, "rot.txt:5: matrix 2 has 2 rows, expected 3");
  msg = errorOf([] { parseNyuRotations("1 0 0\n0 1 0\n0 0 1\n1 0 0\n", "rot.txt"); });
  EXPECT_CONTAINS(msg, "rot.txt:4: matrix 1 has more than 3 rows");
  msg = errorOf([] { parseNyuRotations("1 0 0\n0 2 0\n0 0 1\n", "rot.txt"); });
  EXPECT_CONTAINS(msg, "rot.txt:1: matrix 1 is not a rotation");
  msg = errorOf([] { parseNyuRotations("\n\n", "rot.txt"); });
  EXPECT_CONTAINS(msg, "rot.txt: no rotation matrix");
  const NyuRotations r = parseNyuRotations(kTwoRotations, "rot.txt");
  msg = errorOf([&] { r.upForIndex(3); });
  EXPECT_CONTAINS(msg, "rot.txt: NYU index 3 out of range (file has 2 matrices");
  msg = errorOf([&] { r.upForIndex(0); });
  EXPECT_CONTAINS(msg, "NYU index 0 out of range");
  msg = errorOf([] { loadNyuRotations("/nonexistent/rot.txt"); });
  EXPECT_CONTAINS(msg, "/nonexistent/rot.txt");
}

TEST(NyuRotations, TheShippedFileHasOneRotationPerNyuFrame) {
  FINDMUG_REQUIRE_DATA(path, "nyuv2_meta/camera_rotations_NYU.txt");
  const NyuRotations r = loadNyuRotations(path.string());
  EXPECT_EQ(r.rotations.size(), 1449u);
  // Hand-held Kinect: up is within 45 degrees of camera -y on every frame.
  for (long i = 1; i <= 1449; ++i) EXPECT_LT(r.upForIndex(i)[1], -0.7) << i;
}

TEST(DatasetFolder, GravityFromNyuRotationsAndGravityCsv) {
  TempDir dir;
  RawFolder raw(dir.path());
  raw.good("0001");
  raw.good("0002");
  writeText(dir.path() / "rot.txt", kTwoRotations);
  DatasetOptions options = noBorder();
  EXPECT_FALSE(DatasetFolder(dir.str(), options).load(0).frame.gravity_up.has_value());
  options.nyu_rotations_file = (dir.path() / "rot.txt").string();
  {
    DatasetFolder folder(dir.str(), options);
    ASSERT_TRUE(folder.load(1).frame.gravity_up.has_value());
    EXPECT_DOUBLE_EQ((*folder.load(1).frame.gravity_up)[2], -0.8);
  }
  // gravity.csv overrides per frame; its vector is normalised.
  writeText(dir.path() / "gravity.csv", "name,up_x,up_y,up_z\n0002,0,-2,0\nghost,0,-1,0\n");
  {
    DatasetFolder folder(dir.str(), options);
    EXPECT_EQ(*folder.load(1).frame.gravity_up, (std::array<double, 3>{0.0, -1.0, 0.0}));
    EXPECT_DOUBLE_EQ((*folder.load(0).frame.gravity_up)[1], -1.0);
  }
  writeText(dir.path() / "gravity.csv", "name,up_x,up_y,up_z\n0002,0,nan,0\n");
  auto msg = errorOf([&] { DatasetFolder(dir.str(), options); });
  EXPECT_CONTAINS(msg, "gravity.csv:2: up_y 'nan' is not a finite number");
  writeText(dir.path() / "gravity.csv", "name,up_x,up_y,up_z\n0002,0,0,0\n");
  msg = errorOf([&] { DatasetFolder(dir.str(), options); });
  EXPECT_CONTAINS(msg, "gravity.csv:2: up direction");
  writeText(dir.path() / "gravity.csv", "name,up\n");
  msg = errorOf([&] { DatasetFolder(dir.str(), options); });
  EXPECT_CONTAINS(msg, "expected header 'name,up_x,up_y,up_z'");
  fs::remove(dir.path() / "gravity.csv");

  // A frame beyond the file, or not named by an NYU index.
  raw.good("0003");
  msg = errorOf([&] { DatasetFolder(dir.str(), options); });
  EXPECT_CONTAINS(msg, "NYU index 3 out of range");
  fs::remove(dir.path() / "rgb" / "0003.png");
  raw.good("kitchen");
  msg = errorOf([&] { DatasetFolder(dir.str(), options); });
  EXPECT_CONTAINS(msg, "frame 'kitchen' is not named by an NYU index");
}

TEST(DatasetFolder, BorderMaskOnSmallFrames) {
  TempDir dir;
  RawFolder raw(dir.path());
  raw.rgb("f", 10, 8);
  raw.depth16("f", 10, 8, 1500);
  raw.labels("label40", "f", 10, 8, 2);  // floor
  DatasetOptions options;
  options.border_top = 1;
  options.border_bottom = 2;
  options.border_left = 3;
  options.border_right = 4;
  const auto f = DatasetFolder(dir.str(), options).load(0);
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 10; ++x) {
      const bool inside = y >= 1 && y < 6 && x >= 3 && x < 6;
      const auto p = static_cast<std::size_t>(y) * 10 + x;
      EXPECT_EQ(f.labels[p], inside ? 1 : kVoidLabel) << x << "," << y;
      EXPECT_EQ(f.frame.depth_mm[p], inside ? 1500 : 0) << x << "," << y;
    }
  }
  // The default NYU border leaves nothing of a tiny frame: an error, not an
  // all-void frame.
  const auto msg = errorOf([&] { DatasetFolder(dir.str()).load(0); });
  EXPECT_CONTAINS(msg, "leaves nothing of a 10x8 frame");
}

// --------------------------------------------------------------------------
// Writing

TEST(WriteLabeledFrame, RoundTripsThroughTheFolderReader) {
  TempDir dir;
  auto a = makeFrame("a", 9, 7);
  auto b = makeFrame("b", 9, 7);
  b.frame.extrinsics = CameraExtrinsics{1.234567890123, 0.3, -0.05};
  writeLabeledFrame(dir.str("ds"), a);
  EXPECT_FALSE(fs::exists(dir.path() / "ds" / "extrinsics.csv"));  // nobody has extrinsics yet
  writeLabeledFrame(dir.str("ds"), b);
  ASSERT_TRUE(fs::exists(dir.path() / "ds" / "intrinsics.yaml"));
  ASSERT_TRUE(fs::exists(dir.path() / "ds" / "extrinsics.csv"));

  DatasetFolder folder(dir.str("ds"), noBorder());
  ASSERT_EQ(folder.names(), (std::vector<std::string>{"a", "b"}));
  const auto ra = folder.load(0);
  const auto rb = folder.load(1);
  EXPECT_EQ(ra.frame.rgb, a.frame.rgb);
  EXPECT_EQ(ra.frame.depth_mm, a.frame.depth_mm);
  EXPECT_EQ(ra.labels, a.labels);
  EXPECT_EQ(rb.labels, b.labels);
  EXPECT_DOUBLE_EQ(ra.frame.intrinsics.fy, 301.5);
  EXPECT_DOUBLE_EQ(ra.frame.intrinsics.cx, 4.5);
  EXPECT_FALSE(ra.frame.extrinsics.has_value());
  ASSERT_TRUE(rb.frame.extrinsics.has_value());
  EXPECT_DOUBLE_EQ(rb.frame.extrinsics->height_m, 1.234567890123);  // full precision kept
  EXPECT_DOUBLE_EQ(rb.frame.extrinsics->roll_rad, -0.05);

  // Rewriting a frame replaces its row instead of duplicating it.
  b.frame.extrinsics->height_m = 0.9;
  writeLabeledFrame(dir.str("ds"), b);
  const auto rb2 = DatasetFolder(dir.str("ds"), noBorder()).load(1);
  EXPECT_DOUBLE_EQ(rb2.frame.extrinsics->height_m, 0.9);
  // And a rewrite without extrinsics removes the stale row.
  b.frame.extrinsics.reset();
  writeLabeledFrame(dir.str("ds"), b);
  EXPECT_EQ(readText(dir.path() / "ds" / "extrinsics.csv"), "name,height_m,pitch_rad,roll_rad\n");
  EXPECT_FALSE(DatasetFolder(dir.str("ds"), noBorder()).load(1).frame.extrinsics.has_value());
}

TEST(WriteLabeledFrame, RejectsInconsistentFrames) {
  TempDir dir;
  auto f = makeFrame("f", 4, 3);
  writeLabeledFrame(dir.str(), f);

  auto other_camera = makeFrame("g", 4, 3);
  other_camera.frame.intrinsics.fx = 525;
  auto msg = errorOf([&] { writeLabeledFrame(dir.str(), other_camera); });
  EXPECT_CONTAINS(msg, "intrinsics.yaml: frame 'g' has different intrinsics");

  auto bad_label = makeFrame("h", 4, 3);
  bad_label.labels[3] = 12;
  msg = errorOf([&] { writeLabeledFrame(dir.str(), bad_label); });
  EXPECT_CONTAINS(msg, "id 12 (1 pixels)");

  auto short_labels = makeFrame("i", 4, 3);
  short_labels.labels.pop_back();
  msg = errorOf([&] { writeLabeledFrame(dir.str(), short_labels); });
  EXPECT_CONTAINS(msg, "11 labels for 12 pixels");

  auto short_depth = makeFrame("j", 4, 3);
  short_depth.frame.depth_mm.pop_back();
  EXPECT_THROW(writeLabeledFrame(dir.str(), short_depth), Error);

  for (const std::string bad : {"", "a/b", "a,b"}) {
    auto named = makeFrame(bad, 4, 3);
    msg = errorOf([&] { writeLabeledFrame(dir.str(), named); });
    EXPECT_CONTAINS(msg, "invalid frame name");
  }
  // None of the rejected frames left files behind.
  EXPECT_EQ(DatasetFolder(dir.str(), noBorder()).names(), (std::vector<std::string>{"f"}));
}

}  // namespace
}  // namespace findmug
