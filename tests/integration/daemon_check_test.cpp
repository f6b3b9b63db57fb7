// findmugd --check, the first-run self-test, as a person runs it: a good dataset source
// passes every item; a broken config, model or source, a source without frames, and a
// camera that sees no floor (and too little depth) each give their verdict line with
// what to do, and the exit code says whether anything failed.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
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
                              FINDMUG_SOURCE_DIR "/daemon/findmugd.yaml " + args + " 2>/dev/null";
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

const std::string kModel = "--model " FINDMUG_SOURCE_DIR "/models/findmug.fmf ";

TEST(FindmugdCheck, RealFramesPassEveryItem) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const Result r = check(kModel + "--source dataset:" + nyu.string());
  EXPECT_EQ(r.code, 0) << r.out;
  for (const char* line :
       {"[ OK ] config", "[ OK ] model", "forest of 16 trees", "settings match the config",
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
