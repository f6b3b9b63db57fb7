// One's own recordings: a TUM RGB-D style folder (rgb.txt / depth.txt, depth in 1/5000 m),
// made here from real NYU frames, converted by findmug-import, replayed unlabelled by the
// dataset source and published by findmug-grab. Also the plain rgb/ + depth/ layout and
// bad input.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>

#include "findmug/frame/dataset.hpp"
#include "findmug/frame/image_io.hpp"
#include "findmug/io/frame_source.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "test_data.hpp"

namespace fs = std::filesystem;

namespace findmug {
namespace {

struct ToolRun {
  int code = -1;
  std::string output;  // stdout + stderr
};

ToolRun run(const std::string& args) {
  ToolRun r;
  const std::string command = std::string(FINDMUG_IMPORT_EXE) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return r;
  char buffer[512];
  while (std::fgets(buffer, sizeof(buffer), pipe)) r.output += buffer;
  const int status = pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// Frames 0..2 of the NYU folder as a TUM sequence: colour at t = 10.0, 10.1, 10.2 s,
// depth 8 ms later in 1/5000 m, plus a colour image with no depth near it and a depth
// image with no colour near it, which must both be left out.
std::vector<LabeledFrame> writeTumFolder(const fs::path& nyu, const fs::path& tum) {
  const DatasetFolder folder(nyu.string());
  fs::create_directories(tum / "rgb");
  fs::create_directories(tum / "depth");
  std::ofstream rgb_txt(tum / "rgb.txt"), depth_txt(tum / "depth.txt");
  rgb_txt << "# color images\n# file: 'test'\n# timestamp filename\n";
  depth_txt << "# depth maps\n# file: 'test'\n# timestamp filename\n";
  std::vector<LabeledFrame> frames;
  for (int i = 0; i < 3; ++i) {
    frames.push_back(folder.load(static_cast<std::size_t>(i)));
    const RgbdFrame& f = frames.back().frame;
    char t_rgb[32], t_depth[32];
    std::snprintf(t_rgb, sizeof(t_rgb), "%.6f", 10.0 + 0.1 * i);
    std::snprintf(t_depth, sizeof(t_depth), "%.6f", 10.008 + 0.1 * i);
    writePngRgb((tum / "rgb" / (std::string(t_rgb) + ".png")).string(),
                Image<Rgb8>{f.width, f.height, f.rgb});
    Image<std::uint16_t> depth{f.width, f.height, f.depth_mm};
    for (auto& d : depth.pixels) d = static_cast<std::uint16_t>(d * 5);  // mm -> 1/5000 m
    writePng16((tum / "depth" / (std::string(t_depth) + ".png")).string(), depth);
    rgb_txt << t_rgb << " rgb/" << t_rgb << ".png\n";
    depth_txt << t_depth << " depth/" << t_depth << ".png\n";
  }
  rgb_txt << "20.000000 rgb/10.000000.png\n";      // no depth within 20 ms
  depth_txt << "30.000000 depth/10.008000.png\n";  // no colour within 20 ms
  return frames;
}

TEST(FindmugImport, TumFolderBecomesAnUnlabelledDatasetThatReplays) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  test::TempDir tmp;
  const auto originals = writeTumFolder(nyu, tmp.path() / "tum");
  const ToolRun r = run("--in " + tmp.str("tum") + " --out " + tmp.str("out") +
                        " --depth-scale 5000 --intrinsics 518.5,519,325.5,253.5");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("3 frames (TUM association"), std::string::npos) << r.output;

  DatasetOptions replay;
  replay.require_labels = false;
  const DatasetFolder converted(tmp.str("out"), replay);
  EXPECT_FALSE(converted.hasLabels());
  ASSERT_EQ(converted.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    const LabeledFrame f = converted.load(i);
    EXPECT_EQ(f.frame.rgb, originals[i].frame.rgb) << i;
    // Back in millimetres; no NYU border mask (the folder has its own intrinsics).
    EXPECT_EQ(f.frame.depth_mm, originals[i].frame.depth_mm) << i;
    EXPECT_DOUBLE_EQ(f.frame.intrinsics.fx, 518.5);
    EXPECT_DOUBLE_EQ(f.frame.intrinsics.cy, 253.5);
  }

  // The daemon's dataset source replays it without labels.
  auto source = io::makeSource("dataset:" + tmp.str("out"));
  EXPECT_NE(source->describe().find("unlabelled"), std::string::npos) << source->describe();
  int delivered = 0;
  while (auto frame = source->next()) {
    EXPECT_EQ(frame->depth_mm, originals[static_cast<std::size_t>(delivered)].frame.depth_mm);
    ++delivered;
  }
  EXPECT_EQ(delivered, 3);

  // And findmug-grab publishes it (into an LCM log file).
  const std::string log_path = tmp.str("grab.lcm");
  const std::string grab = std::string(FINDMUG_GRAB_EXE) + " --source 'dataset:" + tmp.str("out") +
                           "' --url 'file://" + log_path + "?mode=w' 2>&1";
  ASSERT_EQ(std::system(grab.c_str()), 0);
  lcm::LogFile log(log_path, "r");
  ASSERT_TRUE(log.good());
  int events = 0;
  while (const lcm::LogEvent* event = log.readNextEvent()) {
    const RgbdFrame f =
        io::decodeRgbdFrame(event->data, static_cast<std::size_t>(event->datalen), event->channel);
    EXPECT_EQ(f.depth_mm, originals[static_cast<std::size_t>(events)].frame.depth_mm);
    ++events;
  }
  EXPECT_EQ(events, 3);
}

TEST(FindmugImport, PlainFolderIsPairedByNameAndScaled) {
  test::TempDir tmp;
  const fs::path in = tmp.path() / "in";
  fs::create_directories(in / "rgb");
  fs::create_directories(in / "depth");
  for (const char* name : {"b", "a", "c"}) {
    writePngRgb((in / "rgb" / (std::string(name) + ".png")).string(),
                Image<Rgb8>{4, 3, std::vector<Rgb8>(12, {9, 8, 7})});
  }
  for (const char* name : {"a", "b"}) {  // c has no depth
    writePng16((in / "depth" / (std::string(name) + ".png")).string(),
               Image<std::uint16_t>{4, 3, std::vector<std::uint16_t>(12, 1500)});
  }
  const ToolRun r = run("--in " + in.string() + " --out " + tmp.str("out") + " --depth-scale 1000");
  ASSERT_EQ(r.code, 0) << r.output;
  DatasetOptions replay;
  replay.require_labels = false;
  const DatasetFolder converted(tmp.str("out"), replay);
  EXPECT_EQ(converted.names(), (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(converted.load(0).frame.depth_mm, std::vector<std::uint16_t>(12, 1500));
  EXPECT_DOUBLE_EQ(converted.load(0).frame.intrinsics.fx, 525.0);  // the default
}

TEST(FindmugImport, BadInputIsNamed) {
  test::TempDir tmp;
  ToolRun r = run("--help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("--depth-scale"), std::string::npos);
  r = run("--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("findmug-import 0."), std::string::npos) << r.output;
  EXPECT_EQ(run("--in x").code, 2);  // --out missing
  EXPECT_EQ(run("--in x --out y --depth-scale -3").code, 2);

  fs::create_directories(tmp.path() / "tum");
  std::ofstream(tmp.path() / "tum" / "rgb.txt") << "1.0 rgb/1.png\n";
  r = run("--in " + tmp.str("tum") + " --out " + tmp.str("o1"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("depth.txt: cannot open"), std::string::npos) << r.output;

  std::ofstream(tmp.path() / "tum" / "depth.txt") << "1.0\n";
  r = run("--in " + tmp.str("tum") + " --out " + tmp.str("o2"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("depth.txt:1: expected 'timestamp path'"), std::string::npos) << r.output;

  r = run("--in " + tmp.str("tum") + " --out " + tmp.str("o3") + " --intrinsics 1,2,3");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("--intrinsics: expected fx,fy,cx,cy"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace findmug
