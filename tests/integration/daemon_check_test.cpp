// findmugd --check, the first-run self-test, as a person runs it: a good dataset source
// passes every item; a broken config, model or source, a source without frames, and a
// camera that sees no floor (and too little depth) each give their verdict line with
// what to do, and the exit code says whether anything failed.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "findmug/frame/image_io.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

struct Result {
  int code = -1;
  std::string out;
};

Result check(const std::string& args) {
  const std::string command = std::string(FINDMUGD_EXE) + " --check --config " +
                              (findmug::test::sourceDir() / "daemon/findmugd.yaml").string() + " " + args + " 2>/dev/null";
  Result r;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return r;
  char buffer[1024];
  while (std::fgets(buffer, sizeof(buffer), pipe)) r.out += buffer;
  const int status = pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

bool has(const Result& r, const std::string& text) { return r.out.find(text) != std::string::npos; }

const std::string kModel =
    "--model " + (findmug::test::sourceDir() / "models/findmug.fmf").string() + " ";

TEST(FindmugdCheck, RealFramesPassEveryItem) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const Result r = check(kModel + "--source dataset:" + nyu.string());
  EXPECT_EQ(r.code, 0) << r.out;
  for (const char* line :
       {"[ OK ] config", "[ OK ] model", "forest of 16 trees", "the settings it records in force",
        "[ OK ] source   dataset:", "[ OK ] frames   10 frames, 640x480", "depth valid on",
        "floor found in", "m above it", "[ OK ] labels   one frame labelled", "all items passed"}) {
    EXPECT_TRUE(has(r, line)) << line << " not in:\n" << r.out;
  }
  EXPECT_FALSE(has(r, "[FAIL]")) << r.out;
}

TEST(FindmugdCheck, BrokenConfigModelAndSourceFailWithWhatToDo) {
  Result r = check(kModel + "--set daemon.wokers=2");
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(has(r, "[FAIL] config")) << r.out;
  EXPECT_TRUE(has(r, "daemon.wokers")) << r.out;
  EXPECT_TRUE(has(r, "       do: ")) << r.out;

  r = check("--model /nonexistent/findmug.fmf --source dataset:/nonexistent/frames");
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(has(r, "[ OK ] config")) << r.out;
  EXPECT_TRUE(has(r, "[FAIL] model    daemon.model_path: /nonexistent/findmug.fmf")) << r.out;
  EXPECT_TRUE(has(r, "[FAIL] source   daemon.source 'dataset:/nonexistent/frames'")) << r.out;
  EXPECT_TRUE(has(r, "[SKIP] frames")) << r.out;
  EXPECT_TRUE(has(r, "2 item(s) failed")) << r.out;

  // A model trained with other feature-extraction settings than the config's.
  r = check(kModel + "--set cloud.max_depth_m=3 --source dataset:/nonexistent/frames");
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(has(r, "[FAIL] model")) << r.out;
  EXPECT_TRUE(has(r, "cloud.max_depth_m")) << r.out;
}

// --help-settings lists every setting of the file findmugd reads (its own, the core's, the
// offline tools' and findmug-web's sections): key = built-in default (what a value must be),
// [model] on the keys a model records, and a doc line under each, never empty.
TEST(FindmugdHelpSettings, ListsEverySettingWithDefaultRangeAndDoc) {
  std::string out;
  FILE* pipe = popen((std::string(FINDMUGD_EXE) + " --help-settings 2>&1").c_str(), "r");
  ASSERT_TRUE(pipe);
  char buffer[1024];
  while (std::fgets(buffer, sizeof(buffer), pipe)) out += buffer;
  const int status = pclose(pipe);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << out;
  for (const char* line :
       {"mrf.lambda = 1  (a number in [0, 1000])\n    weight of the unary term",
        "daemon.queue_capacity = 2  (an integer in [1, 64])\n    frames at the pipeline entry",
        "features.objects = false  (true or false) [model]\n    object features",
        "oversegmentation.method = organized  (one of pcl organized) [model]\n",
        "learner.classes = labels  (one of labels nyu13 nyu40)\n",
        "cloud.fill_depth_max_run_px = 0  (an integer in [0, 10000])\n",
        "web.port = 8088  (", "training.degraded_seed = ", "table_map.forget_misses = "}) {
    EXPECT_NE(out.find(line), std::string::npos) << line << " not in:\n" << out;
  }
  std::istringstream lines(out);
  std::string key_line, doc_line;
  int keys = 0;
  while (std::getline(lines, key_line)) {
    ASSERT_NE(key_line.rfind("    ", 0), 0u) << "a doc line without its key: " << key_line;
    ASSERT_NE(key_line.find(" = "), std::string::npos) << key_line;
    ASSERT_TRUE(std::getline(lines, doc_line)) << key_line << " has no doc line";
    EXPECT_EQ(doc_line.rfind("    ", 0), 0u) << key_line << ": " << doc_line;
    EXPECT_NE(doc_line.find_first_not_of(' '), std::string::npos)
        << key_line << " has an empty doc line";
    ++keys;
  }
  EXPECT_GT(keys, 240);
}

TEST(FindmugdCheck, NoFramesInTimeFails) {
  const Result r =
      check(kModel + "--source 'lcm:FINDMUG_RGBD?url=memq://' --set check.timeout_s=0.5");
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(has(r, "[ OK ] source")) << r.out;
  EXPECT_TRUE(has(r, "[FAIL] frames   none within")) << r.out;
  EXPECT_TRUE(has(r, "do: plug in the camera")) << r.out;
  EXPECT_TRUE(has(r, "[SKIP] ground")) << r.out;
}

TEST(FindmugdCheck, AWallWithHolesWarnsAboutDepthAndFindsNoFloor) {
  // An unlabelled folder of a camera facing a wall 1.5 m away, depth missing on the left 60 %.
  test::TempDir tmp;
  const std::filesystem::path dir = tmp.path() / "wall";
  std::filesystem::create_directories(dir / "rgb");
  std::filesystem::create_directories(dir / "depth");
  std::ofstream(dir / "intrinsics.yaml") << "fx: 300\nfy: 300\ncx: 160\ncy: 120\n";
  for (const char* name : {"a", "b", "c"}) {
    Image<std::uint16_t> depth{320, 240, std::vector<std::uint16_t>(320 * 240, 1500)};
    for (int y = 0; y < 240; ++y) {
      for (int x = 0; x < 192; ++x) depth.pixels[y * 320 + x] = 0;
    }
    writePng16((dir / "depth" / (std::string(name) + ".png")).string(), depth);
    writePngRgb((dir / "rgb" / (std::string(name) + ".png")).string(),
                Image<Rgb8>{320, 240, std::vector<Rgb8>(320 * 240, {200, 200, 190})});
  }
  const Result r = check(kModel + "--source dataset:" + dir.string());
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(has(r, "[WARN] frames   3 frames, 320x240")) << r.out;
  EXPECT_TRUE(has(r, "depth valid on 40% of pixels")) << r.out;
  EXPECT_TRUE(has(r, "[FAIL] ground   no floor plane found in any of 3 frames")) << r.out;
  EXPECT_TRUE(has(r, "do: point the camera")) << r.out;
}

}  // namespace
}  // namespace findmug
