// findmug-synth --lcm-log: the rendered sequence as an LCM log the daemon replays.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <cstdlib>

#include "findmug/frame/dataset.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/labels/labels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "test_data.hpp"

namespace findmug {
namespace {

// Runs `command` (stderr into stdout); returns its output and sets `status` to pclose's.
std::string outputOf(const std::string& command, int& status) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) {
    status = -1;
    return "";
  }
  std::string output;
  char buf[512];
  while (std::fgets(buf, sizeof buf, pipe)) output += buf;
  status = pclose(pipe);
  return output;
}

TEST(SynthTool, WritesAnLcmLogEqualToTheDatasetFolder) {
  test::TempDir tmp;
  const std::string log = tmp.str("synth.lcmlog");
  const std::string command = std::string(FINDMUG_SYNTH_EXE) + " --seed 3 --frames 4 --fps 5 --out " +
                              tmp.str("seq") + " --lcm-log " + log + " > /dev/null 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;

  const DatasetFolder folder(tmp.str("seq"));
  ASSERT_EQ(folder.size(), 4u);
  lcm::LogFile file(log, "r");
  ASSERT_TRUE(file.good());
  std::vector<RgbdFrame> frames;
  std::vector<std::int64_t> timestamps;
  while (const lcm::LogEvent* event = file.readNextEvent()) {
    EXPECT_EQ(event->channel, std::string(io::kRgbdChannel));
    findmug_lcm::rgbd_frame_t message;
    ASSERT_GE(message.decode(event->data, 0, event->datalen), 0);
    frames.push_back(io::decodeRgbdFrame(message, event->channel));
    timestamps.push_back(event->timestamp);
  }
  ASSERT_EQ(frames.size(), 4u);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const LabeledFrame expected = folder.load(i);
    EXPECT_EQ(frames[i].seq, static_cast<std::int64_t>(i));
    EXPECT_EQ(frames[i].depth_mm, expected.frame.depth_mm) << "depth is zlib: lossless";
    ASSERT_TRUE(frames[i].extrinsics.has_value()) << "synthetic frames carry the camera mount";
    EXPECT_NEAR(frames[i].extrinsics->height_m, expected.frame.extrinsics->height_m, 1e-9);
    EXPECT_EQ(static_cast<std::uint64_t>(timestamps[i]), frames[i].utime);
    if (i > 0) {
      // 5 fps: the log replays at the sequence's own rate.
      EXPECT_NEAR(static_cast<double>(frames[i].utime - frames[i - 1].utime), 200000.0, 1.0);
    }
  }
}

// --multi-room: views of the search bench's apartments for training. Frames of two
// apartments carry their seeds in their names (the trainer takes every name once), read
// back as labelled frames that show furniture; the one-room options are refused.
TEST(SynthTool, MultiRoomApartmentsWriteFramesNamedByTheirSeeds) {
  test::TempDir tmp;
  for (const char* seed : {"9001", "9002"}) {
    const std::string command = std::string(FINDMUG_SYNTH_EXE) + " --multi-room --seed " + seed +
                                " --frames 3 --fps 2 --pitch-deg 20:35 --out " +
                                tmp.str(seed) + " > /dev/null 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
  }
  const DatasetFolder a(tmp.str("9001")), b(tmp.str("9002"));
  ASSERT_EQ(a.size(), 3u);
  ASSERT_EQ(b.size(), 3u);
  int furniture_pixels = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    const LabeledFrame fa = a.load(i), fb = b.load(i);
    EXPECT_EQ(fa.name, "apartment9001-00000" + std::to_string(i));
    EXPECT_EQ(fb.name, "apartment9002-00000" + std::to_string(i));
    ASSERT_TRUE(fa.frame.extrinsics.has_value());
    for (const std::uint8_t l : fa.labels)
      furniture_pixels += l == static_cast<std::uint8_t>(Label::Table) ||
                          l == static_cast<std::uint8_t>(Label::Chair) ||
                          l == static_cast<std::uint8_t>(Label::Cabinet);
  }
  EXPECT_GT(furniture_pixels, 3 * 640 * 480 / 20);
  int status = 0;
  const std::string output = outputOf(std::string(FINDMUG_SYNTH_EXE) +
                                          " --multi-room --tables 2 --seed 1 --frames 1 --out " +
                                          tmp.str("bad"),
                                      status);
  EXPECT_NE(status, 0);
  EXPECT_THAT(output, ::testing::HasSubstr("--multi-room"));
}

TEST(SynthTool, UnwritableLogIsNamed) {
  test::TempDir tmp;
  int status = 0;
  const std::string output =
      outputOf(std::string(FINDMUG_SYNTH_EXE) + " --seed 3 --frames 1 --out " + tmp.str("seq") +
                   " --lcm-log /nonexistent-dir/x.lcmlog",
               status);
  EXPECT_NE(status, 0);
  EXPECT_THAT(output, ::testing::HasSubstr("/nonexistent-dir/x.lcmlog"));
}

}  // namespace
}  // namespace findmug
