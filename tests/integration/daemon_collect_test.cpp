// Collecting frames worth labelling (daemon.collect_*, frame_collector.hpp), through
// the daemon's pipeline on real NYU frames (half size, sequential mode, in-memory
// buses): a save_frame command writes the frame in the dataset layout (read back by
// DatasetFolder and frames.csv's reader), the low-confidence and table-flicker
// triggers save exactly the frames they should, the rate limit spaces automatic
// saves, and the folder's bound (frames and bytes, what was there counted) refuses
// and counts further saves.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>

#include "daemon_test_config.hpp"
#include "daemon_test_support.hpp"
#include "findmug/offline/cv_folds.hpp"
#include "findmug/daemon/pipeline.hpp"
#include "findmug/frame/dataset.hpp"
#include "findmug/io/bus.hpp"
#include "findmug/io/channels.hpp"
#include "findmug/io/lcm_codec.hpp"
#include "findmug/segmenter/segmenter.hpp"
#include "test_data.hpp"

namespace findmug::daemon {
namespace {

using namespace std::chrono_literals;
using findmug::test::TempDir;
namespace fs = std::filesystem;

constexpr int kStep = 2;

struct Shared {
  TempDir dir;
  std::vector<LabeledFrame> frames;  // half size
  std::shared_ptr<const RandomForest> forest;
  std::vector<double> mean_confidence;  // per frame, by the library (-1: nothing labelled)
  std::vector<std::size_t> tables;      // per frame, by the library
};

const Shared* shared() {
  static Shared* s = []() -> Shared* {
    const auto nyu = findmug::test::dataPath("nyuv2_labeled");
    if (nyu.empty()) return nullptr;
    auto* out = new Shared;
    for (const LabeledFrame& f : test::framesWithGround(nyu.string(), 8)) {
      out->frames.push_back(test::subsampled(f, kStep));
    }
    const SegmenterConfig config = test::fastSegmenterConfig(kStep);
    out->forest = test::trainTinyModel(config, {out->frames[0], out->frames[1]},
                                       out->dir.str("model.fmf"));
    const Segmenter segmenter(config, out->forest);
    for (const LabeledFrame& f : out->frames) {
      const LabelledFrame r = segmenter.process(f.frame);
      out->mean_confidence.push_back(FrameCollector::meanConfidence(r.labels).value_or(-1.0));
      out->tables.push_back(r.tables.size());
    }
    return out;
  }();
  return s;
}

// A sequential pipeline (every frame published before submit() returns) collecting
// into `dir` with `settings` (daemon.collect_* without the prefix).
struct Rig {
  Rig(const std::string& dir, const std::map<std::string, std::string>& settings) {
    test::TestConfig config;
    config.segmenter = test::fastSegmenterConfig(kStep);
    config.set("daemon.model_path", shared()->dir.str("model.fmf"));
    config.set("daemon.status_period_s", "60");
    config.set("daemon.pose_input", "false");
    if (!dir.empty()) config.set("daemon.collect_dir", dir);
    for (const auto& [key, value] : settings) config.set("daemon.collect_" + key, value);
    PipelineHooks hooks;
    hooks.output_bus = out;
    hooks.command_bus = commands;
    out->subscribe(std::string(io::kStatusChannel),
                   [this](const std::string& c, const std::uint8_t* d, std::size_t n) {
                     statuses.push_back(io::decodeMessage<findmug_lcm::status_t>(d, n, c));
                   });
    pipeline = std::make_unique<Pipeline>(config.segmenter, config.daemon,
                                          shared()->forest, "tiny", ExecutionMode::Sequential,
                                          hooks);
    pipeline->start();
  }

  // Frame `index` of the shared frames as seq `seq`, captured at `utime_s`.
  void submit(std::size_t index, std::int64_t seq, double utime_s) {
    RgbdFrame frame = shared()->frames.at(index).frame;
    frame.seq = seq;
    frame.utime = 1'000'000'000 + static_cast<std::uint64_t>(utime_s * 1e6);
    ASSERT_TRUE(pipeline->submit(std::move(frame)));
  }

  findmug_lcm::status_t finish() {
    pipeline->stop(StopMode::Drain);
    while (out->handle(0ms) == io::HandleResult::Handled) {
    }
    return statuses.back();
  }

  std::shared_ptr<io::MemoryBus> out = std::make_shared<io::MemoryBus>(10000);
  std::shared_ptr<io::MemoryBus> commands = std::make_shared<io::MemoryBus>(100);
  std::unique_ptr<Pipeline> pipeline;
  std::vector<findmug_lcm::status_t> statuses;
};

std::string nameOf(std::int64_t seq, double utime_s) {
  return std::to_string(1'000'000'000 + static_cast<std::uint64_t>(utime_s * 1e6)) + "_" +
         std::to_string(seq);
}

// The frames in the folder's rgb/, sorted.
std::vector<std::string> savedNames(const std::string& dir) {
  std::vector<std::string> names;
  if (!fs::exists(fs::path(dir) / "rgb")) return names;
  for (const auto& e : fs::directory_iterator(fs::path(dir) / "rgb")) {
    names.push_back(e.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::string readText(const fs::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(Collect, SaveFrameCommandWritesTheNextFrameInTheDatasetLayout) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(shared());
  TempDir tmp;
  const std::string dir = tmp.str("collected");
  Rig rig(dir, {});
  const auto send = [&](const std::string& command, std::int64_t id, const std::string& arg) {
    const auto bytes = io::encodeMessage(
        io::encodeCommand(io::CommandMessage{1, id, command, arg}));
    ASSERT_TRUE(rig.commands->publish(std::string(io::kCommandChannel), bytes.data(),
                                      bytes.size()));
  };
  send("save_frame", 5, "two mugs on the table");
  send("save_frame", 6, "a, comma");  // refused: frames.csv is comma-separated
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (rig.pipeline->commandInput()->handled() < 2 &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(20ms);
  }
  rig.submit(2, 10, 0.0);  // saved
  rig.submit(3, 11, 0.1);  // nothing asked for it, no trigger configured
  const findmug_lcm::status_t status = rig.finish();

  EXPECT_EQ(status.frames_collected, 1);
  EXPECT_EQ(status.frames_collect_refused, 0);
  EXPECT_EQ(status.commands_accepted, 1);
  EXPECT_EQ(status.commands_rejected, 1);
  const std::string name = nameOf(10, 0.0);
  EXPECT_EQ(status.last_collected_frame, name);
  ASSERT_EQ(savedNames(dir), std::vector<std::string>{name});

  // Read back as a dataset (no labels yet): the pixels and camera are the frame's.
  DatasetOptions options;
  options.require_labels = false;
  const DatasetFolder folder(dir, options);
  ASSERT_EQ(folder.size(), 1u);
  const LabeledFrame back = folder.load(0);
  const RgbdFrame& sent = shared()->frames[2].frame;
  EXPECT_EQ(back.name, name);
  EXPECT_EQ(back.frame.width, sent.width);
  EXPECT_EQ(back.frame.depth_mm, sent.depth_mm);
  EXPECT_TRUE(back.frame.rgb == sent.rgb);
  EXPECT_DOUBLE_EQ(back.frame.intrinsics.fx, sent.intrinsics.fx);
  EXPECT_DOUBLE_EQ(back.frame.intrinsics.cy, sent.intrinsics.cy);
  // frames.csv: a scene for cross-validation, why it was saved, the note.
  const auto listing = loadFrameListing(dir);
  ASSERT_EQ(listing.count(name), 1u);
  EXPECT_EQ(listing.at(name).scene.rfind("run", 0), 0u);
  const std::string csv = readText(fs::path(dir) / "frames.csv");
  EXPECT_NE(csv.find(",request 5,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",tiny,two mugs on the table\n"), std::string::npos) << csv;
  EXPECT_FALSE(fs::exists(fs::path(dir) / "label8"));
}

TEST(Collect, SaveFrameIsRefusedWhenCollectionIsOff) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(shared());
  Rig rig("", {});
  EXPECT_THROW(rig.pipeline->requestFrameSave(1, ""), Error);
  rig.submit(0, 1, 0.0);
  const auto status = rig.finish();
  EXPECT_EQ(status.frames_collected, 0);
  EXPECT_EQ(status.last_collected_frame, "");
}

TEST(Collect, LowConfidenceSavesExactlyTheFramesBelowTheThreshold) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const Shared* s = shared();
  ASSERT_TRUE(s);
  // A threshold between the frames' means: some below, some above.
  std::vector<double> means;
  for (double m : s->mean_confidence) {
    if (m >= 0) means.push_back(m);
  }
  std::sort(means.begin(), means.end());
  ASSERT_GE(means.size(), 4u);
  const double threshold = (means[means.size() / 2 - 1] + means[means.size() / 2]) / 2;
  ASSERT_LT(means[means.size() / 2 - 1], means[means.size() / 2]);
  TempDir tmp;
  const std::string dir = tmp.str("collected");
  // A queue that holds every save: a writer slower than the frames would refuse some.
  Rig rig(dir, {{"low_confidence", std::to_string(threshold)}, {"min_interval_s", "0"},
                {"max_frames", "100"}, {"queue", "64"}});
  std::vector<std::string> expected;
  for (std::size_t i = 0; i < s->frames.size(); ++i) {
    rig.submit(i, static_cast<std::int64_t>(i), 0.1 * static_cast<double>(i));
    const double m = s->mean_confidence[i];
    if (m >= 0 && m < threshold) expected.push_back(nameOf(static_cast<std::int64_t>(i), 0.1 * i));
  }
  const auto status = rig.finish();
  std::sort(expected.begin(), expected.end());
  EXPECT_FALSE(expected.empty());
  EXPECT_LT(expected.size(), s->frames.size());
  EXPECT_EQ(savedNames(dir), expected);
  EXPECT_EQ(status.frames_collected, static_cast<std::int64_t>(expected.size()));
  EXPECT_EQ(status.frames_collect_refused, 0);
  EXPECT_NE(readText(fs::path(dir) / "frames.csv").find(",low_confidence,"), std::string::npos);
}

// The pixels filled in from their neighbours (labels.fill_holes: confidence 0)
// say nothing about how sure the model is, so they do not lower the mean.
TEST(Collect, MeanConfidenceLeavesFilledHolesOut) {
  LabelImage labels;
  labels.width = 4;
  labels.height = 1;
  labels.labels = {2, 2, 2, kVoidLabel};
  labels.confidence = {0.8f, 0.0f, 0.6f, 0.0f};
  const auto mean = FrameCollector::meanConfidence(labels);
  ASSERT_TRUE(mean.has_value());
  EXPECT_NEAR(*mean, 0.7, 1e-6);
  labels.confidence = {0.0f, 0.0f, 0.0f, 0.0f};
  EXPECT_FALSE(FrameCollector::meanConfidence(labels).has_value());
}

TEST(Collect, TableFlickerSavesAfterNChangesWithinTheWindow) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const Shared* s = shared();
  ASSERT_TRUE(s);
  // Two frames with different table counts, shown alternately: the count changes
  // at every frame after the first.
  std::size_t a = 0, b = s->frames.size();
  for (std::size_t j = 1; j < s->frames.size() && b == s->frames.size(); ++j) {
    if (s->tables[j] != s->tables[a]) b = j;
  }
  ASSERT_LT(b, s->frames.size()) << "no two test frames with different table counts";
  const auto run = [&](const std::string& window_s) {
    TempDir tmp;
    const std::string dir = tmp.str("collected");
    Rig rig(dir, {{"flicker_changes", "3"}, {"flicker_window_s", window_s},
                  {"min_interval_s", "0"}, {"queue", "64"}});
    for (int i = 0; i < 7; ++i) rig.submit(i % 2 == 0 ? a : b, i, 0.1 * i);
    rig.finish();
    return savedNames(dir);
  };
  // Changes at frames 1, 2, 3: the third within 1 s saves frame 3; the count
  // starts again, and frames 4, 5, 6 save frame 6.
  EXPECT_EQ(run("1"), (std::vector<std::string>{nameOf(3, 0.3), nameOf(6, 0.6)}));
  // Three changes take 0.2 s: a window of 0.15 s never holds them.
  EXPECT_TRUE(run("0.15").empty());
}

TEST(Collect, AutomaticSavesAreRateLimitedByCaptureTime) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  const Shared* s = shared();
  ASSERT_TRUE(s);
  // Frames whose mean confidence is below 1 (every one then triggers).
  std::vector<std::size_t> low;
  for (std::size_t i = 0; i < s->frames.size(); ++i) {
    if (s->mean_confidence[i] >= 0 && s->mean_confidence[i] < 0.999) low.push_back(i);
  }
  ASSERT_FALSE(low.empty());
  TempDir tmp;
  const std::string dir = tmp.str("collected");
  Rig rig(dir, {{"low_confidence", "0.999"}, {"min_interval_s", "1"}, {"queue", "64"}});
  // One frame every 0.4 s for 3.2 s: saved at 0, 1.2 (>= 1 s after 0), 2.4.
  for (int i = 0; i < 8; ++i) rig.submit(low[static_cast<std::size_t>(i) % low.size()], i, 0.4 * i);
  const auto status = rig.finish();
  EXPECT_EQ(savedNames(dir),
            (std::vector<std::string>{nameOf(0, 0.0), nameOf(3, 1.2), nameOf(6, 2.4)}));
  EXPECT_EQ(status.frames_collected, 3);
  EXPECT_EQ(status.frames_collect_refused, 0);  // rate-limited triggers are not refusals
}

TEST(Collect, TheFoldersBoundRefusesAndCountsFurtherSaves) {
  FINDMUG_REQUIRE_DATA(nyu, "nyuv2_labeled");
  ASSERT_TRUE(shared());
  {
    // Frames: one already there, room for two more.
    TempDir tmp;
    const std::string dir = tmp.str("collected");
    fs::create_directories(fs::path(dir) / "rgb");
    std::ofstream(fs::path(dir) / "rgb" / "old.png") << "x";
    Rig rig(dir, {{"max_frames", "3"}});
    for (int i = 0; i < 5; ++i) {
      rig.pipeline->requestFrameSave(i, "");
      rig.submit(static_cast<std::size_t>(i), i, 0.1 * i);
    }
    const auto status = rig.finish();
    EXPECT_EQ(status.frames_collected, 2);
    EXPECT_EQ(status.frames_collect_refused, 3);
    EXPECT_EQ(savedNames(dir).size(), 3u);
    EXPECT_NE(status.last_error.find("daemon.collect_max_frames (3) reached"), std::string::npos)
        << status.last_error;
  }
  {
    // Bytes: 1 MB already in depth/ fills a 1 MB bound.
    TempDir tmp;
    const std::string dir = tmp.str("collected");
    fs::create_directories(fs::path(dir) / "depth");
    std::ofstream(fs::path(dir) / "depth" / "big.png") << std::string(1 << 20, 'x');
    Rig rig(dir, {{"max_mb", "1"}});
    rig.pipeline->requestFrameSave(1, "");
    rig.submit(0, 1, 0.0);
    const auto status = rig.finish();
    EXPECT_EQ(status.frames_collected, 0);
    EXPECT_EQ(status.frames_collect_refused, 1);
    EXPECT_TRUE(savedNames(dir).empty());
    EXPECT_NE(status.last_error.find("daemon.collect_max_mb"), std::string::npos)
        << status.last_error;
  }
}

}  // namespace
}  // namespace findmug::daemon
